// Unit tests of the PD attitude controller: signs, mixing, saturation, throttle,
// gain sets by name and strict config loading.

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <catch2/catch.hpp>

#include "../support/config_error.h"

#include "controller/attitude_controller.h"
#include "core/config.h"
#include "core/vehicle.h"

using namespace nimble;

namespace {

const std::string kConfigs = std::string(RIG_SOURCE_DIR) + "/rig_configs/";

/// Runs `n` steps with the same input and returns the last output.
ControllerOutput run(AttitudeController& c, const ControllerInput& in, int n = 512) {
  ControllerOutput out;
  for (int k = 0; k < n; ++k) out = c.step(in);
  return out;
}

ControllerConfig from_text(const std::string& text) {
  ConfigMap map = ConfigMap::load_string(text, "inline.yaml");
  return controller_config_from(map);
}

/// Requires a ConfigError naming `key` (and `value` if given) from from_text().
void expect_key_error(const std::string& text, const std::string& key, const std::string& value = "") {
  nimble::test::expect_inline_key_error([](const std::string& t) { return from_text(t); }, text, key, value);
}

}  // namespace

TEST_CASE("positive roll error gives positive roll command and delta_f (left faster)", "[controller]") {
  ControllerConfig cfg;
  AttitudeController c(cfg);
  ControllerInput in;
  in.phi_rad = -0.1;  // reference stays 0: error +0.1 rad
  const ControllerOutput out = run(c, in);
  CHECK(out.roll_error_rad == Approx(0.1).margin(1e-9));
  CHECK(out.roll_cmd_norm == Approx(1.406 * 0.1).epsilon(1e-6));
  CHECK(out.delta_f_cmd_radps == Approx(cfg.roll_cmd_to_delta_f_radps * 1.406 * 0.1).epsilon(1e-6));
  CHECK(out.delta_f_cmd_radps > 0.0);
  CHECK(out.flap_freq_left_radps > out.flap_freq_right_radps);
  CHECK_FALSE(out.saturated);
}

TEST_CASE("rate error acts through Kd with the right sign", "[controller]") {
  AttitudeController c(ControllerConfig{});
  ControllerInput in;
  in.p_radps = -1.0;  // rolling left while the reference rate is 0
  const ControllerOutput out = run(c, in);
  CHECK(out.roll_cmd_norm == Approx(0.200).epsilon(1e-6));
  CHECK(out.delta_f_cmd_radps > 0.0);
}

TEST_CASE("mixing: left/right = f_c +- delta_f/2 + k 0.1 |roll|", "[controller]") {
  ControllerConfig cfg;
  const double k = cfg.roll_cmd_to_delta_f_radps;
  for (const double phi : {-0.2, 0.2}) {
    AttitudeController c(cfg);
    ControllerInput in;
    in.phi_rad = phi;
    const ControllerOutput out = run(c, in);
    const double roll = out.roll_cmd_norm;
    CHECK(roll == Approx(-1.406 * phi).epsilon(1e-6));
    CHECK(out.flap_freq_left_radps == Approx(cfg.f_trim_radps + 0.5 * k * roll + 0.1 * k * std::fabs(roll)));
    CHECK(out.flap_freq_right_radps == Approx(cfg.f_trim_radps - 0.5 * k * roll + 0.1 * k * std::fabs(roll)));
    CHECK(out.delta_f_cmd_radps == Approx(k * roll));
    CHECK(out.collective_radps == Approx(cfg.f_trim_radps + 0.1 * k * std::fabs(roll)));
  }
}

TEST_CASE("throttle factor raises throttle and collective, delta_t is relative to trim", "[controller]") {
  ControllerConfig cfg;
  AttitudeController c(cfg);
  ControllerInput in;
  CHECK(c.step(in).delta_throttle_pct == Approx(0.0).margin(1e-12));  // no throttle set-point: trim
  in.throttle_pct = cfg.trim_throttle_pct;
  in.throttle_factor = 1.2;
  const ControllerOutput out = c.step(in);
  CHECK(out.throttle_cmd_pct == Approx(1.2 * cfg.trim_throttle_pct));
  CHECK(out.delta_throttle_pct == Approx(0.2 * cfg.trim_throttle_pct));
  CHECK(out.collective_radps ==
        Approx(cfg.f_trim_radps + cfg.throttle_to_freq_radps_per_pct * 0.2 * cfg.trim_throttle_pct));
  CHECK_FALSE(out.saturated);
}

