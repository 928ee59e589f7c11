#include "estimator/sensing_config.h"

#include <array>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace nimble {
namespace {

using Names = std::array<const char*, 3>;
constexpr Names kXyz = {"x", "y", "z"};
constexpr Names kEuler = {"phi", "theta", "psi"};
constexpr Names kUvw = {"u", "v", "w"};

Eigen::Vector3d vec3_or(ConfigMap& map, const std::string& key, const Eigen::Vector3d& fallback,
                        const Range& range, const Names& names = kXyz) {
  if (!map.has(key)) return fallback;
  ConfigMap sub = map.get_map(key);
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) v[i] = sub.get_double_or(names[static_cast<std::size_t>(i)], fallback[i], range);
  sub.finish();
  return v;
}

long long int_or(ConfigMap& map, const std::string& key, long long fallback, const Range& range) {
  if (!map.has(key)) return fallback;
  return map.get_int(key, range);
}

bool bool_or(ConfigMap& map, const std::string& key, bool fallback) {
  if (!map.has(key)) return fallback;
  return map.get_bool(key);
}

/// Runs a struct validator as a backstop and turns its message into a ConfigError of this section.
template <typename Config>
void check(const ConfigMap& map, const Config& config) {
  try {
    validate(config);
  } catch (const std::invalid_argument& e) {
    std::string section = map.key_path("");
    if (!section.empty() && section.back() == '.') section.pop_back();
    throw ConfigError(map.file(), section, "", e.what());
  }
}

}  // namespace

ImuModelConfig imu_model_config_from(ConfigMap& map) {
  ImuModelConfig c;
  const Range nn = Range::non_negative();
  c.sample_rate_hz = map.get_double_or("sample_rate_hz", c.sample_rate_hz, Range{0.0, 1e5, true, false});
  c.gyro_noise_sigma_radps = vec3_or(map, "gyro_noise_sigma_radps", c.gyro_noise_sigma_radps, nn);
  c.accel_noise_sigma_mps2 = vec3_or(map, "accel_noise_sigma_mps2", c.accel_noise_sigma_mps2, nn);
  c.gyro_bias_initial_radps = vec3_or(map, "gyro_bias_initial_radps", c.gyro_bias_initial_radps, Range::closed(-10.0, 10.0));
  c.accel_bias_initial_mps2 = vec3_or(map, "accel_bias_initial_mps2", c.accel_bias_initial_mps2, Range::closed(-50.0, 50.0));
  c.gyro_bias_turn_on_sigma_radps = map.get_double_or("gyro_bias_turn_on_sigma_radps", c.gyro_bias_turn_on_sigma_radps, nn);
  c.accel_bias_turn_on_sigma_mps2 = map.get_double_or("accel_bias_turn_on_sigma_mps2", c.accel_bias_turn_on_sigma_mps2, nn);
  c.gyro_bias_rw_radps_per_sqrts = vec3_or(map, "gyro_bias_rw_radps_per_sqrts", c.gyro_bias_rw_radps_per_sqrts, nn);
  c.accel_bias_rw_mps2_per_sqrts = vec3_or(map, "accel_bias_rw_mps2_per_sqrts", c.accel_bias_rw_mps2_per_sqrts, nn);
  c.gyro_range_radps = map.get_double_or("gyro_range_radps", c.gyro_range_radps, Range::positive());
  c.accel_range_mps2 = map.get_double_or("accel_range_mps2", c.accel_range_mps2, Range::positive());
  c.vibration_enabled = bool_or(map, "vibration_enabled", c.vibration_enabled);
  if (map.has("flapping_harmonics")) {
    const YAML::Node list = map.get_node("flapping_harmonics");
    if (!list.IsSequence()) map.fail("flapping_harmonics", "must be a list of mappings (harmonic, gyro_amplitude_radps, accel_amplitude_mps2)");
    c.flapping_harmonics.clear();
    for (std::size_t i = 0; i < list.size(); ++i) {
      ConfigMap item(list[i], map.file(), map.key_path("flapping_harmonics") + "[" + std::to_string(i) + "]");
      VibrationHarmonic h;
      h.harmonic = static_cast<int>(item.get_int("harmonic", Range::closed(1, 100)));
      h.gyro_amplitude_radps = vec3_or(item, "gyro_amplitude_radps", h.gyro_amplitude_radps, nn);
      h.accel_amplitude_mps2 = vec3_or(item, "accel_amplitude_mps2", h.accel_amplitude_mps2, nn);
      item.finish();
      c.flapping_harmonics.push_back(h);
    }
  }
  c.structural_mode_hz = map.get_double_or("structural_mode_hz", c.structural_mode_hz, Range{0.0, 1e4, true, false});
  c.structural_gyro_amplitude_radps = vec3_or(map, "structural_gyro_amplitude_radps", c.structural_gyro_amplitude_radps, nn);
  c.structural_accel_amplitude_mps2 = vec3_or(map, "structural_accel_amplitude_mps2", c.structural_accel_amplitude_mps2, nn);
  c.temperature_degc = map.get_double_or("temperature_degc", c.temperature_degc, Range::closed(-60.0, 150.0));
  map.finish();
  check(map, c);
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
  c.first_frame_start_utime = int_or(map, "first_frame_start_utime", c.first_frame_start_utime, Range::closed(-9e15, 9e15));
  c.exposure_us = int_or(map, "exposure_us", c.exposure_us, Range::closed(0.0, std::round(period)));
  c.latency_us = int_or(map, "latency_us", c.latency_us, Range::closed(0.0, 1e6));
  c.latency_jitter_sigma_us = map.get_double_or("latency_jitter_sigma_us", c.latency_jitter_sigma_us, nn);
  c.mean_position_error_m = map.get_double_or("mean_position_error_m", c.mean_position_error_m, Range::closed(0.0, 1.0));
  c.attitude_noise_sigma_rad = vec3_or(map, "attitude_noise_sigma_rad", c.attitude_noise_sigma_rad, Range{0.0, 0.5, false, true});
  c.dropout_burst_rate_hz = map.get_double_or("dropout_burst_rate_hz", c.dropout_burst_rate_hz, nn);
  c.dropout_mean_duration_s = map.get_double_or("dropout_mean_duration_s", c.dropout_mean_duration_s, nn);
  c.rigid_body_id = static_cast<int>(int_or(map, "rigid_body_id", c.rigid_body_id, Range::closed(-2147483648.0, 2147483647.0)));
  c.num_markers = static_cast<int>(int_or(map, "num_markers", c.num_markers, Range::closed(0, 32767)));
  map.finish();
  check(map, c);
  return c;
}

