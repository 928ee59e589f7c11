#pragma once
/// Emulated onboard IMU (MPU-6000 on the Lisa/MXS autopilot of the Delfly Nimble).
///
/// From the truth at the sampling instant (body rates, specific force, flapping frequencies) the
/// model produces one sample
///   gyro  = sat( (I + S_g + M_g) omega_body + b_gyro  + vibration_gyro  + n_gyro  )
///   accel = sat( (I + S_a + M_a) f_body     + b_accel + vibration_accel + n_accel )
/// stamped with the IMU's own clock (ImuClock: rig time + offset + drift x rig time), with
///  - S: the scale factor errors, diag(k_x, k_y, k_z): an axis reads (1 + k) times its true value;
///  - M: the cross-axis misalignment, zero diagonal, M(i, j) the fraction of the true value on
///    axis j that the reading of axis i picks up (a small angle [rad]; ImuModelConfig's keys
///    ..._misalignment_rad.ij);
///  - n: white Gaussian noise, independent per sample and axis, standard deviation per sample
///    (thesis Section 8.1: gyro 0.05 deg/s, accelerometer 0.05 g in x and y and 0.08 g in z; the
///    published "accuracy" figures are read as 1-sigma per sample at the 512 Hz output rate);
///  - b: bias = initial bias (fixed part + seeded random turn-on part) + random walk
///    b(t_k) = b(t_{k-1}) + sigma_rw * sqrt(t_k - t_{k-1}) * N(0, 1), per axis;
///  - vibration: sinusoids at multiples of the flapping frequency of each wing pair (half of each
///    harmonic's amplitude at the left, half at the right flapping frequency, so a frequency
///    difference shows up as a beat), plus a fixed-frequency structural mode (the yaw-rate peak
///    near 11 Hz that the thesis reports, Section 8.3 and Appendix D). Phases are seeded.
///  - sat: clamp to +-range per axis; a clamped axis sets its bit in saturation_flags.
/// The errors S and M act on the true motion; the vibration amplitudes are what the sensor reads.
/// Sensor axes coincide with body axes (x forward, y right wing, z down) up to M. Specific force is the
/// non-gravitational acceleration: about (0, 0, -9.81) m/s^2 at rest and level.
///
/// Deterministic for a given seed and call sequence (std::mt19937_64 and
/// std::normal_distribution of the one standard library the rig is built with).

#include <cstdint>
#include <random>
#include <vector>

#include <Eigen/Core>

#include "contract/default_rates.h"
#include "core/rig_values.h"

