// Black-box models (thesis Eq 8.5 / 8.6): every entry of A and B free, read from a model file,
// and flown by the plant through their equivalent derivatives and roll-angle terms.

#include <cmath>
#include <optional>
#include <string>

#include <catch2/catch.hpp>

#include "core/config.h"
#include "core/model.h"
#include "tests/plant/plant_fixture.h"
#include "tests/support/blackbox_model.h"

using namespace nimble;
using namespace nimble::plant_test;
using nimble::test::blackbox_of;

namespace {

/// Flies `plant` for `steps` with a flap-frequency doublet; the largest difference of its
/// lateral state from `other`'s, flown alike, over the flight.
double largest_difference(PlantModel a, PlantModel b, int steps) {
  double worst = 0.0;
  for (int i = 0; i < steps; ++i) {
    auto cmd_a = a.trim_command(), cmd_b = b.trim_command();
    const double df = (i / 100) % 4 == 1 ? 2.0 : (i / 100) % 4 == 2 ? -2.0 : 0.0;  // rad/s, 0.1 s a side
    cmd_a.flap_freq_left_radps += df;
    cmd_b.flap_freq_left_radps += df;
    a.step(cmd_a);
    b.step(cmd_b);
    const auto& ta = a.truth();
    const auto& tb = b.truth();
    worst = std::max(worst, (ta.omega_body_radps - tb.omega_body_radps).cwiseAbs().maxCoeff());
    worst = std::max(worst, (ta.velocity_body_mps - tb.velocity_body_mps).cwiseAbs().maxCoeff());
    worst = std::max(worst, (ta.euler_rad - tb.euler_rad).cwiseAbs().maxCoeff());
  }
  return worst;
}

}  // namespace

