// The plant flies what a model file carries beside its derivatives: every effect of its
// effects: section with the model's coefficients, and its terms.

#include <algorithm>
#include <cmath>
#include <complex>
#include <fstream>
#include <sstream>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include <catch2/catch.hpp>
#include <unsupported/Eigen/MatrixFunctions>

#include "core/model.h"
#include "core/modes.h"
#include "effects/actuator_delay.h"
#include "effects/constant_load.h"
#include "effects/effectiveness_drift.h"
#include "effects/effectiveness_step.h"
#include "effects/flapping_forcing.h"
#include "effects/forward_speed_coupling.h"
#include "effects/lateral_gust.h"
#include "effects/lateral_inflow.h"
#include "effects/registry.h"
#include "effects/term_effect.h"
#include "plant/plant_model.h"
#include "plant_fixture.h"

using namespace nimble;
using nimble::effects::ActuatorInput;
using nimble::plant::PlantConfig;
using nimble::plant::PlantModel;

using namespace nimble::plant_test;

// ---------------------------------------------------------------------------------------
// Every effect a model file's effects: section can carry flies with the model's coefficients.

TEST_CASE("every effect name a model may carry is one the plant flies", "[plant][model_effects]") {
  // A valid section per name: these, with the keys beyond the regressors' (the scanned delay,
  // frequency and change time, the reported fractions and rates), or else every regressor
  // parameter of the effect (effects/registry.h) at 1e-4.
  const std::map<std::string, std::map<std::string, double>> sections{
      {"kinematic_coupling", {{"Y_pw", 0.02876}}},
      {"gravity_nonlinearity", {{"Y_gphi", 0.02876}}},
      {"lateral_inflow", {{"L_vv", -2e-4}, {"Y_vv", -0.02}}},
      {"forward_speed_coupling", {{"L_up", -1e-4}, {"L_uv", -2e-4}, {"Y_up", 1e-3}, {"Y_uv", -0.03}}},
      {"actuator_delay",
       {{"delay_s", 0.02},
        {"L_df_delayed", 1e-4},
        {"Y_df_delayed", -8e-4},
        {"L_df_fraction_delayed", 0.9},
        {"Y_df_fraction_delayed", 0.9},
        {"F_cmd_delayed", 0.5}}},
      {"sensor_bias", {{"L_0", 1e-5}, {"Y_0", -1e-4}}},
      {"constant_load", {{"L_0", 1e-5}, {"Y_0", -1e-4}}},
      {"dihedral_coupling", {{"L_dd", 1.4e-3}, {"Y_dd", -0.06}}},
      {"yaw_coupling", {{"Lr", -2.8e-4}, {"Yr", 8.4e-3}}},
      {"flapping_forcing", {{"flapping_hz", 16.5}, {"L_sin1", 1e-3}, {"L_cos1", 1e-3}, {"L_amp1", std::sqrt(2e-6)}}},
      {"lateral_gust", {{"sigma_mps", 0.1}, {"tau_s", 0.5}}},
      {"effectiveness_drift",
       {{"L_df_rate", -8.8e-8}, {"Y_df_rate", 7.2e-7}, {"rate_per_min", -0.05}, {"t_mid_s", 20.0}}},
      {"effectiveness_step",
       {{"L_df_step", -2.6e-5}, {"Y_df_step", 2.2e-4}, {"t_change_s", 12.0}, {"fraction", -0.25}}},
  };
  for (const auto& effect : nimble::effects::effect_registry()) {
    const std::string& name = effect.name();
    INFO("effect " << name);
    std::map<std::string, double> section;
    if (sections.count(name)) {
      section = sections.at(name);
    } else {
      for (const auto& term : effect.definition.terms) section[term.parameter] = 1e-4;
    }
    const Fixture f = with_effect(name, section);
    CHECK_NOTHROW(make_plant(f));
  }
}

TEST_CASE(
    "the effect registry and the plant agree: every regressor parameter of every effect flies, every plant "
    "effect flies a registry effect and is written in the plant file",
    "[plant][model_effects]") {
  // Built from the registry (effects/registry.h) alone: an effect whose model mapping or plant
  // side does not fly its own regressor parameters fails here.
  for (const auto& effect : nimble::effects::effect_registry()) {
    const auto& spec = effect.definition;
    std::map<std::string, double> section;
    for (const auto& term : spec.terms) section[term.parameter] = 1e-4;
    if (spec.name == "actuator_delay") section["delay_s"] = 0.02;                     // the scanned delay
    if (spec.name == "flapping_forcing") section["flapping_hz"] = 16.5;               // the scanned frequency
    if (spec.name == "lateral_gust") section = {{"sigma_mps", 0.1}, {"tau_s", 0.5}};  // stochastic: no terms
    if (spec.name == "effectiveness_step") section["t_change_s"] = 12.0;              // the scanned change time
    // The drift's coefficients are per second of the model's L_df (1.06e-4) and Y_df (-8.63e-4):
    // 1e-4 would be a rate of 57 per minute; -5 %/min is the plant file's.
    if (spec.name == "effectiveness_drift") section = {{"L_df_rate", -8.8e-8}, {"Y_df_rate", 7.2e-7}};
    INFO("effect " << spec.name);
    CHECK_NOTHROW(make_plant(with_effect(spec.name, section)));
  }
  std::ifstream in(std::string(RIG_SOURCE_DIR) + "/rig_configs/plant/nimble_plant.yaml");
  std::stringstream plant_file;
  plant_file << in.rdbuf();
  for (const auto* effect : nimble::effects::plant_effects()) {
    INFO("plant effect " << effect->name());
    CHECK(plant_file.str().find("\n  " + effect->name() + ":") != std::string::npos);
    CHECK(effect->plant.markdown_rows("x.").find("`x.enabled`") != std::string::npos);
  }
}