namespace nimble {

/// Standard gravity, the unit "g" of the sensor specifications [m/s^2].
constexpr double kStandardGravityMps2 = 9.80665;
/// One degree [rad].
constexpr double kDegToRad = 0.017453292519943295;

/// One harmonic of the flapping-induced vibration.
struct VibrationHarmonic {
  /// Multiple of the flapping frequency [-], >= 1.
  int harmonic = 1;
  /// Amplitude of the sinusoid on the gyro axes x y z [rad/s].
  Eigen::Vector3d gyro_amplitude_radps = Eigen::Vector3d::Zero();
  /// Amplitude of the sinusoid on the accelerometer axes x y z [m/s^2].
  Eigen::Vector3d accel_amplitude_mps2 = Eigen::Vector3d::Zero();
};

/// The IMU's clock against the rig's (the motion capture's): the stamp an IMU sample carries is
///   stamp = t + floor(offset_s 1e6 + drift_ppm 1e-6 t + kStampRoundingPhase)  [us],
/// t the rig time of the sample [us], so the drift accumulates from rig time 0. The identity when
/// both are zero. The clock's error is rounded to the microsecond with its boundaries at the
/// fraction 0.618 (kStampRoundingPhase = 2 - golden ratio), off every decimal fraction: with a slow
/// clock two rig times a microsecond apart share a stamp where the error crosses a boundary, and
/// at .5 (round to nearest) that is exactly where whole-millisecond sample times with a
/// whole-ppm drift sit (-500 ppm: every other millisecond).
constexpr double kStampRoundingPhase = 0.3819660112501051;
struct ImuClock {
  double offset_s = 0.0;   ///< the IMU clock minus the rig clock at rig time 0 [s]
  double drift_ppm = 0.0;  ///< the IMU clock's rate error [1e-6 s/s]
  bool identity() const { return offset_s == 0.0 && drift_ppm == 0.0; }
  /// The stamp of a sample taken at rig time `rig_utime` [us].
  std::int64_t stamp(std::int64_t rig_utime) const;
  /// The rig time [us] of a sample stamped `stamp_utime`: the inverse of stamp() on the stamps it
  /// gives (the nearest rig time for any other). A slow clock (drift < 0) gives two rig times a
  /// microsecond apart the same stamp once in 1e6 / |drift_ppm| us: the earlier is returned (a
  /// sample is read back 1 us early only if it is the later of such a pair, about one in
  /// 1e6 / |drift_ppm|). Rig machinery that must keep to
  /// the rig's clock (lockstep bookkeeping, the time an estimate refers to) reads IMU stamps
  /// through it; the estimator's filter works on the stamps as they come.
  std::int64_t rig_utime(std::int64_t stamp_utime) const;
};

/// The default flapping harmonics (see ImuModelConfig::flapping_harmonics).
std::vector<VibrationHarmonic> default_flapping_harmonics();

/// Parameters of ImuModel. Defaults: thesis Section 8.1 where published, otherwise stated assumptions.
struct ImuModelConfig {
  /// Output rate [Hz]; thesis Section 8.1 (512 Hz). The model uses the actual sample times; this is
  /// the nominal rate for the process that calls it and for matched EKF noise.
  double sample_rate_hz = contract::kDefaultImuRateHz;
  /// White gyro noise, 1-sigma per sample, axes x y z [rad/s]; thesis Section 8.1: 0.05 deg/s.
  Eigen::Vector3d gyro_noise_sigma_radps = Eigen::Vector3d::Constant(0.05 * kDegToRad);
  /// White accelerometer noise, 1-sigma per sample [m/s^2]; thesis Section 8.1: 0.05 g (x, y), 0.08 g (z).
  Eigen::Vector3d accel_noise_sigma_mps2 = Eigen::Vector3d(0.05, 0.05, 0.08) * kStandardGravityMps2;
  /// Fixed part of the initial gyro bias [rad/s] (scenario value, e.g. an injected bias).
  Eigen::Vector3d gyro_bias_initial_radps = Eigen::Vector3d::Zero();
  /// Fixed part of the initial accelerometer bias [m/s^2].
  Eigen::Vector3d accel_bias_initial_mps2 = Eigen::Vector3d::Zero();
  /// 1-sigma of the seeded random turn-on gyro bias per axis [rad/s]. Assumption: residual after
  /// the autopilot's start-up gyro calibration, about 1 deg/s.
  double gyro_bias_turn_on_sigma_radps = 0.02;
  /// 1-sigma of the seeded random turn-on accelerometer bias per axis [m/s^2]. Assumption: about
  /// 0.02 g, well inside the MPU-6000 zero-g offset tolerance.
  double accel_bias_turn_on_sigma_mps2 = 0.2;
  /// Gyro bias random walk per axis [rad/s/sqrt(s)]. Assumption (not published): 2e-4, a drift of
  /// about 0.1 deg/s per minute, typical of consumer MEMS gyros.
  Eigen::Vector3d gyro_bias_rw_radps_per_sqrts = Eigen::Vector3d::Constant(2e-4);
  /// Accelerometer bias random walk per axis [m/s^2/sqrt(s)]. Assumption (not published): 2e-3.
  Eigen::Vector3d accel_bias_rw_mps2_per_sqrts = Eigen::Vector3d::Constant(2e-3);
  /// Gyro full-scale range [rad/s]; MPU-6000 largest setting, +-2000 deg/s.
  double gyro_range_radps = 2000.0 * kDegToRad;
  /// Accelerometer full-scale range [m/s^2]; MPU-6000 largest setting, +-16 g.
  double accel_range_mps2 = 16.0 * kStandardGravityMps2;
  /// Switches all vibration (flapping harmonics and structural mode) on or off.
  bool vibration_enabled = true;
  /// Vibration at multiples of the flapping frequency. The thesis publishes no amplitudes; the
  /// defaults are assumptions (see default_flapping_harmonics() and sensors/README.md): 1st
  /// harmonic gyro (0.2, 0.2, 0.1) rad/s, accel (0.5, 0.3, 1.0) m/s^2; 2nd harmonic gyro
  /// (0.1, 0.1, 0.05) rad/s, accel (1.0, 0.2, 0.5) m/s^2. They stay well below the effective
  /// input noise that the thesis's EKF tuning implies (Eq 8.2 Q: 1.6-3.5 rad/s, 5-7.5 m/s^2).
  std::vector<VibrationHarmonic> flapping_harmonics = default_flapping_harmonics();
  /// Frequency of the structural (fuselage) mode [Hz]; thesis Section 8.3 and Fig D.2: yaw-rate
  /// peak "consistently at around 11 Hz", independent of the manoeuvre.
  double structural_mode_hz = 11.0;
  /// Amplitude of the structural mode on the gyro axes [rad/s]. Assumption: 0.3 rad/s on z (yaw
  /// rate) only, which makes the 11 Hz peak the strongest high-frequency line of the yaw rate, as
  /// in the thesis's PSD; x and y zero.
  Eigen::Vector3d structural_gyro_amplitude_radps = Eigen::Vector3d(0.0, 0.0, 0.3);
  /// Amplitude of the structural mode on the accelerometer axes [m/s^2]. Assumption: zero.
  Eigen::Vector3d structural_accel_amplitude_mps2 = Eigen::Vector3d::Zero();
  /// Reported die temperature [degC]. Assumption: constant 35 degC.
  double temperature_degc = 35.0;
  /// Gyro scale factor error per axis [-]: the axis reads (1 + k) times its true rate.
  /// Assumption: 0 (off); MPU-6000 datasheet: +-3 % initial sensitivity tolerance.
  Eigen::Vector3d gyro_scale_factor = Eigen::Vector3d::Zero();
  /// Accelerometer scale factor error per axis [-]. Assumption: 0 (off); MPU-6000: +-3 %.
  Eigen::Vector3d accel_scale_factor = Eigen::Vector3d::Zero();
  /// Gyro cross-axis misalignment [rad]: misalignment_ij couples the true rate about axis j into
  /// the reading of axis i. Assumption: 0 (off); MPU-6000 datasheet: cross-axis sensitivity +-2 %.
  double gyro_misalignment_xy_rad = 0.0, gyro_misalignment_xz_rad = 0.0, gyro_misalignment_yx_rad = 0.0,
         gyro_misalignment_yz_rad = 0.0, gyro_misalignment_zx_rad = 0.0, gyro_misalignment_zy_rad = 0.0;
  /// Accelerometer cross-axis misalignment [rad], as the gyro's. Assumption: 0 (off); MPU-6000: +-2 %.
  double accel_misalignment_xy_rad = 0.0, accel_misalignment_xz_rad = 0.0, accel_misalignment_yx_rad = 0.0,
         accel_misalignment_yz_rad = 0.0, accel_misalignment_zx_rad = 0.0, accel_misalignment_zy_rad = 0.0;
  /// The IMU clock's offset against the motion capture's (the rig's) at rig time 0 [s].
  /// Assumption: 0 (off); the thesis's records needed synchronising (Section 8.1).
  double clock_offset_s = 0.0;
  /// The IMU clock's drift against the rig's [ppm]. Assumption: 0 (off); a crystal: tens of ppm.
  double clock_drift_ppm = 0.0;

