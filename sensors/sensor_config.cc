#include "sensors/sensor_config.h"

#include <cmath>
#include <string>

#include "core/config_fields.h"

namespace nimble {

const ParamTable<ImuModelConfig>& imu_params() {
  using C = ImuModelConfig;
  const Range nn = Range::non_negative();
  const Range kMisalignment = Range::closed(-0.1, 0.1);  // about 5.7 deg: far beyond a mounting error
  static const ParamTable<C> table = {
      {"sample_rate_hz", &C::sample_rate_hz, Range{0.0, 1e5, true, false}, "Hz",
       "output rate; thesis Section 8.1: 512 Hz"},
      {"gyro_noise_sigma_radps", &C::gyro_noise_sigma_radps, nn, "rad/s",
       "white gyro noise, 1-sigma per sample; thesis Section 8.1: 0.05 deg/s"},
      {"accel_noise_sigma_mps2", &C::accel_noise_sigma_mps2, nn, "m/s^2",
       "white accelerometer noise, 1-sigma per sample; thesis Section 8.1: 0.05 g (x, y), 0.08 g (z)"},
      {"gyro_bias_initial_radps", &C::gyro_bias_initial_radps, Range::closed(-10.0, 10.0), "rad/s",
       "fixed part of the initial gyro bias (an injected bias)"},
      {"accel_bias_initial_mps2", &C::accel_bias_initial_mps2, Range::closed(-50.0, 50.0), "m/s^2",
       "fixed part of the initial accelerometer bias"},
      {"gyro_bias_turn_on_sigma_radps", &C::gyro_bias_turn_on_sigma_radps, nn, "rad/s",
       "1-sigma of the seeded turn-on gyro bias per axis; assumption: residual after start-up calibration, about 1 "
       "deg/s"},
      {"accel_bias_turn_on_sigma_mps2", &C::accel_bias_turn_on_sigma_mps2, nn, "m/s^2",
       "1-sigma of the seeded turn-on accelerometer bias per axis; assumption: about 0.02 g"},
      {"gyro_bias_rw_radps_per_sqrts", &C::gyro_bias_rw_radps_per_sqrts, nn, "rad/s/sqrt(s)",
       "gyro bias random walk; assumption (not published): 2e-4, about 0.1 deg/s per minute"},
      {"accel_bias_rw_mps2_per_sqrts", &C::accel_bias_rw_mps2_per_sqrts, nn, "m/s^2/sqrt(s)",
       "accelerometer bias random walk; assumption (not published): 2e-3"},
      {"gyro_range_radps", &C::gyro_range_radps, Range::positive(), "rad/s",
       "gyro full scale; MPU-6000 largest setting, 2000 deg/s"},
      {"accel_range_mps2", &C::accel_range_mps2, Range::positive(), "m/s^2",
       "accelerometer full scale; MPU-6000 largest setting, 16 g"},
      {"vibration_enabled", &C::vibration_enabled, Range::any(), "-",
       "switches all vibration (flapping harmonics, structural mode) on or off"},
      {"structural_mode_hz", &C::structural_mode_hz, Range{0.0, 1e4, true, false}, "Hz",
       "structural (fuselage) mode; thesis Section 8.3, Fig D.2: about 11 Hz"},
      {"structural_gyro_amplitude_radps", &C::structural_gyro_amplitude_radps, nn, "rad/s",
       "structural mode on the gyro axes; assumption: 0.3 rad/s on z only"},
      {"structural_accel_amplitude_mps2", &C::structural_accel_amplitude_mps2, nn, "m/s^2",
       "structural mode on the accelerometer axes; assumption: zero"},
      {"temperature_degc", &C::temperature_degc, Range::closed(-60.0, 150.0), "degC",
       "reported die temperature; assumption: constant 35 degC"},
      {"gyro_scale_factor", &C::gyro_scale_factor, Range::closed(-0.5, 0.5), "-",
       "gyro scale factor error per axis: the axis reads (1 + k) x its true rate; assumption: 0 (off), MPU-6000 "
       "datasheet +-3 %"},
      {"accel_scale_factor", &C::accel_scale_factor, Range::closed(-0.5, 0.5), "-",
       "accelerometer scale factor error per axis: (1 + k) x the true specific force; assumption: 0 (off), MPU-6000 "
       "datasheet +-3 %"},
      {"gyro_misalignment_rad.xy", &C::gyro_misalignment_xy_rad, kMisalignment, "rad",
       "gyro cross-axis misalignment: the true rate about y read on x; assumption: 0 (off), MPU-6000 cross-axis "
       "sensitivity +-2 %"},
      {"gyro_misalignment_rad.xz", &C::gyro_misalignment_xz_rad, kMisalignment, "rad",
       "the true rate about z read on x"},
      {"gyro_misalignment_rad.yx", &C::gyro_misalignment_yx_rad, kMisalignment, "rad",
       "the true rate about x read on y"},
      {"gyro_misalignment_rad.yz", &C::gyro_misalignment_yz_rad, kMisalignment, "rad",
       "the true rate about z read on y"},
      {"gyro_misalignment_rad.zx", &C::gyro_misalignment_zx_rad, kMisalignment, "rad",
       "the true rate about x read on z"},
      {"gyro_misalignment_rad.zy", &C::gyro_misalignment_zy_rad, kMisalignment, "rad",
       "the true rate about y read on z"},
      {"accel_misalignment_rad.xy", &C::accel_misalignment_xy_rad, kMisalignment, "rad",
       "accelerometer cross-axis misalignment: the true specific force along y read on x; assumption: 0 (off), "
       "MPU-6000 +-2 %"},
      {"accel_misalignment_rad.xz", &C::accel_misalignment_xz_rad, kMisalignment, "rad",
       "the true specific force along z read on x"},
      {"accel_misalignment_rad.yx", &C::accel_misalignment_yx_rad, kMisalignment, "rad",
       "the true specific force along x read on y"},
      {"accel_misalignment_rad.yz", &C::accel_misalignment_yz_rad, kMisalignment, "rad",
       "the true specific force along z read on y"},
      {"accel_misalignment_rad.zx", &C::accel_misalignment_zx_rad, kMisalignment, "rad",
       "the true specific force along x read on z"},
      {"accel_misalignment_rad.zy", &C::accel_misalignment_zy_rad, kMisalignment, "rad",
       "the true specific force along y read on z"},
      {"clock_offset_s", &C::clock_offset_s, Range::closed(-1.0, 1.0), "s",
       "the IMU clock minus the motion capture's at rig time 0: each IMU stamp is rig time + offset + drift x rig "
       "time; assumption: 0 (off), the thesis's records needed synchronising (Section 8.1)"},
      {"clock_drift_ppm", &C::clock_drift_ppm, Range::closed(-1000.0, 1000.0), "ppm",
       "the IMU clock's rate error against the motion capture's; assumption: 0 (off), a crystal: tens of ppm"},
  };
  return table;
}

const ParamTable<MocapConfig>& mocap_params() {
  using C = MocapConfig;
  const Range nn = Range::non_negative();
  static const ParamTable<C> table = {
      {"frame_rate_hz", &C::frame_rate_hz, Range{0.0, 1e5, true, false}, "Hz",
       "frame rate (1e6 / rate a whole number of us); thesis Section 8.1: 200 Hz"},
      {"first_frame_start_utime", &C::first_frame_start_utime, Range::closed(-9e15, 9e15), "us",
       "start of the exposure of frame 0, rig time"},
      {"exposure_us", &C::exposure_us, Range::closed(0.0, 1e5), "us",
       "exposure time, at most one frame period; assumption: 500 us"},
      {"latency_us", &C::latency_us, Range::closed(0.0, 1e6), "us",
       "latency from mid-exposure to publication; assumption: 5 ms"},
      {"latency_jitter_sigma_us", &C::latency_jitter_sigma_us, nn, "us",
       "1-sigma Gaussian jitter of the latency; 0: constant"},
      {"mean_position_error_m", &C::mean_position_error_m, Range::closed(0.0, 1.0), "m",
       "mean 3-D position error; paper Section II.B: 0.85 mm"},
      {"attitude_noise_sigma_rad", &C::attitude_noise_sigma_rad, Range{0.0, 0.5, false, true}, "rad",
       "attitude noise, 1-sigma about body x y z; square roots of thesis Eq 8.2 R"},
      {"dropout_burst_rate_hz", &C::dropout_burst_rate_hz, nn, "1/s",
       "occlusion bursts per second of tracked time; assumption: 0.2"},
      {"dropout_mean_duration_s", &C::dropout_mean_duration_s, nn, "s",
       "mean duration of an occlusion burst; assumption: 0.05 s"},
      {"rigid_body_id", &C::rigid_body_id, Range::closed(-2147483648.0, 2147483647.0), "-",
       "rigid-body identifier in every frame"},
      {"num_markers", &C::num_markers, Range::closed(0, 32767), "-", "markers of the rigid body; thesis Fig 3: four"},
  };
  return table;
}

ImuModelConfig imu_model_config_from(ConfigMap& map) {
  ImuModelConfig c;
  const Range nn = Range::non_negative();
  read_params(map, imu_params(), c);
  for (const char* group : {"gyro_misalignment_rad", "accel_misalignment_rad"}) {
    if (!map.has(group)) continue;
    ConfigMap m = map.get_map(group);
    read_params(m, imu_params(), c, group);
    m.finish();
  }
  if (map.has("flapping_harmonics")) {
    const YAML::Node list = map.get_node("flapping_harmonics");
    if (!list.IsSequence())
      map.fail("flapping_harmonics",
               "must be a list of mappings (harmonic, gyro_amplitude_radps, accel_amplitude_mps2)");
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
  map.finish();
  validate_section(map, c);
  return c;
}

MocapConfig mocap_config_from(ConfigMap& map) {
  MocapConfig c;
  read_params(map, mocap_params(), c);
  const double period = 1e6 / c.frame_rate_hz;
  if (std::fabs(period - std::round(period)) > 1e-6) {
    map.fail("frame_rate_hz", "must give a whole number of microseconds per frame (1e6 / frame_rate_hz)");
  }
  if (static_cast<double>(c.exposure_us) > std::round(period)) {
    map.fail("exposure_us", "must be at most one frame period (" + std::to_string(std::llround(period)) + " us)");
  }
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