TEST_CASE("a model effect the plant does not know is refused with its name", "[plant][model_effects]") {
  const Fixture unknown = with_effect("wind_shear", {{"k", 1.0}});
  CHECK_THROWS_AS(make_plant(unknown), std::invalid_argument);
  CHECK_THROWS_WITH(make_plant(unknown), Catch::Contains("wind_shear") && Catch::Contains("nimble_lateral_set1.yaml"));
  // A parameter the effect does not have, a missing required one, an out-of-range value.
  CHECK_THROWS_WITH(make_plant(with_effect("lateral_inflow", {{"L_vvv", 1e-4}})),
                    Catch::Contains("effects.lateral_inflow.L_vvv"));
  CHECK_THROWS_WITH(make_plant(with_effect("flapping_forcing", {{"L_sin0", 1e-3}})),
                    Catch::Contains("effects.flapping_forcing.L_sin0"));
  CHECK_THROWS_WITH(make_plant(with_effect("actuator_delay", {{"L_df_delayed", 1e-4}})),
                    Catch::Contains("effects.actuator_delay") && Catch::Contains("delay_s"));
  CHECK_THROWS_WITH(make_plant(with_effect("lateral_gust", {{"sigma_mps", 0.1}})),
                    Catch::Contains("effects.lateral_gust") && Catch::Contains("tau_s"));
  CHECK_THROWS_WITH(make_plant(with_effect("actuator_delay", {{"delay_s", 2.0}})),
                    Catch::Contains("effects.actuator_delay.delay_s"));
  CHECK_THROWS_WITH(make_plant(with_effect("sensor_bias", {{"L_0", NAN}})), Catch::Contains("effects.sensor_bias.L_0"));
}

TEST_CASE("forward-speed coupling from the model adds the (u - u0) p and (u - u0) v terms", "[plant][model_effects]") {
  // u moves only with a longitudinal model: fly set 1 with it, perturbed in u, v and p.
  const DerivativeModel lon = load_model(kModels + "nimble_longitudinal.yaml");
  const double L_up = -1.5e-4, L_uv = 3.0e-4, Y_up = 2.0e-3, Y_uv = -0.03;
  Fixture f;
  const Fixture g =
      with_effect("forward_speed_coupling", {{"L_up", L_up}, {"L_uv", L_uv}, {"Y_up", Y_up}, {"Y_uv", Y_uv}});
  PlantConfig cfg;
  cfg.initial.u_mps = 0.6;
  cfg.initial.v_mps = 0.4;
  cfg.initial.p_radps = 0.3;
  const PlantModel plain(f.model, lon, f.vehicle, cfg), coupled(g.model, lon, f.vehicle, cfg);
  const double du = 0.6 - f.model.trim.u0_mps, v = 0.4, p = 0.3;
  REQUIRE(plain.truth().velocity_body_mps.x() == Approx(f.model.trim.u0_mps + 0.6));
  // Truth at t = 0: p_dot = Izz/Ic L (lateral3, no N), side specific force Y/m.
  const double dL = L_up * du * p + L_uv * du * v, dY = Y_up * du * p + Y_uv * du * v;
  const double Izz_over_Ic = f.vehicle.Izz_kgm2 / f.vehicle.Ic();
  CHECK(coupled.truth().angular_accel_body_radps2.x() - plain.truth().angular_accel_body_radps2.x() ==
        Approx(Izz_over_Ic * dL).epsilon(1e-9));
  CHECK(coupled.truth().specific_force_body_mps2.y() - plain.truth().specific_force_body_mps2.y() ==
        Approx(dY / f.vehicle.mass_kg).epsilon(1e-9));
  CHECK(std::fabs(Izz_over_Ic * dL) > 1e-3);  // a change the check can see

  // The model's section replaces the plant file's one-gain form; with coefficients k Lp, k Lv,
  // k Yp, k Yv it flies as the gain k does (lateral3).
  const double k = 0.5;
  PlantConfig by_gain = cfg;
  by_gain.effects.get<effects::ForwardSpeedCouplingConfig>().enabled = true;
  by_gain.effects.get<effects::ForwardSpeedCouplingConfig>().gain_per_mps = k;
  const Fixture h = with_effect("forward_speed_coupling", {{"L_up", k * f.model.at("Lp")},
                                                           {"L_uv", k * f.model.at("Lv")},
                                                           {"Y_up", k * f.model.at("Yp")},
                                                           {"Y_uv", k * f.model.at("Yv")}});
  PlantModel a(f.model, lon, f.vehicle, by_gain), b(h.model, lon, f.vehicle, by_gain);
  for (int i = 0; i < 300; ++i) {
    a.step(a.trim_command());
    b.step(b.trim_command());
  }
  CHECK(b.truth().omega_body_radps.x() == Approx(a.truth().omega_body_radps.x()).epsilon(1e-9));
  CHECK(b.truth().velocity_body_mps.y() == Approx(a.truth().velocity_body_mps.y()).epsilon(1e-9));

  // A plant file with both forms is refused.
  PlantConfig both = by_gain;
  both.effects.get<effects::ForwardSpeedCouplingConfig>().Y_uv_ns2pm2 = 0.01;
  CHECK_THROWS_WITH(PlantModel(f.model, lon, f.vehicle, both), Catch::Contains("forward_speed_coupling"));
}