TEST_CASE("black-box model: A and B entries named by the states, read from a file, built as they are", "[plant]") {
  const Fixture f;
  const StateSpace grey = build_state_space(f.model, f.vehicle);
  const DerivativeModel bb = blackbox_of(f.model, grey);
  CHECK(stability_derivative_names(Structure::kBlackbox3) ==
        std::vector<std::string>{"a_p_p", "a_p_v", "a_p_phi", "a_v_p", "a_v_v", "a_v_phi", "a_phi_p", "a_phi_v",
                                 "a_phi_phi"});
  CHECK(control_derivative_names(Structure::kBlackbox4, "delta_f") ==
        std::vector<std::string>{"b_p_df", "b_r_df", "b_v_df", "b_phi_df"});

  // As a model file: every entry by name, nothing else.
  std::string yaml = "name: bb\nsource: test\nstructure: blackbox3\nvehicle: " + f.model.vehicle_file +
                     "\ninputs: [delta_f, delta_t]\ntrim: {u0_mps: 0, w0_mps: " + std::to_string(f.model.trim.w0_mps) +
                     ", theta0_rad: 0, phi0_rad: 0}\nderivatives:\n";
  char line[96];
  for (const auto& [name, value] : bb.derivatives) {
    std::snprintf(line, sizeof line, "  %s: %.17g\n", name.c_str(), value);
    yaml += line;
  }
  ConfigMap map = ConfigMap::load_string(yaml, "bb.yaml");
  const DerivativeModel read = model_from_config(map);
  CHECK(read.structure == Structure::kBlackbox3);
  const StateSpace ss = build_state_space(read, f.vehicle);
  CHECK(ss.states == grey.states);
  CHECK((ss.A - grey.A).cwiseAbs().maxCoeff() == 0.0);
  CHECK((ss.B - grey.B).cwiseAbs().maxCoeff() == 0.0);

  // A missing entry, terms and effects are refused, naming the key.
  const auto refused = [&](const std::string& text) -> std::string {
    try {
      ConfigMap m = ConfigMap::load_string(text, "bb.yaml");
      model_from_config(m);
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "(accepted)";
  };
  std::string missing = yaml;
  missing.erase(missing.find("  a_v_phi:"),
                missing.find('\n', missing.find("  a_v_phi:")) - missing.find("  a_v_phi:") + 1);
  CHECK_THAT(refused(missing), Catch::Contains("a_v_phi"));
  CHECK_THAT(refused(yaml + "terms:\n  - {equation: L, expression: \"p^3\", coefficient: 1}\n"),
             Catch::Contains("a black-box structure takes no terms"));
  CHECK_THAT(refused(yaml + "effects:\n  ground_effect: {k: 1}\n"),
             Catch::Contains("a black-box structure takes no effects"));
}

TEST_CASE("black-box model: the plant flies it as it flies the grey-box model with the same A and B", "[plant]") {
  SECTION("three states (set 1)") {
    const Fixture f;
    const DerivativeModel bb = blackbox_of(f.model, build_state_space(f.model, f.vehicle));
    double kinematic = -1.0;
    const DerivativeModel flown = plant_equivalent(bb, f.vehicle, &kinematic);
    CHECK(flown.structure == Structure::kLateral3);
    CHECK(kinematic == 0.0);
    CHECK(flown.terms.empty());  // set 1's phi column is the plant's own gravity
    for (const auto& [name, value] : f.model.derivatives) CHECK(flown.at(name) == Approx(value).epsilon(1e-12));
    CHECK(largest_difference(make_plant(f), PlantModel(bb, std::nullopt, f.vehicle, {}), 2000) < 1e-10);
  }
  SECTION("four states, full roll-yaw inertia coupling") {
    Fixture f;
    f.model = load_model(kModels + "nimble_lateral4_yaw.yaml");
    f.vehicle = load_vehicle(f.model.vehicle_file);
    const DerivativeModel bb = blackbox_of(f.model, build_state_space(f.model, f.vehicle));
    double kinematic = -1.0;
    const DerivativeModel flown = plant_equivalent(bb, f.vehicle, &kinematic);
    CHECK(flown.structure == Structure::kLateral4);
    CHECK(flown.coupling == RollYawCoupling::kDecoupled);
    CHECK(kinematic < 1e-15);
    const StateSpace a = build_state_space(f.model, f.vehicle), b = build_state_space(flown, f.vehicle);
    CHECK((a.A - b.A).cwiseAbs().maxCoeff() < 1e-12);
    CHECK((a.B - b.B).cwiseAbs().maxCoeff() < 1e-12);
    CHECK(largest_difference(make_plant(f), PlantModel(bb, std::nullopt, f.vehicle, {}), 2000) < 1e-10);
  }
}

TEST_CASE("black-box model: a roll-angle column no derivative has is flown as a term", "[plant]") {
  const Fixture f;
  StateSpace ss = build_state_space(f.model, f.vehicle);
  ss.A(0, 2) = 3.0;   // p-dot gains 3 rad/s^2 per rad of roll
  ss.A(1, 2) += 0.5;  // v-dot gains 0.5 m/s^2 per rad over gravity's
  ss.A(2, 0) = 0.9;   // a phi-dot row the plant's kinematics do not follow
  const DerivativeModel bb = blackbox_of(f.model, ss);
  double kinematic = 0.0;
  const DerivativeModel flown = plant_equivalent(bb, f.vehicle, &kinematic);
  CHECK(kinematic == Approx(0.1));
  REQUIRE(flown.terms.size() == 2);
  CHECK(flown.terms[0].equation == "L");
  CHECK(flown.terms[0].expression.to_string() == "phi");
  CHECK(flown.terms[0].coefficient == Approx(3.0 * f.vehicle.Ic() / f.vehicle.Izz_kgm2));
  CHECK(flown.terms[1].equation == "Y");
  CHECK(flown.terms[1].coefficient == Approx(0.5 * f.vehicle.mass_kg));

  // Released from rest at 0.1 rad of roll, the first step's rates follow A's phi column.
  PlantConfig cfg;
  cfg.initial.phi_rad = 0.1;
  PlantModel plant(bb, std::nullopt, f.vehicle, cfg);
  const double dt = 1.0 / cfg.rate_hz;
  plant.step(plant.trim_command());
  CHECK(plant.truth().omega_body_radps.x() / dt == Approx(3.0 * 0.1).epsilon(0.01));
  const double g_phi = f.vehicle.gravity_mps2 * std::sin(0.1);  // the plant's own gravity, nonlinear
  CHECK(plant.truth().velocity_body_mps.y() / dt == Approx(g_phi + 0.5 * 0.1).epsilon(0.01));
}
