#include "estimator/sensing_config.h"

#include <cmath>
#include <iomanip>
#include <sstream>

#include "core/config_fields.h"

namespace nimble {
namespace {

constexpr AxisNames kEuler = {"phi", "theta", "psi"};
constexpr AxisNames kUvw = {"u", "v", "w"};

}  // namespace

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
  const Range nn = Range::non_negative();
  const Range pos = Range::positive();
  c.gravity_mps2 = map.get_double_or("gravity_mps2", c.gravity_mps2, Range::closed(9.0, 10.5));
  c.min_abs_cos_theta = map.get_double_or("min_abs_cos_theta", c.min_abs_cos_theta, Range{0.0, 0.5, true, false});
  if (map.has("process_noise")) {
    ConfigMap q = map.get_map("process_noise");
    c.process_noise_reference_rate_hz = q.get_double_or("reference_rate_hz", c.process_noise_reference_rate_hz, pos);
    c.gyro_noise_var_per_sample_rad2ps2 = get_vec3_or(q, "gyro_var_per_sample_rad2ps2", c.gyro_noise_var_per_sample_rad2ps2, nn);
    c.accel_noise_var_per_sample_m2ps4 = get_vec3_or(q, "accel_var_per_sample_m2ps4", c.accel_noise_var_per_sample_m2ps4, nn);
    c.gyro_bias_rw_radps_per_sqrts = get_vec3_or(q, "gyro_bias_rw_radps_per_sqrts", c.gyro_bias_rw_radps_per_sqrts, nn);
    c.accel_bias_rw_mps2_per_sqrts = get_vec3_or(q, "accel_bias_rw_mps2_per_sqrts", c.accel_bias_rw_mps2_per_sqrts, nn);
    q.finish();
  }
  if (map.has("measurement_noise")) {
    ConfigMap r = map.get_map("measurement_noise");
    c.attitude_var_rad2 = get_vec3_or(r, "attitude_var_rad2", c.attitude_var_rad2, pos, kEuler);
    c.velocity_var_m2ps2 = get_vec3_or(r, "velocity_var_m2ps2", c.velocity_var_m2ps2, pos, kUvw);
    r.finish();
  }
  if (map.has("initial_sigma")) {
    ConfigMap s = map.get_map("initial_sigma");
    c.initial_attitude_sigma_rad = s.get_double_or("attitude_rad", c.initial_attitude_sigma_rad, pos);
    c.initial_velocity_sigma_mps = s.get_double_or("velocity_mps", c.initial_velocity_sigma_mps, pos);
    c.initial_gyro_bias_sigma_radps = s.get_double_or("gyro_bias_radps", c.initial_gyro_bias_sigma_radps, pos);
    c.initial_accel_bias_sigma_mps2 = s.get_double_or("accel_bias_mps2", c.initial_accel_bias_sigma_mps2, pos);
    s.finish();
  }
  if (map.has("gate")) {
    ConfigMap g = map.get_map("gate");
    c.gate_enabled = get_bool_or(g, "enabled", c.gate_enabled);
    c.gate_probability = g.get_double_or("probability", c.gate_probability, Range{0.0, 1.0, true, true});
    g.finish();
  }
  if (map.has("velocity_measurement")) {
    c.velocity_measurement = map.get_enum("velocity_measurement", {"window_mean", "instant"}) == "instant"
                                 ? EkfVelocityMeasurement::kInstant
                                 : EkfVelocityMeasurement::kWindowMean;
  }
  if (map.has("latency")) {
    ConfigMap l = map.get_map("latency");
    if (l.has("mode")) {
      c.latency_mode = l.get_enum("mode", {"rollback", "naive"}) == "naive" ? EkfLatencyMode::kNaive
                                                                             : EkfLatencyMode::kRollback;
    }
    c.history_s = l.get_double_or("history_s", c.history_s, Range::closed(0.0, 10.0));
    l.finish();
  }
  if (map.has("integration")) {
    ConfigMap i = map.get_map("integration");
    c.max_step_s = i.get_double_or("max_step_s", c.max_step_s, Range{0.0, 0.1, true, false});
    c.imu_gap_s = i.get_double_or("imu_gap_s", c.imu_gap_s, pos);
    i.finish();
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
  map.finish();
  const EkfHistoryNeed need = ekf_history_need(c);
  const double needed_s = need.total_s();
  if (c.ekf.latency_mode == EkfLatencyMode::kRollback && c.ekf.history_s < needed_s) {
    const bool window = c.ekf.velocity_measurement == EkfVelocityMeasurement::kWindowMean;
    std::ostringstream why;
    why << std::setprecision(3) << "is too short for the motion-capture measurements, which would arrive older than the "
        << "history and be dropped: latency " << 1e3 * need.latency_s << " ms + 3 x jitter " << 1e3 * need.jitter_s
        << " ms + " << (window ? "" : "half ") << "the differentiator span (" << c.velocity_differentiator.span_frames
        << " frames at " << c.mocap.frame_rate_hz << " Hz" << (window ? ", velocity_measurement window_mean" : "")
        << ") " << 1e3 * need.window_s << " ms + 2 IMU periods " << 1e3 * need.imu_s << " ms = " << 1e3 * needed_s
        << " ms; set ekf.latency.history_s >= " << std::ceil(needed_s * 1e3) / 1e3;
    std::ostringstream value;
    value << c.ekf.history_s;
    throw ConfigError(map.file(), map.key_path("ekf.latency.history_s"), value.str(), why.str());
  }
  return c;
}

EkfHistoryNeed ekf_history_need(const SensingConfig& config) {
  const double span_s = config.velocity_differentiator.span_frames / config.mocap.frame_rate_hz;
  EkfHistoryNeed need;
  need.latency_s = 1e-6 * static_cast<double>(config.mocap.latency_us);
  need.jitter_s = 3e-6 * config.mocap.latency_jitter_sigma_us;
  need.window_s = config.ekf.velocity_measurement == EkfVelocityMeasurement::kWindowMean ? span_s : 0.5 * span_s;
  need.imu_s = 2.0 / config.imu.sample_rate_hz;
  return need;
}

double ekf_history_needed_s(const SensingConfig& config) { return ekf_history_need(config).total_s(); }

SensingConfig load_sensing_config(const std::string& file) {
  ConfigMap root = ConfigMap::load_file(file);
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

}  // namespace nimble
