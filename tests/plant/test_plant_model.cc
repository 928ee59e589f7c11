// Unit tests of the plant model: trim, linear-model agreement, actuators, effects.

#include <cmath>
#include <complex>
#include <fstream>
#include <sstream>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <unsupported/Eigen/MatrixFunctions>

#include "core/model.h"
#include "core/modes.h"
#include "effects/actuator_delay.h"
#include "effects/constant_load.h"
#include "effects/flapping_forcing.h"
#include "effects/forward_speed_coupling.h"
#include "effects/lateral_gust.h"
#include "effects/lateral_inflow.h"
#include "effects/registry.h"
#include "plant/plant_model.h"
#include "plant_fixture.h"

using namespace nimble;
using nimble::effects::ActuatorInput;
using nimble::plant::PlantConfig;
using nimble::plant::PlantModel;

using namespace nimble::plant_test;

TEST_CASE("trimmed hover: thrust equals weight and the attitude stays put", "[plant]") {
  Fixture f;
  PlantModel plant = make_plant(f);
  const double f_hz = plant.trim_flap_frequency_radps() / (2 * M_PI);
  CHECK(2.0 * (0.0114 * f_hz - 0.0449) == Approx(f.vehicle.mass_kg * f.vehicle.gravity_mps2));
  const ActuatorInput trim = plant.trim_command();
  for (int i = 0; i < 10000; ++i) plant.step(trim);  // 10 s
  CHECK(lateral(plant).norm() < 1e-9);
  CHECK(plant.truth().velocity_body_mps.z() == Approx(f.model.trim.w0_mps).margin(1e-9));
  CHECK(plant.truth().specific_force_body_mps2.z() == Approx(-f.vehicle.gravity_mps2).epsilon(1e-6));
}

TEST_CASE("small perturbations reproduce the linear model's eigenvalues", "[plant]") {
  Fixture f;
  const StateSpace ss = build_state_space(f.model, f.vehicle);
  const auto linear = sorted_eigenvalues(ss.A);

  // One-step transition matrix of the plant about trim, by finite differences.
  const double eps = 1e-6;
  PlantModel base = make_plant(f);
  base.step(base.trim_command());
  const Eigen::Vector3d x0 = lateral(base);
  Eigen::Matrix3d Phi;
  for (int j = 0; j < 3; ++j) {
    PlantConfig cfg;
    if (j == 0) cfg.initial.p_radps = eps;
    if (j == 1) cfg.initial.v_mps = eps;
    if (j == 2) cfg.initial.phi_rad = eps;
    PlantModel plant = make_plant(f, cfg);
    plant.step(plant.trim_command());
    Phi.col(j) = (lateral(plant) - x0) / eps;
  }
  Eigen::EigenSolver<Eigen::Matrix3d> es(Phi);
  const double dt = base.dt_s();
  for (const auto& lambda : linear) {
    double best = INFINITY;
    for (int i = 0; i < 3; ++i)
      best = std::min(best, std::abs(std::log(std::complex<double>(es.eigenvalues()[i])) / dt - lambda));
    INFO("linear eigenvalue " << lambda);
    CHECK(best / std::abs(lambda) < 0.005);
  }
}

TEST_CASE("a small initial roll follows the linear model for one second", "[plant]") {
  Fixture f;
  const StateSpace ss = build_state_space(f.model, f.vehicle);
  PlantConfig cfg;
  cfg.initial.phi_rad = 0.002;
  PlantModel plant = make_plant(f, cfg);
  for (int i = 0; i < 1000; ++i) plant.step(plant.trim_command());
  const Eigen::MatrixXd At = ss.A * 1.0;
  const Eigen::MatrixXd E = At.exp();
  const Eigen::Vector3d expected = E * Eigen::Vector3d(0, 0, 0.002);
  INFO("plant " << lateral(plant).transpose() << " linear " << expected.transpose());
  CHECK((lateral(plant) - expected).norm() < 0.01 * expected.norm());
}

