#pragma once
/// Test support for the plant's tests: set 1 and its vehicle, a plant made of them, one model
/// effect switched on, the lateral state.

#include <cmath>
#include <map>
#include <optional>
#include <string>

#include <catch2/catch.hpp>

#include "core/model.h"
#include "plant/plant_model.h"

namespace nimble::plant_test {

using nimble::plant::PlantConfig;
using nimble::plant::PlantModel;

inline const std::string kModels = std::string(RIG_SOURCE_DIR) + "/rig_configs/models/";

struct Fixture {
  DerivativeModel model = load_model(kModels + "nimble_lateral_set1.yaml");
  Vehicle vehicle = load_vehicle(model.vehicle_file);
};

inline PlantModel make_plant(const Fixture& f, PlantConfig cfg = {}) {
  return PlantModel(f.model, std::nullopt, f.vehicle, cfg);
}

/// Steps `a` and `b` at trim for n steps, requiring the same side gust at every step; the gust's
/// RMS.
inline double same_gust_rms(PlantModel& a, PlantModel& b, int n) {
  double sum2 = 0;
  for (int i = 0; i < n; ++i) {
    a.step(a.trim_command());
    b.step(b.trim_command());
    REQUIRE(a.truth().gust_v_mps == b.truth().gust_v_mps);
    sum2 += a.truth().gust_v_mps * a.truth().gust_v_mps;
  }
  return std::sqrt(sum2 / n);
}

/// Set 1 with one effect in its effects: section.
inline Fixture with_effect(const std::string& effect, const std::map<std::string, double>& params) {
  Fixture f;
  f.model.effects[effect] = params;
  return f;
}

/// Lateral state [p v phi] of a plant.
inline Eigen::Vector3d lateral(const PlantModel& plant) {
  const auto& t = plant.truth();
  return {t.omega_body_radps.x(), t.velocity_body_mps.y(), t.euler_rad.x()};
}

}  // namespace nimble::plant_test