  /// The clock of the stamps (clock_offset_s, clock_drift_ppm).
  ImuClock clock() const { return ImuClock{clock_offset_s, clock_drift_ppm}; }
  /// I + S + M of the gyro and of the accelerometer (sensor reading per unit of true value).
  Eigen::Matrix3d gyro_error_matrix() const;
  Eigen::Matrix3d accel_error_matrix() const;
};

/// Truth at one IMU sampling instant.
struct ImuTruthInput {
  /// Sampling instant, rig time [us] (the sample's stamp is ImuModelConfig::clock().stamp of it).
  std::int64_t utime = 0;
  /// Angular rate of the body relative to the world, body axes [rad/s], order p q r.
  Eigen::Vector3d omega_body_radps = Eigen::Vector3d::Zero();
  /// Specific force at the IMU, body axes [m/s^2]; about (0, 0, -9.81) at rest.
  Eigen::Vector3d specific_force_body_mps2 = Eigen::Vector3d(0.0, 0.0, -9.81);
  /// Flapping frequency of the left wing pair [rad/s].
  double flap_freq_left_radps = 0.0;
  /// Flapping frequency of the right wing pair [rad/s].
  double flap_freq_right_radps = 0.0;
};

/// Checks an ImuModelConfig.
/// @throws std::invalid_argument naming the field, its value and the allowed range.
void validate(const ImuModelConfig& config);

/// Transport-free IMU emulator: sample(truth) -> ImuSample. See the top of this header.
class ImuModel {
 public:
  /// @throws std::invalid_argument if `config` is invalid (see validate()).
  ImuModel(const ImuModelConfig& config, std::uint64_t seed);