TEST_CASE("flap actuator: delta_f step response is 8.97/(s+12.56)", "[plant]") {
  Fixture f;
  PlantModel plant = make_plant(f);
  ActuatorInput cmd = plant.trim_command();
  const double step = 20.0;  // rad/s of delta_f command
  cmd.flap_freq_left_radps += step / 2;
  cmd.flap_freq_right_radps -= step / 2;
  for (int i = 1; i <= 200; ++i) {
    plant.step(cmd);
    const double t = i * plant.dt_s();
    const double expected = 8.97 / 12.56 * step * (1.0 - std::exp(-12.56 * t));
    REQUIRE(plant.truth().delta_f_radps == Approx(expected).epsilon(1e-6));
  }
  // Positive delta_f rolls right wing down (positive p), as L_df > 0.
  CHECK(plant.truth().omega_body_radps.x() > 0.0);
}

TEST_CASE("servo: dihedral step settles with the second-order response", "[plant]") {
  Fixture f;
  PlantModel plant = make_plant(f);
  ActuatorInput cmd = plant.trim_command();
  cmd.dihedral_rad = 0.2;
  double peak = 0.0;
  for (int i = 0; i < 1000; ++i) {
    plant.step(cmd);
    peak = std::max(peak, plant.truth().dihedral_rad);
  }
  CHECK(plant.truth().dihedral_rad == Approx(0.2).epsilon(1e-4));
  // zeta = 30.25 / (2 sqrt(554.2)) = 0.643: overshoot exp(-pi zeta / sqrt(1 - zeta^2)) = 7.2 %.
  const double zeta = 30.25 / (2 * std::sqrt(554.2));
  CHECK(peak / 0.2 - 1.0 == Approx(std::exp(-M_PI * zeta / std::sqrt(1 - zeta * zeta))).epsilon(0.02));
}

TEST_CASE("actuator delay postpones the response by the configured time", "[plant]") {
  Fixture f;
  PlantConfig cfg;
  cfg.effects.get<effects::ActuatorDelayConfig>().enabled = true;
  cfg.effects.get<effects::ActuatorDelayConfig>().delay_s = 0.020;
  PlantModel plant = make_plant(f, cfg);
  ActuatorInput cmd = plant.trim_command();
  cmd.flap_freq_left_radps += 10;
  for (int i = 0; i < 20; ++i) {
    plant.step(cmd);
    REQUIRE(std::fabs(plant.truth().delta_f_radps) < 1e-12);
  }
  for (int i = 0; i < 5; ++i) plant.step(cmd);
  CHECK(plant.truth().delta_f_radps > 0.1);
}

TEST_CASE("lateral gust: seeded, with the configured standard deviation", "[plant]") {
  Fixture f;
  PlantConfig cfg;
  cfg.effects.get<effects::LateralGustConfig>().enabled = true;
  cfg.effects.get<effects::LateralGustConfig>().sigma_mps = 0.2;
  cfg.effects.get<effects::LateralGustConfig>().tau_s = 0.05;
  cfg.seed = 7;
  PlantModel a = make_plant(f, cfg), b = make_plant(f, cfg);
  CHECK(same_gust_rms(a, b, 60000) == Approx(0.2).epsilon(0.1));
}

TEST_CASE("flapping forcing puts a roll-rate oscillation at the flapping frequency", "[plant]") {
  Fixture f;
  PlantConfig cfg;
  cfg.effects.get<effects::FlappingForcingConfig>().enabled = true;
  cfg.effects.get<effects::FlappingForcingConfig>().roll_moment_amplitudes_nm = {2e-3};
  PlantModel plant = make_plant(f, cfg);
  // Correlate p with sin/cos at the flapping frequency over 1 s, against a frequency 5 Hz off.
  const double w = plant.trim_flap_frequency_radps();
  std::complex<double> at_f = 0, off_f = 0;
  for (int i = 0; i < 1000; ++i) {
    plant.step(plant.trim_command());
    const double t = plant.truth().time_s, p = plant.truth().omega_body_radps.x();
    at_f += p * std::exp(std::complex<double>(0, -w * t));
    off_f += p * std::exp(std::complex<double>(0, -(w + 2 * M_PI * 5) * t));
  }
  // Expected amplitude of p: L / (Ixx_eff w) with Ixx_eff = Ic / Izz.
  const double amp = 2.0 * std::abs(at_f) / 1000.0;
  CHECK(amp == Approx(2e-3 * f.vehicle.Izz_kgm2 / f.vehicle.Ic() / w).epsilon(0.15));
  CHECK(std::abs(off_f) < 0.2 * std::abs(at_f));
}

