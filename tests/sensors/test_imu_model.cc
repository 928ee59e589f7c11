// Unit tests of the emulated IMU (sensors/imu_model.h).

#include <cmath>
#include <complex>
#include <vector>

#include <catch2/catch.hpp>

#include "sensors/imu_model.h"

using namespace nimble;

namespace {

constexpr double kRateHz = 512.0;

std::int64_t sample_utime(int k) { return static_cast<std::int64_t>(std::llround(k * 1e6 / kRateHz)); }

ImuTruthInput at_rest(int k, double flap_radps = 2.0 * M_PI * 17.0) {
  ImuTruthInput t;
  t.utime = sample_utime(k);
  t.flap_freq_left_radps = flap_radps;
  t.flap_freq_right_radps = flap_radps;
  return t;
}

ImuModelConfig white_noise_only() {
  ImuModelConfig c;
  c.vibration_enabled = false;
  c.gyro_bias_turn_on_sigma_radps = 0.0;
  c.accel_bias_turn_on_sigma_mps2 = 0.0;
  c.gyro_bias_rw_radps_per_sqrts.setZero();
  c.accel_bias_rw_mps2_per_sqrts.setZero();
  return c;
}

/// Amplitude of the sinusoid at f_hz in x (sampled at kRateHz), 2 |X(f)| / N.
double dft_amplitude(const std::vector<double>& x, double f_hz) {
  std::complex<double> acc(0.0, 0.0);
  for (std::size_t n = 0; n < x.size(); ++n) {
    acc += x[n] * std::polar(1.0, -2.0 * M_PI * f_hz * static_cast<double>(n) / kRateHz);
  }
  return 2.0 * std::abs(acc) / static_cast<double>(x.size());
}

}  // namespace

TEST_CASE("IMU white noise: sample sigma per axis within 3 % of the config", "[imu]") {
  const ImuModelConfig c = white_noise_only();
  ImuModel imu(c, 5);
  const int n = 200000;
  Eigen::Vector3d sg = Eigen::Vector3d::Zero(), sa = Eigen::Vector3d::Zero(), mg = Eigen::Vector3d::Zero(),
                  ma = Eigen::Vector3d::Zero();
  for (int k = 0; k < n; ++k) {
    const ImuSample s = imu.sample(at_rest(k));
    const Eigen::Vector3d ea = s.accel_mps2 - Eigen::Vector3d(0, 0, -9.81);
    mg += s.gyro_radps;
    ma += ea;
    sg += s.gyro_radps.cwiseAbs2();
    sa += ea.cwiseAbs2();
  }
  mg /= n;
  ma /= n;
  const Eigen::Vector3d sigma_g = (sg / n - mg.cwiseAbs2()).cwiseSqrt();
  const Eigen::Vector3d sigma_a = (sa / n - ma.cwiseAbs2()).cwiseSqrt();
  for (int i = 0; i < 3; ++i) {
    INFO("axis " << i << ": gyro sigma " << sigma_g[i] << " rad/s, accel sigma " << sigma_a[i] << " m/s^2");
    CHECK(sigma_g[i] == Approx(c.gyro_noise_sigma_radps[i]).epsilon(0.03));
    CHECK(sigma_a[i] == Approx(c.accel_noise_sigma_mps2[i]).epsilon(0.03));
  }
  // Thesis Section 8.1 / paper Section II.B values: 0.05 deg/s, 0.05 g, 0.05 g, 0.08 g.
  CHECK(c.gyro_noise_sigma_radps[2] == Approx(0.05 * M_PI / 180.0));
  CHECK(c.accel_noise_sigma_mps2[2] == Approx(0.08 * 9.80665));
}