  /// Produces the sample at truth.utime, stamped with the IMU's clock. Samples must come in increasing time; a non-increasing
  /// time is accepted (no bias random-walk step) and counted in non_increasing_time_count().
  /// Never throws.
  ImuSample sample(const ImuTruthInput& truth);

  /// Current gyro bias (the one in the last sample) [rad/s].
  const Eigen::Vector3d& gyro_bias_radps() const { return gyro_bias_radps_; }
  /// Current accelerometer bias [m/s^2].
  const Eigen::Vector3d& accel_bias_mps2() const { return accel_bias_mps2_; }
  /// Vibration added to the last sample: gyro [rad/s].
  const Eigen::Vector3d& last_gyro_vibration_radps() const { return last_gyro_vibration_radps_; }
  /// Vibration added to the last sample: accelerometer [m/s^2].
  const Eigen::Vector3d& last_accel_vibration_mps2() const { return last_accel_vibration_mps2_; }
  /// Samples with at least one saturated axis [-].
  std::int64_t saturated_sample_count() const { return saturated_samples_; }
  /// Samples whose time did not increase [-].
  std::int64_t non_increasing_time_count() const { return non_increasing_time_; }
  /// The configuration in use.
  const ImuModelConfig& config() const { return config_; }

 private:
  ImuModelConfig config_;
  ImuClock clock_;
  /// I + S + M, and whether they differ from I (else the true values pass untouched).
  Eigen::Matrix3d gyro_matrix_, accel_matrix_;
  bool gyro_errors_ = false, accel_errors_ = false;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  Eigen::Vector3d gyro_bias_radps_, accel_bias_mps2_;
  std::vector<Eigen::Vector3d> harmonic_gyro_phase_rad_, harmonic_accel_phase_rad_;
  Eigen::Vector3d structural_gyro_phase_rad_, structural_accel_phase_rad_;
  double flap_phase_left_rad_ = 0.0, flap_phase_right_rad_ = 0.0, structural_phase_rad_ = 0.0;
  Eigen::Vector3d last_gyro_vibration_radps_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d last_accel_vibration_mps2_ = Eigen::Vector3d::Zero();
  std::int64_t last_utime_ = 0;
  std::int64_t seq_ = 0;
  std::int64_t saturated_samples_ = 0;
  std::int64_t non_increasing_time_ = 0;
};

}  // namespace nimble
