#include "sensors/sensor_config.h"

#include <cmath>
#include <string>

#include "core/config_fields.h"

namespace nimble {

ImuModelConfig imu_model_config_from(ConfigMap& map) {
  ImuModelConfig c;
  const Range nn = Range::non_negative();
  c.sample_rate_hz = map.get_double_or("sample_rate_hz", c.sample_rate_hz, Range{0.0, 1e5, true, false});
  c.gyro_noise_sigma_radps = get_vec3_or(map, "gyro_noise_sigma_radps", c.gyro_noise_sigma_radps, nn);
  c.accel_noise_sigma_mps2 = get_vec3_or(map, "accel_noise_sigma_mps2", c.accel_noise_sigma_mps2, nn);
  c.gyro_bias_initial_radps = get_vec3_or(map, "gyro_bias_initial_radps", c.gyro_bias_initial_radps, Range::closed(-10.0, 10.0));
  c.accel_bias_initial_mps2 = get_vec3_or(map, "accel_bias_initial_mps2", c.accel_bias_initial_mps2, Range::closed(-50.0, 50.0));
  c.gyro_bias_turn_on_sigma_radps = map.get_double_or("gyro_bias_turn_on_sigma_radps", c.gyro_bias_turn_on_sigma_radps, nn);
  c.accel_bias_turn_on_sigma_mps2 = map.get_double_or("accel_bias_turn_on_sigma_mps2", c.accel_bias_turn_on_sigma_mps2, nn);
  c.gyro_bias_rw_radps_per_sqrts = get_vec3_or(map, "gyro_bias_rw_radps_per_sqrts", c.gyro_bias_rw_radps_per_sqrts, nn);
  c.accel_bias_rw_mps2_per_sqrts = get_vec3_or(map, "accel_bias_rw_mps2_per_sqrts", c.accel_bias_rw_mps2_per_sqrts, nn);
  c.gyro_range_radps = map.get_double_or("gyro_range_radps", c.gyro_range_radps, Range::positive());
  c.accel_range_mps2 = map.get_double_or("accel_range_mps2", c.accel_range_mps2, Range::positive());
  c.vibration_enabled = get_bool_or(map, "vibration_enabled", c.vibration_enabled);
  if (map.has("flapping_harmonics")) {
    const YAML::Node list = map.get_node("flapping_harmonics");
    if (!list.IsSequence()) map.fail("flapping_harmonics", "must be a list of mappings (harmonic, gyro_amplitude_radps, accel_amplitude_mps2)");
    c.flapping_harmonics.clear();
    for (std::size_t i = 0; i < list.size(); ++i) {
      ConfigMap item(list[i], map.file(), map.key_path("flapping_harmonics") + "[" + std::to_string(i) + "]");
      VibrationHarmonic h;
      h.harmonic = static_cast<int>(item.get_int("harmonic", Range::closed(1, 100)));
      h.gyro_amplitude_radps = get_vec3_or(item, "gyro_amplitude_radps", h.gyro_amplitude_radps, nn);
      h.accel_amplitude_mps2 = get_vec3_or(item, "accel_amplitude_mps2", h.accel_amplitude_mps2, nn);
      item.finish();
      c.flapping_harmonics.push_back(h);
    }
  }
  c.structural_mode_hz = map.get_double_or("structural_mode_hz", c.structural_mode_hz, Range{0.0, 1e4, true, false});
  c.structural_gyro_amplitude_radps = get_vec3_or(map, "structural_gyro_amplitude_radps", c.structural_gyro_amplitude_radps, nn);
  c.structural_accel_amplitude_mps2 = get_vec3_or(map, "structural_accel_amplitude_mps2", c.structural_accel_amplitude_mps2, nn);
  c.temperature_degc = map.get_double_or("temperature_degc", c.temperature_degc, Range::closed(-60.0, 150.0));
  map.finish();
  validate_section(map, c);
  return c;
}

MocapConfig mocap_config_from(ConfigMap& map) {
  MocapConfig c;
  const Range nn = Range::non_negative();
  c.frame_rate_hz = map.get_double_or("frame_rate_hz", c.frame_rate_hz, Range{0.0, 1e5, true, false});
  const double period = 1e6 / c.frame_rate_hz;
  if (std::fabs(period - std::round(period)) > 1e-6) {
    map.fail("frame_rate_hz", "must give a whole number of microseconds per frame (1e6 / frame_rate_hz)");
  }
  c.first_frame_start_utime = get_int_or(map, "first_frame_start_utime", c.first_frame_start_utime, Range::closed(-9e15, 9e15));
  c.exposure_us = get_int_or(map, "exposure_us", c.exposure_us, Range::closed(0.0, std::round(period)));
  c.latency_us = get_int_or(map, "latency_us", c.latency_us, Range::closed(0.0, 1e6));
  c.latency_jitter_sigma_us = map.get_double_or("latency_jitter_sigma_us", c.latency_jitter_sigma_us, nn);
  c.mean_position_error_m = map.get_double_or("mean_position_error_m", c.mean_position_error_m, Range::closed(0.0, 1.0));
  c.attitude_noise_sigma_rad = get_vec3_or(map, "attitude_noise_sigma_rad", c.attitude_noise_sigma_rad, Range{0.0, 0.5, false, true});
  c.dropout_burst_rate_hz = map.get_double_or("dropout_burst_rate_hz", c.dropout_burst_rate_hz, nn);
  c.dropout_mean_duration_s = map.get_double_or("dropout_mean_duration_s", c.dropout_mean_duration_s, nn);
  c.rigid_body_id = static_cast<int>(get_int_or(map, "rigid_body_id", c.rigid_body_id, Range::closed(-2147483648.0, 2147483647.0)));
  c.num_markers = static_cast<int>(get_int_or(map, "num_markers", c.num_markers, Range::closed(0, 32767)));
  map.finish();
  validate_section(map, c);
  return c;
}

SensorConfig sensor_config_from(ConfigMap& map) {
  SensorConfig c;
  if (map.has("seed")) c.seed = static_cast<std::uint64_t>(map.get_int("seed", Range::closed(0, 9e15)));
  if (map.has("imu")) {
    ConfigMap m = map.get_map("imu");
    c.imu = imu_model_config_from(m);
  }
  if (map.has("mocap")) {
    ConfigMap m = map.get_map("mocap");
    c.mocap = mocap_config_from(m);
  }
  return c;
}

}  // namespace nimble
