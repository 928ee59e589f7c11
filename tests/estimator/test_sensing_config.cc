// Unit tests of the sensing config loaders (estimator/sensing_config.h) and the shipped
// rig_configs/sensing/default_sensing.yaml.

#include <cmath>
#include <string>

#include <catch2/catch.hpp>

#include "estimator/sensing_config.h"

using namespace nimble;

namespace {

const std::string kDefaultFile = std::string(RIG_SOURCE_DIR) + "/rig_configs/sensing/default_sensing.yaml";

SensingConfig load_text(const std::string& text) {
  ConfigMap map = ConfigMap::load_string(text, "inline.yaml");
  return sensing_config_from(map);
}

void expect_config_error(const std::string& text, const std::string& key, const std::string& problem_part) {
  try {
    load_text(text);
    FAIL("expected a ConfigError for " << key);
  } catch (const ConfigError& e) {
    INFO(e.what());
    CHECK(e.file() == "inline.yaml");
    CHECK(e.key() == key);
    CHECK_THAT(std::string(e.what()), Catch::Contains(problem_part));
  }
}

}  // namespace

TEST_CASE("default_sensing.yaml loads and equals the struct defaults", "[sensing_config]") {
  const SensingConfig file = load_sensing_config(kDefaultFile);
  const SensingConfig def;
  const double tol = 1e-4;  // the file writes some values rounded (e.g. 0.05 deg/s in rad/s)
  CHECK(file.seed == def.seed);
  CHECK(file.imu.sample_rate_hz == def.imu.sample_rate_hz);
  CHECK(file.imu.gyro_noise_sigma_radps.isApprox(def.imu.gyro_noise_sigma_radps, tol));
  CHECK(file.imu.accel_noise_sigma_mps2.isApprox(def.imu.accel_noise_sigma_mps2, tol));
  CHECK(file.imu.gyro_bias_rw_radps_per_sqrts == def.imu.gyro_bias_rw_radps_per_sqrts);
  CHECK(file.imu.gyro_range_radps == Approx(def.imu.gyro_range_radps).epsilon(tol));
  CHECK(file.imu.accel_range_mps2 == Approx(def.imu.accel_range_mps2).epsilon(tol));
  REQUIRE(file.imu.flapping_harmonics.size() == def.imu.flapping_harmonics.size());
  for (std::size_t i = 0; i < def.imu.flapping_harmonics.size(); ++i) {
    CHECK(file.imu.flapping_harmonics[i].harmonic == def.imu.flapping_harmonics[i].harmonic);
    CHECK(file.imu.flapping_harmonics[i].gyro_amplitude_radps == def.imu.flapping_harmonics[i].gyro_amplitude_radps);
    CHECK(file.imu.flapping_harmonics[i].accel_amplitude_mps2 == def.imu.flapping_harmonics[i].accel_amplitude_mps2);
  }
  CHECK(file.imu.structural_mode_hz == 11.0);
  CHECK(file.imu.structural_gyro_amplitude_radps == def.imu.structural_gyro_amplitude_radps);
  CHECK(file.mocap.frame_rate_hz == 200.0);
  CHECK(file.mocap.mean_position_error_m == 0.85e-3);
  CHECK(file.mocap.attitude_noise_sigma_rad.isApprox(def.mocap.attitude_noise_sigma_rad, tol));
  CHECK(file.mocap.latency_us == def.mocap.latency_us);
  CHECK(file.mocap.exposure_us == def.mocap.exposure_us);
  CHECK(file.velocity_differentiator.span_frames == def.velocity_differentiator.span_frames);
  CHECK(file.velocity_differentiator.stride_frames == def.velocity_differentiator.stride_frames);
  // Thesis Eq 8.2.
  CHECK(file.ekf.gyro_noise_var_per_sample_rad2ps2 == Eigen::Vector3d(7.60, 2.60, 12.07));
  CHECK(file.ekf.accel_noise_var_per_sample_m2ps4 == Eigen::Vector3d(26.99, 36.66, 56.12));
  CHECK(file.ekf.attitude_var_rad2 == Eigen::Vector3d(0.125e-3, 0.057e-3, 0.037e-3));
  CHECK(file.ekf.velocity_var_m2ps2 == Eigen::Vector3d(0.113e-3, 0.216e-3, 0.135e-3));
  CHECK(file.ekf.attitude_var_rad2 == def.ekf.attitude_var_rad2);
  CHECK(file.ekf.process_noise_reference_rate_hz == 512.0);
  CHECK(file.ekf.gate_probability == def.ekf.gate_probability);
  CHECK(file.ekf.history_s == def.ekf.history_s);
  CHECK(file.ekf.latency_mode == EkfLatencyMode::kRollback);
  CHECK(file.ekf.initial_gyro_bias_sigma_radps == def.ekf.initial_gyro_bias_sigma_radps);
}

