// Unit tests of the IMU's own errors (sensors/imu_model.h): scale factor, cross-axis
// misalignment and the clock of its stamps, each exactly as documented; their keys in the `imu`
// section (sensors/sensor_config.h), refused out of range naming the key.

#include <cstdint>
#include <string>

#include <catch2/catch.hpp>

#include "sensors/imu_model.h"
#include "sensors/sensor_config.h"

using namespace nimble;

namespace {

/// An IMU that reads the truth through its error matrix only: no noise, bias or vibration.
ImuModelConfig exact() {
  ImuModelConfig c;
  c.vibration_enabled = false;
  c.gyro_noise_sigma_radps.setZero();
  c.accel_noise_sigma_mps2.setZero();
  c.gyro_bias_turn_on_sigma_radps = 0.0;
  c.accel_bias_turn_on_sigma_mps2 = 0.0;
  c.gyro_bias_rw_radps_per_sqrts.setZero();
  c.accel_bias_rw_mps2_per_sqrts.setZero();
  return c;
}

ImuTruthInput truth_at(std::int64_t utime) {
  ImuTruthInput t;
  t.utime = utime;
  t.omega_body_radps = Eigen::Vector3d(0.5, -0.2, 0.1);
  t.specific_force_body_mps2 = Eigen::Vector3d(1.0, -2.0, -9.81);
  return t;
}

}  // namespace

TEST_CASE("IMU errors: scale factor and misalignment give (I + S + M) truth exactly", "[imu_errors]") {
  ImuModelConfig c = exact();
  c.gyro_scale_factor = Eigen::Vector3d(0.10, -0.05, 0.02);
  c.accel_scale_factor = Eigen::Vector3d(-0.03, 0.04, 0.01);
  c.gyro_misalignment_xy_rad = 0.01;   // the true q read on p
  c.gyro_misalignment_zx_rad = -0.02;  // the true p read on r
  c.accel_misalignment_yz_rad = 0.005;
  ImuModel imu(c, 3);
  const ImuTruthInput t = truth_at(1000);
  const ImuSample s = imu.sample(t);
  const Eigen::Vector3d w = t.omega_body_radps, f = t.specific_force_body_mps2;
  CHECK(s.gyro_radps.x() == Approx(1.10 * w.x() + 0.01 * w.y()).epsilon(1e-14));
  CHECK(s.gyro_radps.y() == Approx(0.95 * w.y()).epsilon(1e-14));
  CHECK(s.gyro_radps.z() == Approx(1.02 * w.z() - 0.02 * w.x()).epsilon(1e-14));
  CHECK(s.accel_mps2.x() == Approx(0.97 * f.x()).epsilon(1e-14));
  CHECK(s.accel_mps2.y() == Approx(1.04 * f.y() + 0.005 * f.z()).epsilon(1e-14));
  CHECK(s.accel_mps2.z() == Approx(1.01 * f.z()).epsilon(1e-14));
  CHECK(s.utime == 1000);  // no clock error: the stamp is the rig time

  // Off, the truth passes bit for bit.
  ImuModel plain(exact(), 3);
  const ImuSample p = plain.sample(t);
  CHECK(p.gyro_radps == w);
  CHECK(p.accel_mps2 == f);
}

