#include "estimator/sensing_config.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "core/config_fields.h"
#include "scenario/scenario.h"

namespace nimble {

VelocityDifferentiatorConfig velocity_differentiator_config_from(ConfigMap& map) {
  VelocityDifferentiatorConfig c;
  c.span_frames = static_cast<int>(get_int_or(map, "span_frames", c.span_frames, Range::closed(2, 1000)));
  if (c.span_frames % 2 != 0) map.fail("span_frames", "must be even (the velocity refers to the middle frame)");
  c.stride_frames = static_cast<int>(get_int_or(map, "stride_frames", c.stride_frames, Range::closed(1, 1000)));
  if (c.span_frames % c.stride_frames == 0) {
    map.fail("stride_frames", "span_frames (" + std::to_string(c.span_frames) +
                                  ") must not be a multiple of stride_frames, otherwise successive velocity pairs "
                                  "share a frame and the velocity noise is not white");
  }
  map.finish();
  validate_section(map, c);
  return c;
}

EkfConfig ekf_config_from(ConfigMap& map) {
  EkfConfig c;
  read_params(map, ekf_params(), c);
  for (const char* group : {"process_noise", "measurement_noise", "initial_sigma", "gate", "integration"}) {
    if (!map.has(group)) continue;
    ConfigMap m = map.get_map(group);
    read_params(m, ekf_params(), c, group);
    m.finish();
  }
  if (map.has("velocity_measurement")) {
    c.velocity_measurement = map.get_enum("velocity_measurement", {"window_mean", "instant"}) == "instant"
                                 ? EkfVelocityMeasurement::kInstant
                                 : EkfVelocityMeasurement::kWindowMean;
  }
  if (map.has("latency")) {
    ConfigMap l = map.get_map("latency");
    if (l.has("mode")) {
      c.latency_mode =
          l.get_enum("mode", {"rollback", "naive"}) == "naive" ? EkfLatencyMode::kNaive : EkfLatencyMode::kRollback;
    }
    read_params(l, ekf_params(), c, "latency");
    l.finish();
  }
  map.finish();
  validate_section(map, c);
  return c;
}

SensingConfig sensing_config_from(ConfigMap& map) {
  SensingConfig c;
  static_cast<SensorConfig&>(c) = sensor_config_from(map);
  if (map.has("velocity_differentiator")) {
    ConfigMap m = map.get_map("velocity_differentiator");
    c.velocity_differentiator = velocity_differentiator_config_from(m);
  }
  if (map.has("ekf")) {
    ConfigMap m = map.get_map("ekf");
    c.ekf = ekf_config_from(m);
  }
  if (map.has("imu_prefilter")) {
    ConfigMap m = map.get_map("imu_prefilter");
    read_params(m, imu_prefilter_params(), c.imu_prefilter);
    m.finish();
  }
  map.finish();
  check_ekf_history(map, c, 0.0);
  return c;
}

void check_ekf_history(ConfigMap& map, const SensingConfig& c, double duration_s) {
  const EkfHistoryNeed need = ekf_history_need(c, duration_s);
  const double needed_s = need.total_s();
  if (c.ekf.latency_mode != EkfLatencyMode::kRollback || c.ekf.history_s >= needed_s) return;
  const bool window = c.ekf.velocity_measurement == EkfVelocityMeasurement::kWindowMean;
  std::ostringstream why;
  why << std::setprecision(3) << "is too short for the motion-capture measurements, which would arrive older than the "
      << "history and be dropped: latency " << 1e3 * need.latency_s << " ms + 3 x jitter " << 1e3 * need.jitter_s
      << " ms + " << (window ? "" : "half ") << "the differentiator span (" << c.velocity_differentiator.span_frames
      << " frames at " << c.mocap.frame_rate_hz << " Hz" << (window ? ", velocity_measurement window_mean" : "") << ") "
      << 1e3 * need.window_s << " ms + 2 IMU periods " << 1e3 * need.imu_s << " ms";
  if (need.clock_s > 0.0) {
    why << " + the IMU clock against the motion capture's (imu.clock_offset_s " << c.imu.clock_offset_s
        << " s, clock_drift_ppm " << c.imu.clock_drift_ppm;
    if (duration_s > 0.0) why << " over " << duration_s << " s";
    why << ") " << 1e3 * need.clock_s << " ms";
  }
  why << " = " << 1e3 * needed_s << " ms; set ekf.latency.history_s >= " << std::ceil(needed_s * 1e3) / 1e3;
  std::ostringstream value;
  value << c.ekf.history_s;
  throw ConfigError(map.file(), map.key_path("ekf.latency.history_s"), value.str(), why.str());
}

EkfHistoryNeed ekf_history_need(const SensingConfig& config, double duration_s) {
  const double span_s = config.velocity_differentiator.span_frames / config.mocap.frame_rate_hz;
  EkfHistoryNeed need;
  need.latency_s = 1e-6 * static_cast<double>(config.mocap.latency_us);
  need.jitter_s = 3e-6 * config.mocap.latency_jitter_sigma_us;
  need.window_s = config.ekf.velocity_measurement == EkfVelocityMeasurement::kWindowMean ? span_s : 0.5 * span_s;
  need.imu_s = 2.0 / config.imu.sample_rate_hz;
  const double offset_s = config.imu.clock_offset_s;
  need.clock_s = std::max(std::fabs(offset_s), std::fabs(offset_s + 1e-6 * config.imu.clock_drift_ppm * duration_s));
  return need;
}

double ekf_history_needed_s(const SensingConfig& config) { return ekf_history_need(config).total_s(); }

SensingConfig load_sensing_config(const std::string& file) {
  // A scenario's merging of bases (scenario/scenario.h): a file that stands on another
  // (`base: default_sensing.yaml`) reads as the section it makes in a scenario.
  ConfigMap root(load_scenario_tree(file), file, "");
  return sensing_config_from(root);
}

EkfConfig ekf_config_matched_to_sensors(const EkfConfig& base, const ImuModelConfig& imu, const MocapConfig& mocap,
                                        const VelocityDifferentiatorConfig& differentiator,
                                        const MatchedNoiseOptions& options) {
  EkfConfig c = base;
  c.process_noise_reference_rate_hz = imu.sample_rate_hz;
  c.gyro_noise_var_per_sample_rad2ps2 = imu.gyro_noise_sigma_radps.array().square().matrix();
  c.accel_noise_var_per_sample_m2ps4 = imu.accel_noise_sigma_mps2.array().square().matrix();
  if (options.include_vibration && imu.vibration_enabled) {
    for (const VibrationHarmonic& h : imu.flapping_harmonics) {
      c.gyro_noise_var_per_sample_rad2ps2 += 0.5 * h.gyro_amplitude_radps.array().square().matrix();
      c.accel_noise_var_per_sample_m2ps4 += 0.5 * h.accel_amplitude_mps2.array().square().matrix();
    }
    c.gyro_noise_var_per_sample_rad2ps2 += 0.5 * imu.structural_gyro_amplitude_radps.array().square().matrix();
    c.accel_noise_var_per_sample_m2ps4 += 0.5 * imu.structural_accel_amplitude_mps2.array().square().matrix();
  }
  c.gyro_bias_rw_radps_per_sqrts = imu.gyro_bias_rw_radps_per_sqrts;
  c.accel_bias_rw_mps2_per_sqrts = imu.accel_bias_rw_mps2_per_sqrts;
  c.attitude_var_rad2 = mocap.attitude_noise_sigma_rad.array().square().matrix();
  const double span_s = differentiator.span_frames / mocap.frame_rate_hz;
  const double sigma_v = differentiated_velocity_sigma_mps(mocap.position_sigma_m(), span_s);
  const double rotation_var = options.rotation_speed_mps * options.rotation_speed_mps * c.attitude_var_rad2.mean();
  c.velocity_var_m2ps2 = Eigen::Vector3d::Constant(sigma_v * sigma_v + rotation_var);
  c.initial_gyro_bias_sigma_radps = std::max(imu.gyro_bias_turn_on_sigma_radps, 1e-6);
  c.initial_accel_bias_sigma_mps2 = std::max(imu.accel_bias_turn_on_sigma_mps2, 1e-6);
  return c;
}

EkfConfig smoother_ekf_config(const SensingConfig& sensing) {
  MatchedNoiseOptions options;
  options.include_vibration = true;
  return ekf_config_matched_to_sensors(sensing.ekf, sensing.imu, sensing.mocap, sensing.velocity_differentiator,
                                       options);
}

}  // namespace nimble