TEST_CASE("sensing config: every key optional, overrides applied", "[sensing_config]") {
  const SensingConfig empty = load_text("{}");
  CHECK(empty.ekf.gate_probability == 0.999);
  CHECK(ekf_history_needed_s(empty) == Approx(0.005 + 0.060 + 2.0 / 512.0));
  CHECK(load_text("ekf: {velocity_measurement: instant, latency: {history_s: 0.04}}").ekf.history_s ==
        0.04);                                                                               // 5 + 30 + 3.9 ms
  CHECK(load_text("ekf: {latency: {mode: naive, history_s: 0.01}}").ekf.history_s == 0.01);  // naive: no rollback
  CHECK(empty.ekf.velocity_measurement == EkfVelocityMeasurement::kWindowMean);
  const SensingConfig c = load_text(R"(
seed: 42
imu: {vibration_enabled: false, gyro_noise_sigma_radps: {y: 0.01}}
mocap: {latency_us: 20000, dropout_burst_rate_hz: 0}
velocity_differentiator: {span_frames: 4, stride_frames: 3}
ekf:
  velocity_measurement: instant
  latency: {mode: naive, history_s: 0.2}
  gate: {enabled: false}
  measurement_noise: {velocity_var_m2ps2: {v: 1.0e-3}}
)");
  CHECK(c.seed == 42);
  CHECK_FALSE(c.imu.vibration_enabled);
  CHECK(c.imu.gyro_noise_sigma_radps[1] == 0.01);
  CHECK(c.imu.gyro_noise_sigma_radps[0] == ImuModelConfig().gyro_noise_sigma_radps[0]);
  CHECK(c.mocap.latency_us == 20000);
  CHECK(c.velocity_differentiator.span_frames == 4);
  CHECK(c.ekf.latency_mode == EkfLatencyMode::kNaive);
  CHECK(c.ekf.velocity_measurement == EkfVelocityMeasurement::kInstant);
  CHECK(c.ekf.history_s == 0.2);
  CHECK_FALSE(c.ekf.gate_enabled);
  CHECK(c.ekf.velocity_var_m2ps2 == Eigen::Vector3d(0.113e-3, 1.0e-3, 0.135e-3));
}

TEST_CASE("sensing config: strict errors name file, key and problem", "[sensing_config]") {
  expect_config_error("imu: {gyro_noise_sigma: 0.1}", "imu.gyro_noise_sigma", "unknown key");
  expect_config_error("ekf: {process_noise: {gyro_var_per_sample_rad2ps2: {p: 1}}}",
                      "ekf.process_noise.gyro_var_per_sample_rad2ps2.p", "unknown key");
  expect_config_error("imu: {accel_noise_sigma_mps2: {z: -0.1}}", "imu.accel_noise_sigma_mps2.z", ">= 0");
  expect_config_error("mocap: {frame_rate_hz: 300}", "mocap.frame_rate_hz", "whole number of microseconds");
  expect_config_error("mocap: {latency_us: 5 ms}", "mocap.latency_us", "must be a number");
  expect_config_error("velocity_differentiator: {span_frames: 7}", "velocity_differentiator.span_frames", "even");
  expect_config_error("velocity_differentiator: {span_frames: 10, stride_frames: 5}",
                      "velocity_differentiator.stride_frames", "not white");
  expect_config_error("ekf: {latency: {mode: late}}", "ekf.latency.mode", "rollback, naive");
  expect_config_error("ekf: {velocity_measurement: mean}", "ekf.velocity_measurement", "window_mean, instant");
  // The rollback history must hold a velocity measurement's window when it arrives: 5 ms latency
  // + 60 ms span + 2 IMU periods = 68.9 ms by default.
  expect_config_error("ekf: {latency: {history_s: 0.05}}", "ekf.latency.history_s",
                      "= 68.9 ms; set ekf.latency.history_s >= 0.069");
  expect_config_error("mocap: {latency_us: 40000}", "ekf.latency.history_s", "latency 40 ms");
  expect_config_error("ekf: {gate: {probability: 1.0}}", "ekf.gate.probability", "in (0, 1)");
  expect_config_error("ekf: {measurement_noise: {attitude_var_rad2: {phi: 0}}}",
                      "ekf.measurement_noise.attitude_var_rad2.phi", "> 0");
  expect_config_error("imu: {flapping_harmonics: [{harmonic: 0}]}", "imu.flapping_harmonics[0].harmonic",
                      "in [1, 100]");
  expect_config_error("imu: {flapping_harmonics: {harmonic: 1}}", "imu.flapping_harmonics", "list");
  expect_config_error("sensors: {}", "sensors", "unknown key");
}

TEST_CASE("EKF noise matched to the emulated sensors", "[sensing_config]") {
  const SensingConfig s;
  const EkfConfig m = ekf_config_matched_to_sensors(s.ekf, s.imu, s.mocap, s.velocity_differentiator);
  CHECK(m.process_noise_reference_rate_hz == 512.0);
  CHECK(m.gyro_noise_var_per_sample_rad2ps2[0] == Approx(std::pow(0.05 * M_PI / 180.0, 2)));
  CHECK(m.accel_noise_var_per_sample_m2ps4[2] == Approx(std::pow(0.08 * 9.80665, 2)));
  CHECK(m.attitude_var_rad2[0] == Approx(0.125e-3));
  const double sigma_v = std::sqrt(2.0) * s.mocap.position_sigma_m() / 0.06;
  CHECK(m.velocity_var_m2ps2[1] == Approx(sigma_v * sigma_v + 0.25 * m.attitude_var_rad2.mean()));
  CHECK(m.gyro_bias_rw_radps_per_sqrts == s.imu.gyro_bias_rw_radps_per_sqrts);
  MatchedNoiseOptions with_vibration;
  with_vibration.include_vibration = true;
  const EkfConfig v = ekf_config_matched_to_sensors(s.ekf, s.imu, s.mocap, s.velocity_differentiator, with_vibration);
  CHECK(v.gyro_noise_var_per_sample_rad2ps2[2] ==
        Approx(m.gyro_noise_var_per_sample_rad2ps2[2] + 0.5 * (0.1 * 0.1 + 0.05 * 0.05 + 0.3 * 0.3)));
}