TEST_CASE("actuator delay from the model postpones the delta_f response by delay_s", "[plant][model_effects]") {
  // The plant file's delay (50 ms) is replaced by the model's (20 ms).
  const Fixture g =
      with_effect("actuator_delay", {{"delay_s", 0.020}, {"L_df_delayed", 1.0e-4}, {"L_df_fraction_delayed", 0.95}});
  PlantConfig cfg;
  cfg.effects.get<effects::ActuatorDelayConfig>().enabled = true;
  cfg.effects.get<effects::ActuatorDelayConfig>().delay_s = 0.050;
  PlantModel plant = make_plant(g, cfg), undelayed = make_plant(Fixture{});
  ActuatorInput cmd = plant.trim_command();
  cmd.flap_freq_left_radps += 10;
  for (int i = 0; i < 20; ++i) {
    plant.step(cmd);
    undelayed.step(cmd);
    REQUIRE(std::fabs(plant.truth().delta_f_radps) < 1e-12);
  }
  CHECK(undelayed.truth().delta_f_radps > 0.1);
  std::vector<double> reference;  // the undelayed response from its start
  PlantModel ref = make_plant(Fixture{});
  for (int i = 0; i < 30; ++i) {
    ref.step(cmd);
    reference.push_back(ref.truth().delta_f_radps);
  }
  for (int i = 0; i < 30; ++i) {
    plant.step(cmd);
    REQUIRE(plant.truth().delta_f_radps == Approx(reference[static_cast<std::size_t>(i)]).epsilon(1e-12));
  }
}

TEST_CASE("flapping forcing from the model oscillates at the plant's flapping frequency", "[plant][model_effects]") {
  // Amplitude hypot(L_sin1, L_cos1) = 2e-3 N m at the plant's flapping frequency (about 16.3 Hz
  // at trim), not at the model's flapping_hz (given 12 Hz here).
  const Fixture g = with_effect("flapping_forcing", {{"flapping_hz", 12.0}, {"L_sin1", 1.2e-3}, {"L_cos1", -1.6e-3}});
  PlantModel plant = make_plant(g);
  const double w = plant.trim_flap_frequency_radps();
  std::complex<double> at_f = 0, at_model_f = 0;
  for (int i = 0; i < 1000; ++i) {
    plant.step(plant.trim_command());
    const double t = plant.truth().time_s, p = plant.truth().omega_body_radps.x();
    at_f += p * std::exp(std::complex<double>(0, -w * t));
    at_model_f += p * std::exp(std::complex<double>(0, -2 * M_PI * 12.0 * t));
  }
  const double amp = 2.0 * std::abs(at_f) / 1000.0;
  CHECK(amp == Approx(2e-3 * g.vehicle.Izz_kgm2 / g.vehicle.Ic() / w).epsilon(0.15));
  CHECK(std::abs(at_model_f) < 0.2 * std::abs(at_f));

  // Both equations and two harmonics: the same as the plant file's forcing with the
  // amplitudes hypot(sin_h, cos_h), with the plant's seeded phases.
  const Fixture h = with_effect("flapping_forcing", {{"flapping_hz", 16.0},
                                                     {"L_sin1", 1.2e-3},
                                                     {"L_cos1", -1.6e-3},
                                                     {"L_sin2", 0.6e-3},
                                                     {"L_cos2", 0.8e-3},
                                                     {"Y_cos1", 1.0e-2},
                                                     {"Y_sin2", -3.0e-3},
                                                     {"Y_cos2", 4.0e-3}});
  PlantConfig by_config;
  by_config.effects.get<effects::FlappingForcingConfig>().enabled = true;
  by_config.effects.get<effects::FlappingForcingConfig>().roll_moment_amplitudes_nm = {2.0e-3, 1.0e-3};
  by_config.effects.get<effects::FlappingForcingConfig>().side_force_amplitudes_n = {1.0e-2, 5.0e-3};
  PlantConfig other;  // the plant file's own forcing, replaced by the model's
  other.effects.get<effects::FlappingForcingConfig>() = by_config.effects.get<effects::FlappingForcingConfig>();
  other.effects.get<effects::FlappingForcingConfig>().roll_moment_amplitudes_nm = {5.0e-3, 1.0e-3};
  PlantModel a = make_plant(Fixture{}, by_config), b = make_plant(h, other);
  for (int i = 0; i < 500; ++i) {
    a.step(a.trim_command());
    b.step(b.trim_command());
  }
  CHECK(b.truth().omega_body_radps.x() == Approx(a.truth().omega_body_radps.x()).epsilon(1e-9));
  CHECK(b.truth().velocity_body_mps.y() == Approx(a.truth().velocity_body_mps.y()).epsilon(1e-9));
  CHECK(std::fabs(a.truth().omega_body_radps.x()) > 1e-4);
}