VelocityDifferentiatorConfig velocity_differentiator_config_from(ConfigMap& map) {
  VelocityDifferentiatorConfig c;
  c.span_frames = static_cast<int>(int_or(map, "span_frames", c.span_frames, Range::closed(2, 1000)));
  if (c.span_frames % 2 != 0) map.fail("span_frames", "must be even (the velocity refers to the middle frame)");
  c.stride_frames = static_cast<int>(int_or(map, "stride_frames", c.stride_frames, Range::closed(1, 1000)));
  if (c.span_frames % c.stride_frames == 0) {
    map.fail("stride_frames", "span_frames (" + std::to_string(c.span_frames) +
                                  ") must not be a multiple of stride_frames, otherwise successive velocity pairs "
                                  "share a frame and the velocity noise is not white");
  }
  map.finish();
  check(map, c);
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
    c.gyro_noise_var_per_sample_rad2ps2 = vec3_or(q, "gyro_var_per_sample_rad2ps2", c.gyro_noise_var_per_sample_rad2ps2, nn);
    c.accel_noise_var_per_sample_m2ps4 = vec3_or(q, "accel_var_per_sample_m2ps4", c.accel_noise_var_per_sample_m2ps4, nn);
    c.gyro_bias_rw_radps_per_sqrts = vec3_or(q, "gyro_bias_rw_radps_per_sqrts", c.gyro_bias_rw_radps_per_sqrts, nn);
    c.accel_bias_rw_mps2_per_sqrts = vec3_or(q, "accel_bias_rw_mps2_per_sqrts", c.accel_bias_rw_mps2_per_sqrts, nn);
    q.finish();
  }
  if (map.has("measurement_noise")) {
    ConfigMap r = map.get_map("measurement_noise");
    c.attitude_var_rad2 = vec3_or(r, "attitude_var_rad2", c.attitude_var_rad2, pos, kEuler);
    c.velocity_var_m2ps2 = vec3_or(r, "velocity_var_m2ps2", c.velocity_var_m2ps2, pos, kUvw);
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
    c.gate_enabled = bool_or(g, "enabled", c.gate_enabled);
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
  check(map, c);
  return c;
}

SensingConfig sensing_config_from(ConfigMap& map) {
  SensingConfig c;
  if (map.has("seed")) c.seed = static_cast<std::uint64_t>(map.get_int("seed", Range::closed(0, 9e15)));
  if (map.has("imu")) {
    ConfigMap m = map.get_map("imu");
    c.imu = imu_model_config_from(m);
  }
  if (map.has("mocap")) {
    ConfigMap m = map.get_map("mocap");
    c.mocap = mocap_config_from(m);
  }
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
