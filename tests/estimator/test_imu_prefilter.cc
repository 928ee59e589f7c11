// The on-board IMU filtering (estimator/imu_prefilter.h): the flight vibration's lines removed,
// the motion passed without lag, its configuration checked.

#include <cmath>
#include <string>

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

#include "core/config.h"
#include "estimator/imu_prefilter.h"
#include "estimator/sensing_config.h"
#include "sensors/imu_model.h"

using namespace nimble;

namespace {

constexpr double kRate = 512.0;

/// RMS over samples [from, to) of (filtered gyro - true rate) and of the raw vibration, per axis.
struct Residual {
  Eigen::Vector3d filtered = Eigen::Vector3d::Zero(), raw = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_filtered = Eigen::Vector3d::Zero(), accel_raw = Eigen::Vector3d::Zero();
};

/// The flight-vibration IMU at rest with the flapping frequencies `left_hz`, `right_hz`, through
/// the prefilter given the same frequencies.
/// The white noise is off: what is left is what the lines leave.
Residual at_rest(const SensingConfig& sensing, ImuPrefilterConfig pf, double left_hz, double right_hz) {
  ImuModelConfig quiet = sensing.imu;
  quiet.gyro_noise_sigma_radps.setZero();
  quiet.accel_noise_sigma_mps2.setZero();
  ImuModel imu(quiet, 3);
  ImuPrefilter filter(pf, kRate);
  filter.set_flap_frequencies(2 * M_PI * left_hz, 2 * M_PI * right_hz, 0);
  Residual r;
  const int n = static_cast<int>(4 * kRate), settle = static_cast<int>(kRate);
  ImuTruthInput truth;
  truth.flap_freq_left_radps = 2 * M_PI * left_hz;
  truth.flap_freq_right_radps = 2 * M_PI * right_hz;
  for (int k = 0; k < n; ++k) {
    truth.utime = static_cast<std::int64_t>(std::llround(k * 1e6 / kRate));
    const ImuSample raw = imu.sample(truth);
    const ImuSample f = filter.filter(raw, raw.utime);
    if (k < settle) continue;
    r.filtered += (f.gyro_radps - imu.gyro_bias_radps()).array().square().matrix();
    r.raw += imu.last_gyro_vibration_radps().array().square().matrix();
    r.accel_filtered +=
        (f.accel_mps2 - imu.accel_bias_mps2() - truth.specific_force_body_mps2).array().square().matrix();
    r.accel_raw += imu.last_accel_vibration_mps2().array().square().matrix();
  }
  const double m = n - settle;
  r.filtered = (r.filtered / m).cwiseSqrt();
  r.raw = (r.raw / m).cwiseSqrt();
  r.accel_filtered = (r.accel_filtered / m).cwiseSqrt();
  r.accel_raw = (r.accel_raw / m).cwiseSqrt();
  return r;
}

/// The flight-vibration file, which stands on default_sensing.yaml, whose keys are the struct
/// defaults: only its own keys are read.
SensingConfig flight_vibration() {
  const std::string file = std::string(RIG_SOURCE_DIR) + "/rig_configs/sensing/nimble_flight_vibration.yaml";
  YAML::Node node = YAML::LoadFile(file);
  REQUIRE(node["base"].as<std::string>() == "default_sensing.yaml");
  node.remove("base");
  ConfigMap map(node, file, "");
  return sensing_config_from(map);
}

}  // namespace

TEST_CASE("the prefilter removes the flight vibration's lines at the measured flapping frequencies", "[prefilter]") {
  const SensingConfig sensing = flight_vibration();
  REQUIRE(sensing.imu_prefilter.enabled);
  for (const auto& [left, right] : {std::pair{17.0, 17.0}, std::pair{19.0, 15.0}}) {
    CAPTURE(left, right);
    const Residual r = at_rest(sensing, sensing.imu_prefilter, left, right);
    for (int i = 0; i < 3; ++i) {
      CAPTURE(i, r.raw[i], r.filtered[i], r.accel_raw[i], r.accel_filtered[i]);
      CHECK(r.raw[i] > 1.0);  // the file's vibration: 1.6-3.5 rad/s
      CHECK(r.filtered[i] < 0.01 * r.raw[i]);
      CHECK(r.accel_filtered[i] < 0.01 * r.accel_raw[i]);
    }
  }
  // Told the wrong frequencies (3 Hz off), the lines stay: the notches are where the feedback says.
  ImuPrefilterConfig pf = sensing.imu_prefilter;
  ImuModel imu(sensing.imu, 3);
  ImuPrefilter filter(pf, kRate);
  filter.set_flap_frequencies(2 * M_PI * 20.0, 2 * M_PI * 20.0, 0);
  ImuTruthInput truth;
  truth.flap_freq_left_radps = truth.flap_freq_right_radps = 2 * M_PI * 17.0;
  double sum = 0.0;
  for (int k = 0; k < 2048; ++k) {
    truth.utime = static_cast<std::int64_t>(std::llround(k * 1e6 / kRate));
    const ImuSample f = filter.filter(imu.sample(truth), truth.utime);
    if (k >= 512) sum += std::pow(f.gyro_radps.x() - imu.gyro_bias_radps().x(), 2);
  }
  CHECK(std::sqrt(sum / 1536) > 1.0);
}