TEST_CASE("sensor_bias from the model is a constant roll moment and side force", "[plant][model_effects]") {
  const double L0 = 1.0e-4, Y0 = -2.0e-3;
  const Fixture g = with_effect("sensor_bias", {{"L_0", L0}, {"Y_0", Y0}});
  const PlantModel plain = make_plant(Fixture{});
  PlantModel biased = make_plant(g);
  REQUIRE(plain.truth().angular_accel_body_radps2.x() == 0.0);
  CHECK(biased.truth().angular_accel_body_radps2.x() ==
        Approx(g.vehicle.Izz_kgm2 / g.vehicle.Ic() * L0).epsilon(1e-12));
  CHECK(biased.truth().specific_force_body_mps2.y() == Approx(Y0 / g.vehicle.mass_kg).epsilon(1e-12));
  // The same as the plant file's constant load.
  PlantConfig by_config;
  by_config.effects.get<effects::ConstantLoadConfig>() = {true, L0, Y0};
  PlantModel a = make_plant(Fixture{}, by_config);
  for (int i = 0; i < 200; ++i) {
    a.step(a.trim_command());
    biased.step(biased.trim_command());
  }
  CHECK(biased.truth().omega_body_radps.x() == a.truth().omega_body_radps.x());
  CHECK(biased.truth().omega_body_radps.x() > 1e-3);
}

TEST_CASE("dihedral_coupling from the model sets the dihedral derivatives", "[plant][model_effects]") {
  const double L_dd = 1.41e-3, Y_dd = -6.06e-2;
  const Fixture g = with_effect("dihedral_coupling", {{"L_dd", L_dd}, {"Y_dd", Y_dd}});
  Fixture d;  // the same derivatives in the model's derivatives
  d.model.derivatives["L_dd"] = L_dd;
  d.model.derivatives["Y_dd"] = Y_dd;
  PlantModel a = make_plant(d), b = make_plant(g), plain = make_plant(Fixture{});
  ActuatorInput cmd = a.trim_command();
  cmd.dihedral_rad = 0.1;
  for (int i = 0; i < 300; ++i) {
    a.step(cmd);
    b.step(cmd);
    plain.step(cmd);
  }
  CHECK(b.truth().omega_body_radps.x() == a.truth().omega_body_radps.x());
  CHECK(b.truth().velocity_body_mps.y() == a.truth().velocity_body_mps.y());
  CHECK(std::fabs(b.truth().omega_body_radps.x()) > 1e-3);
  CHECK(std::fabs(plain.truth().omega_body_radps.x()) < 1e-12);
  // Given both as a derivative and in effects: refused, naming it.
  Fixture both = d;
  both.model.effects["dihedral_coupling"] = {{"L_dd", L_dd}};
  CHECK_THROWS_WITH(make_plant(both), Catch::Contains("effects.dihedral_coupling.L_dd"));
}

TEST_CASE("yaw_coupling from the model sets Lr and Yr (acting where r is a state)", "[plant][model_effects]") {
  // Lateral4: the model without Lr, Yr among its derivatives but in effects flies as the original.
  const DerivativeModel full = load_model(kModels + "nimble_lateral4_yaw.yaml");
  const Vehicle vehicle = load_vehicle(full.vehicle_file);
  DerivativeModel moved = full, without = full;
  moved.derivatives.erase("Lr");
  moved.derivatives.erase("Yr");
  without.derivatives.erase("Lr");
  without.derivatives.erase("Yr");
  moved.effects["yaw_coupling"] = {{"Lr", full.at("Lr")}, {"Yr", full.at("Yr")}};
  PlantConfig cfg;
  cfg.initial.r_radps = 0.5;
  PlantModel a(full, std::nullopt, vehicle, cfg), b(moved, std::nullopt, vehicle, cfg),
      c(without, std::nullopt, vehicle, cfg);
  for (int i = 0; i < 300; ++i) {
    a.step(a.trim_command());
    b.step(b.trim_command());
    c.step(c.trim_command());
  }
  CHECK(b.truth().omega_body_radps.x() == a.truth().omega_body_radps.x());
  CHECK(b.truth().velocity_body_mps.y() == a.truth().velocity_body_mps.y());
  CHECK(std::fabs(c.truth().omega_body_radps.x() - a.truth().omega_body_radps.x()) > 1e-3);
}

