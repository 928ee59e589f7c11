// Unit tests of the truth side's sensing loader (sensors/sensor_config.h). The whole section,
// with the estimator's keys and the strict check, is tested in tests/estimator/test_sensing_config.cc.

#include <string>

#include <catch2/catch.hpp>

#include "sensors/sensor_config.h"

using namespace nimble;

TEST_CASE("sensor config: seed, imu and mocap read, the estimator's sections left to it", "[sensor_config]") {
  ConfigMap map = ConfigMap::load_string(R"(
seed: 7
imu: {sample_rate_hz: 256, vibration_enabled: false}
mocap: {latency_us: 8000}
velocity_differentiator: {span_frames: 4, stride_frames: 3}
ekf: {gate: {enabled: false}}
)",
                                         "inline.yaml");
  const SensorConfig c = sensor_config_from(map);
  CHECK(c.seed == 7);
  CHECK(c.imu.sample_rate_hz == 256.0);
  CHECK_FALSE(c.imu.vibration_enabled);
  CHECK(c.mocap.latency_us == 8000);
  CHECK(c.mocap.frame_rate_hz == MocapConfig().frame_rate_hz);

  ConfigMap empty = ConfigMap::load_string("{}", "inline.yaml");
  const SensorConfig d = sensor_config_from(empty);
  CHECK(d.seed == 1);
  CHECK(d.imu.gyro_range_radps == ImuModelConfig().gyro_range_radps);
}

TEST_CASE("sensor config: errors in the sensor sections name file and key", "[sensor_config]") {
  ConfigMap map = ConfigMap::load_string("mocap: {num_markers: -1}", "inline.yaml");
  try {
    sensor_config_from(map);
    FAIL("expected a ConfigError");
  } catch (const ConfigError& e) {
    CHECK(e.file() == "inline.yaml");
    CHECK(e.key() == "mocap.num_markers");
  }
}