TEST_CASE("saturation clips to +-1 and is counted", "[controller]") {
  ControllerConfig cfg;
  AttitudeController c(cfg);
  ControllerInput in;
  in.phi_rad = -1.5;  // fast gains: 2.1 before clipping
  run(c, in, 100);
  const ControllerOutput out = c.step(in);
  CHECK(out.roll_cmd_norm == 1.0);
  CHECK(out.saturated);
  CHECK(out.delta_f_cmd_radps == Approx(cfg.roll_cmd_to_delta_f_radps));
  CHECK(c.counters().roll_saturations > 50);
  CHECK(c.counters().saturated_steps >= c.counters().roll_saturations);
  CHECK(c.counters().steps == 101);

  AttitudeController t(cfg);
  ControllerInput thr;
  thr.throttle_pct = 90.0;
  thr.throttle_factor = 1.5;
  const ControllerOutput o2 = t.step(thr);
  CHECK(o2.throttle_cmd_pct == 100.0);
  CHECK(o2.saturated);
  CHECK(t.counters().throttle_saturations == 1);

  ControllerConfig narrow = cfg;
  narrow.flap_freq_max_radps = cfg.f_trim_radps + 1.0;
  AttitudeController f(narrow);
  ControllerInput big;
  big.phi_rad = -0.3;
  const ControllerOutput o3 = run(f, big, 100);
  CHECK(o3.flap_freq_left_radps == Approx(narrow.flap_freq_max_radps));
  CHECK(o3.delta_f_cmd_radps == Approx(o3.flap_freq_left_radps - o3.flap_freq_right_radps));
  CHECK(f.counters().flap_freq_saturations > 0);
}

TEST_CASE("step never throws and counts non-finite inputs", "[controller]") {
  AttitudeController c(ControllerConfig{});
  ControllerInput in;
  in.phi_rad = std::numeric_limits<double>::quiet_NaN();
  in.p_radps = std::numeric_limits<double>::infinity();
  in.roll_sp_rad = std::numeric_limits<double>::quiet_NaN();
  in.throttle_factor = std::numeric_limits<double>::quiet_NaN();
  ControllerOutput out;
  REQUIRE_NOTHROW(out = c.step(in));
  CHECK(std::isfinite(out.flap_freq_left_radps));
  CHECK(std::isfinite(out.flap_freq_right_radps));
  CHECK(c.counters().invalid_inputs == 1);
}

TEST_CASE("pitch loop: positive pitch error gives nose-up dihedral", "[controller]") {
  ControllerConfig cfg;
  AttitudeController c(cfg);
  ControllerInput in;
  in.theta_rad = -0.1;
  const ControllerOutput out = run(c, in);
  CHECK(out.pitch_cmd_norm == Approx(cfg.pitch_gains.kp_per_rad * 0.1).epsilon(1e-6));
  CHECK(out.dihedral_rad == Approx(cfg.pitch_cmd_to_dihedral_rad * out.pitch_cmd_norm));
  CHECK(out.wing_root_rad == 0.0);
}

TEST_CASE("gain sets by name, unknown name is an error naming it", "[controller][gains]") {
  ControllerConfig cfg;
  AttitudeController c(cfg);
  CHECK(c.gain_set() == "fast");
  CHECK(c.gains().kp_per_rad == 1.406);
  REQUIRE(c.select_gain_set("slow"));
  CHECK(c.gains().kp_per_rad == 0.625);
  CHECK(c.gains().kd_per_radps == 0.156);
  CHECK(c.step(ControllerInput{}).roll_kp_per_rad == 0.625);
  CHECK_FALSE(c.select_gain_set("medium"));
  CHECK(c.gain_set() == "slow");
  CHECK(c.counters().unknown_gain_set_requests == 1);
  CHECK_THROWS_WITH(roll_gain_set(cfg, "medium"), Catch::Contains("medium") && Catch::Contains("fast"));

  expect_key_error("default_gain_set: medium\n", "default_gain_set", "medium");

  const ControllerConfig user = from_text(
      "roll_gain_sets:\n  gentle: {kp_per_rad: 0.3, kd_per_radps: 0.1}\n"
      "default_gain_set: gentle\n");
  CHECK(user.roll_gain_sets.size() == 3);
  AttitudeController g(user);
  CHECK(g.gain_set() == "gentle");
  CHECK(g.gains().kp_per_rad == 0.3);
  REQUIRE(g.select_gain_set("fast"));
  expect_key_error("roll_gain_sets:\n  gentle: {kp_per_rad: 0.3}\n", "roll_gain_sets.gentle.kd_per_radps");
  expect_key_error("roll_gain_sets:\n  fast: {kp_per_rad: -1}\n", "roll_gain_sets.fast.kp_per_rad", "-1");
}