TEST_CASE("lateral_gust from the model has the model's sigma and tau", "[plant][model_effects]") {
  const Fixture g = with_effect("lateral_gust", {{"sigma_mps", 0.2}, {"tau_s", 0.05}});
  PlantConfig file_gust;  // the plant file's gust, replaced by the model's
  file_gust.effects.get<effects::LateralGustConfig>() = {true, 1.0, 0.5};
  file_gust.seed = 7;
  PlantConfig by_config;
  by_config.effects.get<effects::LateralGustConfig>() = {true, 0.2, 0.05};
  by_config.seed = 7;
  PlantModel a = make_plant(g, file_gust), b = make_plant(Fixture{}, by_config);
  CHECK(same_gust_rms(a, b, 60000) == Approx(0.2).epsilon(0.1));
}

TEST_CASE("kinematic and gravity terms from the model are the plant's equations of motion", "[plant][model_effects]") {
  // Set 1 with kinematic_coupling and gravity_nonlinearity flies exactly as set 1: the plant's
  // equations of motion carry p w and g sin(phi) already.
  const Fixture f;
  Fixture k;
  k.model = load_model(kModels + "nimble_lateral_set1_kinematic.yaml");
  REQUIRE(k.model.effects.count("kinematic_coupling") == 1);
  REQUIRE(k.model.effects.count("gravity_nonlinearity") == 1);
  PlantConfig cfg;
  cfg.initial.phi_rad = 0.3;
  cfg.initial.p_radps = 0.5;
  PlantModel a = make_plant(f, cfg), b = make_plant(k, cfg);
  for (int i = 0; i < 500; ++i) {
    a.step(a.trim_command());
    b.step(b.trim_command());
  }
  CHECK(b.state() == a.state());
}

TEST_CASE("effectiveness step: from t_change_s on the plant flies L_df and Y_df changed by their fractions",
          "[plant][model_effects]") {
  const double fL = -0.3, fY = -0.2;
  ActuatorInput cmd;
  auto flown = [&](PlantModel plant, int steps) {
    cmd = plant.trim_command();
    cmd.flap_freq_left_radps += 10;
    for (int i = 0; i < steps; ++i) plant.step(cmd);
    return plant;
  };
  // Changed from the start: the same as a model with the changed derivatives.
  PlantConfig from_start;
  from_start.effects.get<effects::EffectivenessStepConfig>() = {true, 0.0, fL, fY};
  Fixture scaled;
  scaled.model.derivatives["L_df"] *= 1.0 + fL;
  scaled.model.derivatives["Y_df"] *= 1.0 + fY;
  const PlantModel a = flown(make_plant(Fixture{}, from_start), 300), b = flown(make_plant(scaled), 300);
  CHECK(a.truth().omega_body_radps.x() == Approx(b.truth().omega_body_radps.x()).epsilon(1e-9));
  CHECK(a.truth().velocity_body_mps.y() == Approx(b.truth().velocity_body_mps.y()).epsilon(1e-9));
  CHECK(std::fabs(a.truth().omega_body_radps.x()) > 1e-2);
  // Changed at 0.3 s: the plain plant's flight until then, another after.
  PlantConfig later;
  later.effects.get<effects::EffectivenessStepConfig>() = {true, 0.3, fL, fY};
  const int before = static_cast<int>(0.3 / make_plant(Fixture{}).dt_s()) - 1;
  CHECK(flown(make_plant(Fixture{}, later), before).truth().omega_body_radps.x() ==
        flown(make_plant(Fixture{}), before).truth().omega_body_radps.x());
  CHECK(std::fabs(flown(make_plant(Fixture{}, later), 600).truth().omega_body_radps.x() -
                  flown(make_plant(Fixture{}), 600).truth().omega_body_radps.x()) > 1e-3);

  // From a model: the fractions are the coefficients over the model's L_df and Y_df.
  const Fixture g = with_effect(
      "effectiveness_step",
      {{"L_df_step", fL * 1.06e-4}, {"Y_df_step", fY * -8.63e-4}, {"t_change_s", 0.3}, {"t_change_lo_s", 0.2}});
  const PlantModel c = flown(make_plant(g), 600), d = flown(make_plant(Fixture{}, later), 600);
  CHECK(c.truth().omega_body_radps.x() == Approx(d.truth().omega_body_radps.x()).epsilon(1e-9));
  CHECK_THROWS_WITH(make_plant(with_effect("effectiveness_step", {{"L_df_step", -1e-5}})),
                    Catch::Contains("effects.effectiveness_step") && Catch::Contains("t_change_s"));
  CHECK_THROWS_WITH(make_plant(with_effect("effectiveness_step", {{"L_df_step", -5e-4}, {"t_change_s", 1.0}})),
                    Catch::Contains("effects.effectiveness_step.L_df_step / L_df"));
}