TEST_CASE("IMU bias random walk grows like sqrt(t)", "[imu]") {
  ImuModelConfig c = white_noise_only();
  c.gyro_noise_sigma_radps.setZero();
  c.accel_noise_sigma_mps2.setZero();
  c.gyro_bias_rw_radps_per_sqrts = Eigen::Vector3d(1e-3, 2e-3, 3e-3);
  c.accel_bias_rw_mps2_per_sqrts = Eigen::Vector3d::Constant(1e-2);
  const int models = 1000;
  const int k1 = 512, k2 = 4 * 512;  // 1 s and 4 s
  Eigen::Vector3d var_g1 = Eigen::Vector3d::Zero(), var_g2 = Eigen::Vector3d::Zero(), var_a2 = Eigen::Vector3d::Zero();
  for (int m = 0; m < models; ++m) {
    ImuModel imu(c, 1000 + m);
    for (int k = 0; k <= k2; ++k) {
      imu.sample(at_rest(k));
      if (k == k1) var_g1 += imu.gyro_bias_radps().cwiseAbs2();
    }
    var_g2 += imu.gyro_bias_radps().cwiseAbs2();
    var_a2 += imu.accel_bias_mps2().cwiseAbs2();
  }
  var_g1 /= models;
  var_g2 /= models;
  var_a2 /= models;
  const double t1 = sample_utime(k1) * 1e-6, t2 = sample_utime(k2) * 1e-6;
  for (int i = 0; i < 3; ++i) {
    const double q = c.gyro_bias_rw_radps_per_sqrts[i] * c.gyro_bias_rw_radps_per_sqrts[i];
    INFO("axis " << i << ": var(t1)/(q t1) " << var_g1[i] / (q * t1) << ", var(t2)/(q t2) " << var_g2[i] / (q * t2));
    // 1000 walks: relative standard error of a variance sqrt(2/1000) = 4.5 %; 15 % is 3.3 of them.
    CHECK(var_g1[i] / (q * t1) == Approx(1.0).epsilon(0.15));
    CHECK(var_g2[i] / (q * t2) == Approx(1.0).epsilon(0.15));
    CHECK(var_a2[i] / (1e-4 * t2) == Approx(1.0).epsilon(0.15));
  }
  // Standard deviation ratio between 4 s and 1 s: sqrt(4) = 2.
  CHECK(std::sqrt(var_g2.sum() / var_g1.sum()) == Approx(2.0).epsilon(0.1));
}

TEST_CASE("IMU saturation clamps to the range and sets the flags", "[imu]") {
  ImuModelConfig c = white_noise_only();
  c.gyro_noise_sigma_radps.setZero();
  c.accel_noise_sigma_mps2.setZero();
  ImuModel imu(c, 1);
  ImuTruthInput t = at_rest(0);
  const ImuSample calm = imu.sample(t);
  CHECK(calm.saturation_flags == 0);
  t = at_rest(1);
  t.omega_body_radps = Eigen::Vector3d(40.0, -40.0, 1.0);          // > 2000 deg/s = 34.9 rad/s on x and y
  t.specific_force_body_mps2 = Eigen::Vector3d(0.0, 0.0, -200.0);  // > 16 g on z
  const ImuSample s = imu.sample(t);
  CHECK(s.gyro_radps[0] == Approx(2000.0 * M_PI / 180.0));
  CHECK(s.gyro_radps[1] == Approx(-2000.0 * M_PI / 180.0));
  CHECK(s.gyro_radps[2] == Approx(1.0));
  CHECK(s.accel_mps2[2] == Approx(-16.0 * 9.80665));
  CHECK(s.saturation_flags == (kSatGyroX | kSatGyroY | kSatAccelZ));
  CHECK(imu.saturated_sample_count() == 1);
  // Bit values are those of imu_sample_t.
  CHECK(static_cast<int>(kSatGyroX) == 1);
  CHECK(static_cast<int>(kSatAccelZ) == 32);
}