TEST_CASE("the prefilter passes the motion without lag", "[prefilter]") {
  // A roll doublet-like rate, 5 rad/s at 2 Hz from 0.5 s (after the filter's start), no
  // vibration: the attitude integrated from the filtered rate against the one integrated from the
  // true rate. A notch of the same widths delays the slow part by about 10 ms: 3° here.
  ImuPrefilterConfig pf = flight_vibration().imu_prefilter;
  const auto worst_attitude_error = [&](double smoothing_s) {
    pf.amplitude_smoothing_s = smoothing_s;
    ImuPrefilter filter(pf, kRate);
    filter.set_flap_frequencies(2 * M_PI * 17.0, 2 * M_PI * 15.0, 0);
    double phi_true = 0.0, phi_filtered = 0.0, worst = 0.0;
    for (int k = 0; k < 4 * 512; ++k) {
      const double t = k / kRate;
      ImuSample s;
      s.utime = static_cast<std::int64_t>(std::llround(t * 1e6));
      s.gyro_radps.x() = t < 0.5 ? 0.0 : 5.0 * std::sin(2 * M_PI * 2.0 * (t - 0.5)) * std::min(1.0, t - 0.5);
      s.accel_mps2 = Eigen::Vector3d(0, 0, -9.81);
      const ImuSample f = filter.filter(s, s.utime);
      phi_true += s.gyro_radps.x() / kRate;
      phi_filtered += f.gyro_radps.x() / kRate;
      if (t > 0.5) worst = std::max(worst, std::fabs(phi_filtered - phi_true));
      CHECK(f.accel_mps2.z() == Approx(-9.81).margin(1e-6));  // gravity passes
    }
    return worst * 180.0 / M_PI;
  };
  const double smoothed = worst_attitude_error(pf.amplitude_smoothing_s), raw = worst_attitude_error(0.0);
  CAPTURE(smoothed, raw);
  CHECK(smoothed < 0.25);  // degrees: 0.15 (0.6 % of the 23° swing), against 1.06 unsmoothed
  CHECK(raw > smoothed);
}

TEST_CASE("the prefilter switched off is the identity", "[prefilter]") {
  ImuPrefilter filter(ImuPrefilterConfig{}, kRate);
  ImuSample s;
  s.gyro_radps = Eigen::Vector3d(1, 2, 3);
  s.accel_mps2 = Eigen::Vector3d(4, 5, 6);
  s.saturation_flags = 3;
  const ImuSample f = filter.filter(s, 0);
  CHECK(f.gyro_radps == s.gyro_radps);
  CHECK(f.accel_mps2 == s.accel_mps2);
  CHECK(f.saturation_flags == 3);
}

TEST_CASE("the imu_prefilter section is checked key by key", "[prefilter]") {
  const auto load = [](const std::string& text) {
    ConfigMap m = ConfigMap::load_string(text, "test.yaml");
    return sensing_config_from(m);
  };
  CHECK(load("imu_prefilter: {enabled: true, flap_harmonics: 3}").imu_prefilter.flap_harmonics == 3);
  CHECK_THROWS_WITH(load("imu_prefilter: {flap_notch_bandwidth_hz: 0}"),
                    Catch::Matchers::Contains("imu_prefilter.flap_notch_bandwidth_hz"));
  CHECK_THROWS_WITH(load("imu_prefilter: {notch: 3}"), Catch::Matchers::Contains("imu_prefilter.notch"));
}

TEST_CASE("the prefilter reports what it may have left when the wing pairs part after flapping in step",
          "[prefilter]") {
  // Two seconds in step (17 Hz each: only the sum of their lines can be known), then the pairs
  // part to 19 and 15 Hz, as delta_f does at a manoeuvre's first doublet. Over 8 seeds (the
  // pairs' relative phase, which decides how much of each pair's power the sum shows): the
  // reported variance against the error's mean square over the first 0.2 s apart, on p.
  const SensingConfig sensing = flight_vibration();
  ImuModelConfig quiet = sensing.imu;
  quiet.gyro_noise_sigma_radps.setZero();
  quiet.accel_noise_sigma_mps2.setZero();
  double before = 0.0, after = 0.0, err_parting = 0.0, var_parting = 0.0, err_after = 0.0, raw_after = 0.0;
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    ImuModel imu(quiet, seed);
    ImuPrefilter filter(sensing.imu_prefilter, kRate);
    for (int k = 0; k < static_cast<int>(3.5 * kRate); ++k) {
      const double t = k / kRate;
      const bool parted = t >= 2.0;
      ImuTruthInput truth;
      truth.utime = static_cast<std::int64_t>(std::llround(t * 1e6));
      truth.flap_freq_left_radps = 2 * M_PI * (parted ? 19.0 : 17.0);
      truth.flap_freq_right_radps = 2 * M_PI * (parted ? 15.0 : 17.0);
      filter.set_flap_frequencies(truth.flap_freq_left_radps, truth.flap_freq_right_radps, truth.utime);
      const ImuSample f = filter.filter(imu.sample(truth), truth.utime);
      const double var = filter.residual_var()[0];
      const double err2 = std::pow(f.gyro_radps.x() - imu.gyro_bias_radps().x(), 2);
      if (t > 1.5 && !parted) before = std::max(before, var);
      if (parted && t < 2.2) {
        err_parting += err2;
        var_parting += var;
      }
      if (t > 3.0) {
        after = std::max(after, var);
        err_after += err2;
        raw_after += std::pow(imu.last_gyro_vibration_radps().x(), 2);
      }
    }
  }
  CAPTURE(before, after, err_parting, var_parting, std::sqrt(err_after / raw_after));
  CHECK(err_parting > 100.0 * err_after);  // the parting leaves an error the lines did not know
  CHECK(var_parting > err_parting / 3.0);  // and the report holds it, within a factor of 3
  CHECK(var_parting < 3.0 * err_parting);
  CHECK(before < 1e-3 * var_parting / (0.2 * kRate * 8));  // in step: nothing beyond the usual
  CHECK(after < 1e-3);                                     // (rad/s)^2: learnt
  CHECK(std::sqrt(err_after / raw_after) < 0.01);          // and removed
}