TEST_CASE(
    "effectiveness drift: L_df and Y_df scale with 1 + rate (t - t_ref) / 60, clamped at 0, and a model's "
    "coefficients give the rate",
    "[plant][model_effects]") {
  effects::EffectivenessDriftConfig c{true, -0.05, 10.0};
  double L = 0.0, Y = 0.0;
  effects::add_effectiveness_drift(c, 40.0, 2e-3, -1e-2, L, Y);  // 30 s after t_ref: -2.5 %
  CHECK(L == Approx(-0.025 * 2e-3));
  CHECK(Y == Approx(-0.025 * -1e-2));
  L = Y = 0.0;
  effects::add_effectiveness_drift(c, 10.0 + 3600.0, 2e-3, -1e-2, L, Y);  // an hour later: no input left, not reversed
  CHECK(L == Approx(-2e-3));
  c.enabled = false;
  L = 0.0;
  effects::add_effectiveness_drift(c, 40.0, 2e-3, -1e-2, L, Y);
  CHECK(L == 0.0);

  // Flown: differs from the plain plant, and not at all with rate 0.
  auto flown = [](PlantModel plant) {
    ActuatorInput cmd = plant.trim_command();
    cmd.flap_freq_left_radps += 10;
    for (int i = 0; i < 600; ++i) plant.step(cmd);
    return plant.truth().omega_body_radps.x();
  };
  PlantConfig drift, none;
  drift.effects.get<effects::EffectivenessDriftConfig>() = {true, -0.5, 0.0};
  none.effects.get<effects::EffectivenessDriftConfig>() = {true, 0.0, 0.0};
  CHECK(flown(make_plant(Fixture{}, none)) == flown(make_plant(Fixture{})));
  CHECK(std::fabs(flown(make_plant(Fixture{}, drift)) - flown(make_plant(Fixture{}))) > 1e-5);

  // From a model: rate = 60 L_df_rate / L_df (per minute), t_ref = t_mid_s.
  const Fixture f;
  const std::map<std::string, double> params{
      {"L_df_rate", -0.05 / 60.0 * 1.06e-4}, {"Y_df_rate", 1e-6}, {"t_mid_s", 30.0}};
  effects::EffectivenessDriftConfig m;
  effects::effectiveness_drift_from_model({f.model, "effectiveness_drift", params}, m);
  CHECK(m.enabled);
  CHECK(m.rate_per_min == Approx(-0.05));
  CHECK(m.t_ref_s == 30.0);
  CHECK_THROWS_WITH(make_plant(with_effect("effectiveness_drift", {{"L_df_rate", 1e-4}})),
                    Catch::Contains("effects.effectiveness_drift.L_df_rate / L_df per minute"));
  CHECK_THROWS_WITH(make_plant(with_effect("effectiveness_drift", {{"t_mid_s", 3.0}})),
                    Catch::Contains("effects.effectiveness_drift") && Catch::Contains("rate_per_min"));
}

TEST_CASE("plant terms add coefficient * expression to the roll moment and side force", "[plant][terms]") {
  Fixture f;
  PlantConfig cfg;
  cfg.initial.p_radps = 2.0;
  cfg.initial.v_mps = 0.5;
  const PlantModel base = make_plant(f, cfg);
  cfg.terms = {nimble::Term{"L", nimble::TermExpression::parse("p^3"), -2.0e-5, "test"},
               nimble::Term{"Y", nimble::TermExpression::parse("v*abs(v)"), -0.02, "test"}};
  const PlantModel with = make_plant(f, cfg);
  const double Izz = f.vehicle.Izz_kgm2, Ic = f.vehicle.Ic(), m = f.vehicle.mass_kg;
  // At the initial state: p_dot += Izz/Ic * (-2e-5 * 8), the side specific force += -0.02 * 0.25 / m.
  CHECK(with.truth().angular_accel_body_radps2.x() - base.truth().angular_accel_body_radps2.x() ==
        Approx(Izz / Ic * -2.0e-5 * 8.0).epsilon(1e-9));
  CHECK(with.truth().specific_force_body_mps2.y() - base.truth().specific_force_body_mps2.y() ==
        Approx(-0.02 * 0.25 / m).epsilon(1e-9));

  // A lag in the plant: the moment of lag(delta_f, tau) follows delta_f with the time constant.
  PlantConfig lag_cfg;
  lag_cfg.terms = {nimble::Term{"L", nimble::TermExpression::parse("lag(delta_f, 0.05)"), 1.0e-4, "test"}};
  PlantModel lagged = make_plant(f, lag_cfg);
  PlantModel plain = make_plant(f);
  auto cmd = plain.trim_command();
  cmd.flap_freq_left_radps += 1.0;
  for (int i = 0; i < 300; ++i) {
    lagged.step(cmd);
    plain.step(cmd);
  }
  // After 0.3 s the lagged moment (positive with delta_f) has rolled the vehicle faster.
  CHECK(lagged.truth().omega_body_radps.x() > plain.truth().omega_body_radps.x());
}