TEST_CASE("every controller config error names its key", "[controller][config]") {
  expect_key_error("rate_hzz: 512\n", "rate_hzz", "512");
  expect_key_error("rate_hz: 10\n", "rate_hz", "10");
  expect_key_error("mixing: {roll_cmd_to_delta_f_radps: -5}\n", "mixing.roll_cmd_to_delta_f_radps", "-5");
  expect_key_error("mixing: {roll_cmd_to_delta_f_radps: 125 rad/s}\n", "mixing.roll_cmd_to_delta_f_radps");
  expect_key_error("mixing: {roll_map: 125}\n", "mixing.roll_map", "125");
  expect_key_error("lowpass: {roll_cutoff_hz: 300}\n", "lowpass.roll_cutoff_hz", "300");
  expect_key_error("reference: {roll: {zeta: abc}}\n", "reference.roll.zeta", "abc");
  expect_key_error("reference: {roll: {setpoint_max_rad: 2.0}}\n", "reference.roll.setpoint_max_rad", "2.0");
  expect_key_error("reference: {yaw: {zeta: 0.8}}\n", "reference.yaw");
  expect_key_error("throttle: {trim_throttle_pct: 0}\n", "throttle.trim_throttle_pct", "0");
  expect_key_error("throttle: {f_trim_radps: 250}\n", "throttle.f_trim_radps", "250");
  expect_key_error("limits: {flap_freq_min_radps: 50, flap_freq_max_radps: 40}\n", "limits.flap_freq_max_radps", "40");
  expect_key_error("pitch_gains: {kp: 1}\n", "pitch_gains.kp", "1");
}

TEST_CASE("shipped controller config: loads, hover trim from the thrust curve, map in the stable range",
          "[controller][config]") {
  const ControllerConfig cfg = load_controller_config(kConfigs + "controller/nimble_attitude.yaml");
  const Vehicle vehicle = load_vehicle(kConfigs + "vehicles/nimble_no_wifi.yaml");
  const double f_hover = hover_flap_frequency_radps(vehicle.mass_kg, vehicle.gravity_mps2);
  CHECK(flap_thrust_n(f_hover) == Approx(vehicle.mass_kg * vehicle.gravity_mps2).epsilon(1e-12));
  CHECK(cfg.f_trim_radps == Approx(f_hover).margin(1e-3));
  CHECK(cfg.throttle_to_freq_radps_per_pct == Approx(cfg.f_trim_radps / cfg.trim_throttle_pct).margin(1e-3));
  // Linear closed loop on set 1: with either gain set the linear loop is stable for 10..160 rad/s per unit.
  CHECK(cfg.roll_cmd_to_delta_f_radps >= 10.0);
  CHECK(cfg.roll_cmd_to_delta_f_radps <= 160.0);
  CHECK(cfg.roll_gain_sets.at("fast").kp_per_rad == 1.406);
  CHECK(cfg.roll_gain_sets.at("slow").kd_per_radps == 0.156);
  // The built-in defaults are the values of the file.
  const ControllerConfig d;
  CHECK(d.f_trim_radps == Approx(cfg.f_trim_radps).margin(1e-5));
  CHECK(d.roll_reference.omega_radps == Approx(cfg.roll_reference.omega_radps).margin(1e-5));
  CHECK(d.trim_throttle_pct == cfg.trim_throttle_pct);
  CHECK(d.roll_cmd_to_delta_f_radps == cfg.roll_cmd_to_delta_f_radps);
  CHECK_THROWS_AS(hover_flap_frequency_radps(0.0, 9.81), std::invalid_argument);
}