TEST_CASE("plant config: errors name the key", "[plant]") {
  const auto load = [](const std::string& text) {
    ConfigMap m = ConfigMap::load_string(text, "scenario.yaml");
    return nimble::plant::plant_config_from(m);
  };
  CHECK(load("rate_hz: 2000\ntruth_rate_hz: 500\n").truth_rate_hz == 500);
  CHECK_THROWS_WITH(load("rate_hz: 1000\ntruth_rate_hz: 300\n"), Catch::Contains("truth_rate_hz"));
  CHECK_THROWS_WITH(load("rate_hz: 1024\ntruth_rate_hz: 1024\nfeedback_rate_hz: 1024\n"), Catch::Contains("rate_hz"));
  CHECK_THROWS_WITH(load("command_timeout_s: -1\n"), Catch::Contains("command_timeout_s"));
  CHECK_THROWS_WITH(load("effects:\n  lateral_gust: {enabled: true, sigma_mps: 9}\n"),
                    Catch::Contains("effects.lateral_gust.sigma_mps"));
  CHECK_THROWS_WITH(load("effects:\n  gusty: {enabled: true}\n"), Catch::Contains("effects.gusty"));
  CHECK(load("initial: {u_mps: 0.4}\n").initial.u_mps == 0.4);
  const PlantConfig c = load(
      "effects:\n  forward_speed_coupling: {enabled: true, L_up: 1.0e-4, L_uv: 2.0e-4, Y_up: 3.0e-3, "
      "Y_uv: -4.0e-2}\n  constant_load: {enabled: true, L_0: 1.0e-4, Y_0: -2.0e-3}\n");
  CHECK(c.effects.get<effects::ForwardSpeedCouplingConfig>().enabled);
  CHECK(c.effects.get<effects::ForwardSpeedCouplingConfig>().gain_per_mps == 0.0);
  CHECK(c.effects.get<effects::ForwardSpeedCouplingConfig>().L_up_ns2 == 1.0e-4);
  CHECK(c.effects.get<effects::ForwardSpeedCouplingConfig>().L_uv_ns2pm == 2.0e-4);
  CHECK(c.effects.get<effects::ForwardSpeedCouplingConfig>().Y_up_ns2pm == 3.0e-3);
  CHECK(c.effects.get<effects::ForwardSpeedCouplingConfig>().Y_uv_ns2pm2 == -4.0e-2);
  CHECK(c.effects.get<effects::ConstantLoadConfig>().enabled);
  CHECK(c.effects.get<effects::ConstantLoadConfig>().roll_moment_nm == 1.0e-4);
  CHECK(c.effects.get<effects::ConstantLoadConfig>().side_force_n == -2.0e-3);
  // The two forms of forward-speed coupling do not mix.
  CHECK_THROWS_WITH(load("effects:\n  forward_speed_coupling: {enabled: true, gain_per_mps: 0.5, Y_uv: 0.01}\n"),
                    Catch::Contains("effects.forward_speed_coupling.gain_per_mps") && Catch::Contains("Y_uv"));
  CHECK_THROWS_WITH(load("effects:\n  constant_load: {enabled: true, L_0: 0.5}\n"),
                    Catch::Contains("effects.constant_load.L_0"));
}

TEST_CASE("a model that carries lateral_inflow flies it with the model's coefficients", "[plant]") {
  Fixture f;
  PlantConfig by_config;
  by_config.initial.v_mps = 1.2;
  by_config.effects.get<effects::LateralInflowConfig>() = {true, -0.025, -2.5e-4};
  Fixture g;
  g.model.effects["lateral_inflow"] = {{"Y_vv", -0.025}, {"L_vv", -2.5e-4}};
  PlantConfig plain;
  plain.initial.v_mps = 1.2;
  PlantModel a = make_plant(f, by_config), b = make_plant(g, plain), c = make_plant(f, plain);
  for (int i = 0; i < 300; ++i) {
    a.step(a.trim_command());
    b.step(b.trim_command());
    c.step(c.trim_command());
  }
  CHECK(b.truth().velocity_body_mps[1] == Approx(a.truth().velocity_body_mps[1]).epsilon(1e-12));
  CHECK(b.truth().omega_body_radps[0] == Approx(a.truth().omega_body_radps[0]).epsilon(1e-12));
  CHECK(std::fabs(c.truth().velocity_body_mps[1] - a.truth().velocity_body_mps[1]) > 1e-3);
}