TEST_CASE("a plant term ratelimit(delta_f, 300) - delta_f limits the flap moment on a fast flap input only",
          "[plant][terms]") {
  // With coefficient L_df the term replaces the flap moment L_df delta_f by L_df times delta_f
  // limited to 300 rad/s per s. A flap difference of +-60 rad/s (command) gives delta_f rates
  // up to about 570 rad/s^2 at 10 Hz (limited), 130 rad/s^2 at 0.5 Hz (not: below half the
  // limit, so the plant's RK4 stages, which see the window of the step before, do not clip).
  Fixture f;
  PlantConfig cfg;
  cfg.terms = {nimble::Term{"L", nimble::TermExpression::parse("ratelimit(delta_f, 300) - delta_f"), f.model.at("L_df"),
                            "test"}};
  const auto fly = [&](double hz, int steps) {
    PlantModel limited = make_plant(f, cfg), plain = make_plant(f);
    double max_gap = 0.0, max_plain = 0.0, max_df_rate = 0.0, df_before = 0.0;
    int differ = 0;
    for (int i = 0; i < steps; ++i) {
      auto cmd = plain.trim_command();
      const double half = 30.0 * std::sin(2.0 * M_PI * hz * i * 1e-3);
      cmd.flap_freq_left_radps += half;
      cmd.flap_freq_right_radps -= half;
      limited.step(cmd);
      plain.step(cmd);
      const double p_limited = limited.truth().omega_body_radps.x(), p_plain = plain.truth().omega_body_radps.x();
      differ += p_limited != p_plain;
      max_gap = std::max(max_gap, std::fabs(p_limited - p_plain));
      max_plain = std::max(max_plain, std::fabs(p_plain));
      max_df_rate = std::max(max_df_rate, std::fabs(plain.truth().delta_f_radps - df_before) / 1e-3);
      df_before = plain.truth().delta_f_radps;
    }
    return std::tuple<int, double, double, double>{differ, max_gap, max_plain, max_df_rate};
  };
  const auto [slow_differ, slow_gap, slow_plain, slow_rate] = fly(0.5, 1000);
  CHECK(slow_rate < 150.0);
  CHECK(slow_differ == 0);
  CHECK(slow_gap == 0.0);
  CHECK(slow_plain > 1.0);
  const auto [fast_differ, fast_gap, fast_plain, fast_rate] = fly(10.0, 300);
  CHECK(fast_rate > 450.0);
  CHECK(fast_differ > 250);
  CHECK(fast_gap > 0.1 * fast_plain);
}

// ---------------------------------------------------------------------------------------
// The plant holds one process per effect that acts, from the registry, and has no line for any
// one effect.

TEST_CASE("effects act through their processes: none when all are off, one per effect that is on",
          "[plant][effect_process]") {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal(0.0, 1.0);
  effects::ProcessContext context{1e-3, rng, normal};
  effects::EffectsConfig off;
  CHECK(effects::make_effect_processes(off, context).empty());

  effects::EffectsConfig on;
  on.get<effects::LateralInflowConfig>().enabled = true;
  on.get<effects::LateralInflowConfig>().Y_vv_ns2pm2 = -0.02;
  on.get<effects::ActuatorDelayConfig>().enabled = true;
  on.get<effects::ActuatorDelayConfig>().delay_s = 0.0;  // on with no delay: acts on nothing, so no process
  on.get<effects::LateralGustConfig>().enabled = true;
  on.get<effects::LateralGustConfig>().sigma_mps = 0.3;
  const auto processes = effects::make_effect_processes(on, context);
  REQUIRE(processes.size() == 2);
  double L = 0.0, Y = 0.0;
  effects::LoadInputs in;
  in.v_rel = 2.0;
  processes[0]->add_loads(in, L, Y);
  CHECK(Y == Approx(-0.02 * 4.0));
  CHECK(processes[0]->side_wind_mps() == 0.0);
  // Only the gust has a wind, and it moves with its steps.
  for (int k = 0; k < 100; ++k) processes[1]->step(1e-3, rng, normal);
  CHECK(processes[1]->side_wind_mps() != 0.0);
}

TEST_CASE("the flapping forcing draws its phases whether it is on or not: the gust's draws stay where they were",
          "[plant][effect_process]") {
  const auto gust_after = [](bool forcing_on) {
    std::mt19937_64 rng(11);
    std::normal_distribution<double> normal(0.0, 1.0);
    effects::ProcessContext context{1e-3, rng, normal};
    effects::EffectsConfig fx;
    fx.get<effects::FlappingForcingConfig>().enabled = forcing_on;
    fx.get<effects::FlappingForcingConfig>().roll_moment_amplitudes_nm = {2e-3, 1e-3};
    fx.get<effects::FlappingForcingConfig>().side_force_amplitudes_n = {1e-2};
    fx.get<effects::LateralGustConfig>().enabled = true;
    fx.get<effects::LateralGustConfig>().form = effects::GustForm::kDryden;
    fx.get<effects::LateralGustConfig>().sigma_mps = 0.5;
    auto processes = effects::make_effect_processes(fx, context);
    REQUIRE(processes.size() == (forcing_on ? 2u : 1u));
    for (int k = 0; k < 50; ++k) {
      for (auto& p : processes) p->step(1e-3, rng, normal);
    }
    return processes.back()->side_wind_mps();
  };
  CHECK(gust_after(true) == gust_after(false));
  CHECK(gust_after(true) != 0.0);
}