TEST_CASE("IMU errors: each stamp is rig time + offset + drift x rig time, and reads back", "[imu_errors]") {
  ImuModelConfig c = exact();
  c.clock_offset_s = -0.05;
  c.clock_drift_ppm = 200.0;
  ImuModel imu(c, 3);
  // rig time -> stamp: t - 50 ms + 200 ppm of t, to the microsecond.
  const std::int64_t expected[][2] = {{0, -50000}, {1953, -48047}, {10000000, 9952000}, {60000000, 59962000}};
  for (const auto& [t, stamp] : expected) {
    const ImuSample s = imu.sample(truth_at(t));
    CHECK(s.utime == stamp);
    CHECK(c.clock().rig_utime(s.utime) == t);
  }
  // The bias walk and the vibration keep to the rig time: with the clock's error alone the
  // readings are those of an IMU without it.
  ImuModelConfig noisy;
  ImuModelConfig shifted = noisy;
  shifted.clock_offset_s = 0.2;
  ImuModel a(noisy, 9), b(shifted, 9);
  for (int k = 0; k < 100; ++k) {
    const std::int64_t t = std::llround(k * 1e6 / 512.0);
    const ImuSample sa = a.sample(truth_at(t)), sb = b.sample(truth_at(t));
    REQUIRE(sb.utime == sa.utime + 200000);
    REQUIRE(sb.gyro_radps == sa.gyro_radps);
    REQUIRE(sb.accel_mps2 == sa.accel_mps2);
  }
  // The inverse holds on every stamp a fast clock gives; a slow one shares a stamp between two
  // rig times a microsecond apart now and then, and gives the earlier.
  const ImuClock fast{0.2, 1000.0}, slow{-0.2, -1000.0};
  int shared = 0;
  for (std::int64_t t = 0; t < 3000000; t += 977) {
    REQUIRE(fast.rig_utime(fast.stamp(t)) == t);
    const std::int64_t back = slow.rig_utime(slow.stamp(t));
    REQUIRE(slow.stamp(back) == slow.stamp(t));
    REQUIRE((back == t || (back == t - 1 && slow.stamp(t - 1) == slow.stamp(t))));
    shared += back != t;
  }
  CHECK(shared < 10);
  // Whole-millisecond sample times and a whole-ppm slow clock never share a stamp: each reads back.
  const ImuClock half{-0.05, -500.0};
  for (std::int64_t t = 0; t < 10000000; t += 1000) REQUIRE(half.rig_utime(half.stamp(t)) == t);
}

TEST_CASE("IMU errors: the keys of the imu section, each refused out of range by name", "[imu_errors]") {
  ConfigMap map = ConfigMap::load_string(R"(
gyro_scale_factor: {x: 0.1, y: 0.0, z: -0.05}
accel_scale_factor: {x: 0.0, y: 0.02, z: 0.0}
gyro_misalignment_rad: {xy: 0.01, zy: -0.02}
accel_misalignment_rad: {yx: 0.003}
clock_offset_s: -0.2
clock_drift_ppm: 50
)",
                                         "sensing.yaml");
  const ImuModelConfig c = imu_model_config_from(map);
  CHECK(c.gyro_scale_factor == Eigen::Vector3d(0.1, 0.0, -0.05));
  CHECK(c.accel_scale_factor.y() == 0.02);
  CHECK(c.gyro_misalignment_xy_rad == 0.01);
  CHECK(c.gyro_misalignment_zy_rad == -0.02);
  CHECK(c.gyro_misalignment_xz_rad == 0.0);
  CHECK(c.accel_misalignment_yx_rad == 0.003);
  CHECK(c.clock_offset_s == -0.2);
  CHECK(c.clock_drift_ppm == 50.0);

  const struct {
    const char* yaml;
    const char* key;
    const char* value;
  } bad[] = {
      {"gyro_scale_factor: {x: 0.7, y: 0, z: 0}", "gyro_scale_factor.x", "0.7"},
      {"accel_scale_factor: {x: 0, y: 0, z: -0.6}", "accel_scale_factor.z", "-0.6"},
      {"gyro_misalignment_rad: {yz: 0.2}", "gyro_misalignment_rad.yz", "0.2"},
      {"accel_misalignment_rad: {xx: 0.01}", "accel_misalignment_rad.xx", "0.01"},
      {"clock_offset_s: 1.5", "clock_offset_s", "1.5"},
      {"clock_drift_ppm: -2000", "clock_drift_ppm", "-2000"},
  };
  for (const auto& b : bad) {
    INFO(b.yaml);
    ConfigMap m = ConfigMap::load_string(b.yaml, "sensing.yaml");
    try {
      imu_model_config_from(m);
      FAIL("expected a ConfigError");
    } catch (const ConfigError& e) {
      CHECK(e.file() == "sensing.yaml");
      CHECK(std::string(e.what()).find(b.key) != std::string::npos);
      CHECK(std::string(e.what()).find(b.value) != std::string::npos);
    }
  }
  // Built in code, validate() names the field.
  ImuModelConfig wrong;
  wrong.clock_offset_s = 2.0;
  CHECK_THROWS_WITH(validate(wrong), Catch::Contains("clock_offset_s"));
}
