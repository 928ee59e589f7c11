// Fuzz target: the derivative-model loader (core/model.h) from YAML text, as `rig model`, the
// plant and the identification use a model file: ConfigMap::load_string + model_from_config,
// then, for a model that loads with one of the shipped vehicles, its state space, its ZOH
// discretisation and its modes. Bad text is a ConfigError; anything else is a finding, and a
// model that loads must give finite A and B.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>

#include "core/config.h"
#include "core/model.h"
#include "core/modes.h"
#include "core/vehicle.h"
#include "fuzz/fuzz_support.h"

using nimble::fuzz::require;

namespace {

/// The shipped vehicles by resolved path: the only vehicle files this target reads (a fuzzed
/// path could name a device file that never ends).
const nimble::Vehicle* shipped_vehicle(const std::string& path) {
  static std::map<std::string, nimble::Vehicle> vehicles = [] {
    std::map<std::string, nimble::Vehicle> v;
    for (const auto& e : std::filesystem::directory_iterator(nimble::fuzz::source_dir() + "/rig_configs/vehicles")) {
      v.emplace(e.path().lexically_normal().string(), nimble::load_vehicle(e.path().string()));
    }
    return v;
  }();
  const auto it = vehicles.find(std::filesystem::path(path).lexically_normal().string());
  return it == vehicles.end() ? nullptr : &it->second;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  // Named as a file of rig_configs/models/, so that a relative vehicle path resolves as there.
  const std::string origin = nimble::fuzz::source_dir() + "/rig_configs/models/fuzz.yaml";
  nimble::DerivativeModel model;
  try {
    nimble::ConfigMap map = nimble::ConfigMap::load_string(text, origin);
    model = nimble::model_from_config(map);
  } catch (const nimble::ConfigError&) {
    return 0;  // the documented outcome of a bad model file
  }
  for (const auto& [name, value] : model.derivatives) {
    require(std::isfinite(value), "model loaded with a non-finite derivative " + name);
  }
  const nimble::Vehicle* vehicle = shipped_vehicle(model.vehicle_file);
  if (vehicle == nullptr) return 0;
  const nimble::StateSpace ss = nimble::build_state_space(model, *vehicle);
  require(ss.A.allFinite() && ss.B.allFinite(), "a model that loads gives a non-finite A or B");
  const nimble::DiscreteStateSpace d = nimble::discretize_zoh(ss, 1e-3);
  (void)d;
  (void)nimble::analyse_modes(ss, *vehicle);
  return 0;
}