// ---------------------------------------------------------------------------------------
// An effect the term grammar states needs no plant code: its plant side comes from its columns.

TEST_CASE("a term effect's plant section is its columns' coefficients, flown as the plant's terms",
          "[plant][model_effects]") {
  using namespace nimble::effects;
  const Effect cubic = term_effect(
      {"cubic_roll_damping",
       "p^3 in roll moment",
       {},
       {{"L", "L_ppp", "p^3", ColumnForm::kTerm, "p^3", "N m s^3/rad^3", nimble::Range::closed(-1e-3, 1e-3)}},
       Scan::kNone,
       Signature::kNone,
       EffectivenessChange::kNone,
       "plant.effects.cubic_roll_damping"});
  REQUIRE(cubic.has_plant_section());
  EffectsConfig fx;
  CHECK_FALSE(cubic.plant.enabled(fx));
  CHECK(cubic.plant.terms(fx, nimble::Trim{}).empty());
  {
    ConfigMap m = ConfigMap::load_string("enabled: true\nL_ppp: -2.5e-5\n", "plant.yaml");
    cubic.plant.load(m, fx);
    m.finish();
  }
  CHECK(cubic.plant.enabled(fx));
  const std::vector<nimble::Term> terms = cubic.plant.terms(fx, nimble::Trim{});
  REQUIRE(terms.size() == 1);
  CHECK(terms[0].equation == "L");
  CHECK(terms[0].expression.to_string() == "p^3");
  CHECK(terms[0].coefficient == -2.5e-5);
  // The section's keys are the model's, with the column's range; a value outside it is refused.
  ConfigMap wide = ConfigMap::load_string("enabled: true\nL_ppp: 0.5\n", "plant.yaml");
  CHECK_THROWS_WITH(cubic.plant.load(wide, fx), Catch::Contains("L_ppp"));
  const std::string rows = cubic.plant.markdown_rows("plant.effects.cubic_roll_damping.");
  CHECK(rows.find("`plant.effects.cubic_roll_damping.L_ppp`") != std::string::npos);
  CHECK(rows.find("N m s^3/rad^3") != std::string::npos);
  // Off again: no terms.
  ConfigMap off = ConfigMap::load_string("enabled: false\nL_ppp: -2.5e-5\n", "plant.yaml");
  cubic.plant.load(off, fx);
  CHECK(cubic.plant.terms(fx, nimble::Trim{}).empty());
  // From a model's effects: section, with the same key; an unknown key is refused by name.
  DerivativeModel model;
  model.name = "m";
  const std::map<std::string, double> params{{"L_ppp", -1e-5}};
  std::map<std::string, double> derivatives;
  cubic.from_model(ModelSection{model, "cubic_roll_damping", params}, fx, derivatives);
  REQUIRE(cubic.plant.terms(fx, nimble::Trim{}).size() == 1);
  CHECK(cubic.plant.terms(fx, nimble::Trim{})[0].coefficient == -1e-5);
  const std::map<std::string, double> typo{{"L_pp", -1e-5}};
  CHECK_THROWS_WITH(cubic.from_model(ModelSection{model, "cubic_roll_damping", typo}, fx, derivatives),
                    Catch::Contains("L_pp") && Catch::Contains("L_ppp"));
  // A column with the trim's u0 flies at the plant's trim: its u is the whole forward speed.
  const Effect speed = term_effect(
      {"speed_roll",
       "(u - u0) p in roll moment",
       {"u"},
       {{"L", "L_up", "(u - u0) p", ColumnForm::kTerm, "(u - u0)*p", "N s^2", nimble::Range::closed(-0.1, 0.1)}},
       Scan::kNone,
       Signature::kNone,
       EffectivenessChange::kNone,
       "plant.effects.speed_roll"});
  ConfigMap on = ConfigMap::load_string("enabled: true\nL_up: 1e-4\n", "plant.yaml");
  speed.plant.load(on, fx);
  nimble::Trim trim;
  trim.u0_mps = 0.25;
  const std::vector<nimble::Term> at_trim = speed.plant.terms(fx, trim);
  REQUIRE(at_trim.size() == 1);
  CHECK(at_trim[0].expression.same_as(nimble::TermExpression::parse("(u - 0.25)*p")));
  // A column that is not a load term cannot make a term effect.
  CHECK_THROWS_AS(term_effect({"bad",
                               "x",
                               {},
                               {{"L", "L_x", "x", ColumnForm::kInputTimesTime}},
                               Scan::kNone,
                               Signature::kNone,
                               EffectivenessChange::kNone,
                               ""}),
                  std::logic_error);
}
