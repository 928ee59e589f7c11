#include "estimator/ekf.h"

// EkfConfig: the initial covariance, the parameter table the loader, validate() and `rig params`
// read, and validate() (the filter itself: ekf.cc).

#include <stdexcept>
#include <string>

namespace nimble {

EkfCovariance EkfConfig::initial_covariance() const {
  EkfState d;
  d << Eigen::Vector3d::Constant(initial_attitude_sigma_rad), Eigen::Vector3d::Constant(initial_velocity_sigma_mps),
      Eigen::Vector3d::Constant(initial_gyro_bias_sigma_radps),
      Eigen::Vector3d::Constant(initial_accel_bias_sigma_mps2);
  return d.array().square().matrix().asDiagonal();
}

const ParamTable<EkfConfig>& ekf_params() {
  using C = EkfConfig;
  const Range nn = Range::non_negative();
  const Range pos = Range::positive();
  static const AxisNames euler = {"phi", "theta", "psi"};
  static const AxisNames uvw = {"u", "v", "w"};
  static const ParamTable<C> table = {
      {"gravity_mps2", &C::gravity_mps2, Range::closed(9.0, 10.5), "m/s^2",
       "gravity; the value of the thesis's models (9.81)"},
      {"min_abs_cos_theta", &C::min_abs_cos_theta, Range{0.0, 0.5, true, false}, "-",
       "smallest |cos(theta)| in the Euler kinematics (pitch singularity guard)"},
      {"process_noise.reference_rate_hz", &C::process_noise_reference_rate_hz, pos, "Hz",
       "rate at which the *_var_per_sample values are per-sample variances; thesis: 512 Hz"},
      {"process_noise.gyro_var_per_sample_rad2ps2", &C::gyro_noise_var_per_sample_rad2ps2, nn, "(rad/s)^2",
       "gyro input noise per sample at the reference rate; thesis Eq 8.2 Q(1:3)"},
      {"process_noise.accel_var_per_sample_m2ps4", &C::accel_noise_var_per_sample_m2ps4, nn, "(m/s^2)^2",
       "accelerometer input noise per sample at the reference rate; thesis Eq 8.2 Q(4:6)"},
      {"process_noise.gyro_bias_rw_radps_per_sqrts", &C::gyro_bias_rw_radps_per_sqrts, nn, "rad/s/sqrt(s)",
       "gyro bias random walk; not in the thesis, the emulated IMU's"},
      {"process_noise.accel_bias_rw_mps2_per_sqrts", &C::accel_bias_rw_mps2_per_sqrts, nn, "m/s^2/sqrt(s)",
       "accelerometer bias random walk; the emulated IMU's"},
      {"measurement_noise.attitude_var_rad2", &C::attitude_var_rad2, pos, "rad^2",
       "variance of the measured phi, theta, psi; thesis Eq 8.2 R(1:3)", euler},
      {"measurement_noise.velocity_var_m2ps2", &C::velocity_var_m2ps2, pos, "(m/s)^2",
       "variance of the measured u, v, w; thesis Eq 8.2 R(4:6)", uvw},
      {"initial_sigma.attitude_rad", &C::initial_attitude_sigma_rad, pos, "rad",
       "initial 1-sigma of the attitude; assumption: 0.02"},
      {"initial_sigma.velocity_mps", &C::initial_velocity_sigma_mps, pos, "m/s",
       "initial 1-sigma of the body velocity; assumption: 0.1 (near hover)"},
      {"initial_sigma.gyro_bias_radps", &C::initial_gyro_bias_sigma_radps, pos, "rad/s",
       "initial 1-sigma of the gyro bias; the emulated IMU's turn-on sigma"},
      {"initial_sigma.accel_bias_mps2", &C::initial_accel_bias_sigma_mps2, pos, "m/s^2",
       "initial 1-sigma of the accelerometer bias; the emulated IMU's turn-on sigma"},
      {"gate.enabled", &C::gate_enabled, Range::any(), "-", "innovation gating on or off"},
      {"gate.probability", &C::gate_probability, Range{0.0, 1.0, true, true}, "-",
       "probability of the chi-square gate (0.999: a consistent measurement is rejected 1 in 1000)"},
      {"latency.history_s", &C::history_s, Range::closed(0.0, 10.0), "s",
       "length of the rollback history; older measurements are dropped and counted"},
      {"latency.replay_relinearise_attitude_rad", &C::replay_relinearise_attitude_rad, nn, "rad",
       "a replay reuses a step's linearisation while the attitude differs by at most this; 0: always "
       "linearise again (exact replay)"},
      {"latency.replay_relinearise_velocity_mps", &C::replay_relinearise_velocity_mps, nn, "m/s",
       "the same for the body velocity"},
      {"latency.replay_relinearise_gyro_bias_radps", &C::replay_relinearise_gyro_bias_radps, nn, "rad/s",
       "the same for the gyro bias"},
      {"integration.max_step_s", &C::max_step_s, Range{0.0, 0.1, true, false}, "s",
       "longest single integration step; longer IMU intervals are split"},
      {"integration.imu_gap_s", &C::imu_gap_s, pos, "s", "IMU interval above which a gap is counted"},
  };
  return table;
}

void validate(const EkfConfig& c) {
  // Each parameter's range: the loader's table.
  try {
    check_params(ekf_params(), c);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("EkfConfig.") + e.what());
  }
}

}  // namespace nimble