TEST_CASE("IMU vibration: spectral lines at the flapping harmonics and at 11 Hz in yaw rate", "[imu]") {
  ImuModelConfig c;  // defaults: vibration on, noise on, biases on
  ImuModel imu(c, 9);
  const int n = 4096;  // 8 s: 0.125 Hz bins, 11, 17 and 34 Hz fall on bins
  std::vector<double> gx(n), gz(n), ax(n), az(n);
  for (int k = 0; k < n; ++k) {
    const ImuSample s = imu.sample(at_rest(k));
    gx[static_cast<std::size_t>(k)] = s.gyro_radps[0];
    gz[static_cast<std::size_t>(k)] = s.gyro_radps[2];
    ax[static_cast<std::size_t>(k)] = s.accel_mps2[0];
    az[static_cast<std::size_t>(k)] = s.accel_mps2[2];
  }
  struct Line {
    const std::vector<double>* x;
    double f_hz, amplitude;
    const char* what;
  };
  const Line lines[] = {
      {&gz, c.structural_mode_hz, c.structural_gyro_amplitude_radps[2], "yaw rate at the 11 Hz structural mode"},
      {&gx, 17.0, c.flapping_harmonics[0].gyro_amplitude_radps[0], "roll rate at the flapping frequency"},
      {&gx, 34.0, c.flapping_harmonics[1].gyro_amplitude_radps[0], "roll rate at twice the flapping frequency"},
      {&az, 17.0, c.flapping_harmonics[0].accel_amplitude_mps2[2], "a_z at the flapping frequency"},
      {&ax, 34.0, c.flapping_harmonics[1].accel_amplitude_mps2[0], "a_x at twice the flapping frequency"},
  };
  for (const Line& line : lines) {
    const double peak = dft_amplitude(*line.x, line.f_hz);
    double neighbours = 0.0;
    for (const double df : {-2.0, -1.0, -0.5, 0.5, 1.0, 2.0}) {
      neighbours = std::max(neighbours, dft_amplitude(*line.x, line.f_hz + df));
    }
    INFO(line.what << ": amplitude " << peak << ", largest neighbour " << neighbours);
    CHECK(peak == Approx(line.amplitude).epsilon(0.05));
    CHECK(peak > 10.0 * neighbours);
  }
  // Without vibration the 11 Hz line is gone.
  ImuModelConfig quiet = c;
  quiet.vibration_enabled = false;
  ImuModel imu_quiet(quiet, 9);
  std::vector<double> gz_quiet(n);
  for (int k = 0; k < n; ++k) gz_quiet[static_cast<std::size_t>(k)] = imu_quiet.sample(at_rest(k)).gyro_radps[2];
  CHECK(dft_amplitude(gz_quiet, 11.0) < 0.01 * c.structural_gyro_amplitude_radps[2]);
}

TEST_CASE("IMU vibration follows the flapping frequency of each wing pair", "[imu]") {
  ImuModelConfig c = white_noise_only();
  c.vibration_enabled = true;
  c.structural_gyro_amplitude_radps.setZero();
  ImuModel imu(c, 2);
  const int n = 4096;
  std::vector<double> gx(n);
  for (int k = 0; k < n; ++k) {
    ImuTruthInput t = at_rest(k);
    t.flap_freq_left_radps = 2.0 * M_PI * 16.0;
    t.flap_freq_right_radps = 2.0 * M_PI * 18.0;
    gx[static_cast<std::size_t>(k)] = imu.sample(t).gyro_radps[0];
  }
  const double a = c.flapping_harmonics[0].gyro_amplitude_radps[0];
  CHECK(dft_amplitude(gx, 16.0) == Approx(0.5 * a).epsilon(0.05));
  CHECK(dft_amplitude(gx, 18.0) == Approx(0.5 * a).epsilon(0.05));
  CHECK(dft_amplitude(gx, 17.0) < 0.05 * a);
}

TEST_CASE("IMU model is deterministic for a seed", "[imu]") {
  ImuModelConfig c;
  ImuModel a(c, 77), b(c, 77), other(c, 78);
  bool differs = false;
  for (int k = 0; k < 100; ++k) {
    const ImuSample sa = a.sample(at_rest(k)), sb = b.sample(at_rest(k)), so = other.sample(at_rest(k));
    REQUIRE(sa.gyro_radps == sb.gyro_radps);
    REQUIRE(sa.accel_mps2 == sb.accel_mps2);
    REQUIRE(sa.seq == k);
    differs = differs || sa.gyro_radps != so.gyro_radps;
  }
  CHECK(differs);
}

TEST_CASE("IMU config validation names the field", "[imu]") {
  ImuModelConfig c;
  c.gyro_noise_sigma_radps[1] = -1.0;
  CHECK_THROWS_WITH(ImuModel(c, 1), Catch::Contains("gyro_noise_sigma_radps[1]"));
  ImuModelConfig d;
  d.flapping_harmonics[0].harmonic = 0;
  CHECK_THROWS_WITH(ImuModel(d, 1), Catch::Contains("flapping_harmonics[0].harmonic"));
}
