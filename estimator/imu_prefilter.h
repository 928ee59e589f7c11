#pragma once
/// ImuPrefilter: the on-board firmware's filtering of the IMU before the EKF, for a vehicle whose
/// IMU reads the flapping vibration (rig_configs/sensing/nimble_flight_vibration.yaml).
///
/// From each of the six channels (gyro p q r, accelerometer x y z) lines are removed:
///  - at k times each wing pair's flapping frequency, k = 1..flap_harmonics (two per harmonic,
///    one per wing pair: their frequencies differ by delta_f while the vehicle rolls), following
///    the measured flapping frequencies (the rig's ACTUATOR_FB, the way a multicopter firmware
///    moves its notches with the motors' measured speed);
///  - optionally at a fixed structural frequency (the thesis's 11 Hz yaw-rate line), on the gyro
///    and/or the accelerometer;
///  - then a lead gives the result unit gain and zero group delay at DC.
///
/// The lines are cancelled adaptively (Widrow's adaptive noise cancelling with sinusoidal
/// references): each line is Re(c e^{j theta}), theta the integral of its measured frequency over
/// the samples' own intervals, c its complex amplitude; the output e is the input minus every
/// line, and each c += (2 dt / T) e e^{-j theta}, all learnt from the same e (in a cascade of
/// single notches the two wing pairs' lines, within a notch width of each other while delta_f
/// swings, would keep moving each other's phase: 0.6 rad/s left on p of the identification train
/// against 0.04). For one fixed line this is exactly the notch (s^2 + w0^2) / (s^2 + (2/T) s +
/// w0^2): -3 dB width B = 1 / (pi T). Unlike a fixed
/// second-order section it keeps the line's amplitude and phase when the frequency moves (the
/// vibration's phase is the integral of a flapping frequency that delta_f swings by +-10 Hz in the
/// paper's manoeuvres), and it needs no even sampling (the rig's IMU samples at 512 Hz on the
/// plant's 1 kHz steps: 1 and 2 ms intervals). At start c is 0; the gain starts at 2 dt / t
/// (a running mean) and falls to 2 dt / T, so the lines are learnt within a few periods rather
/// than T's e-folds. They learn from what a stage leaves minus the channel's level (its running
/// mean over the start, kStartS, then held), so that gravity on the accelerometer is not taken
/// for a line while they are learnt.
///
/// Why the lead: a notch of width B at f0 delays the slow part of the signal by
/// tau = 2 pi B / w0^2 (2.2 ms for 4 Hz at 17 Hz); an attitude integrated from delayed rates lags
/// by that delay times the rate (1.3° at 10 rad/s), an error the motion capture then sees. The
/// lead y + tau (y[k] - y[k-1]) / dt, tau the sum over the chain, is exact for a ramp whatever the
/// intervals: the slow part passes with an error of second order in its frequency while each line
/// is removed. A notch at or above 0.45 x the IMU's rate, or at zero, is bypassed.
///
/// The sample's stamp, temperature and saturation flags pass unchanged.

#include <array>
#include <complex>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "core/param_table.h"
#include "core/rig_values.h"

namespace nimble {

/// Section `sensing.imu_prefilter`. Defaults: off (the emulated IMU's default vibration is small).
struct ImuPrefilterConfig {
  bool enabled = false;
  /// Notches at k x each wing pair's flapping frequency, k = 1..flap_harmonics (0: none).
  int flap_harmonics = 2;
  /// -3 dB width of each flapping-harmonic notch [Hz] (its time constant T = 1 / (pi B)).
  double flap_notch_bandwidth_hz = 4.0;
  /// Flapping frequency assumed before the first actuator feedback [Hz]; the thesis's 17 Hz.
  double initial_flap_freq_hz = 17.0;
  /// Fixed notch [Hz] (0: none): the fuselage's yaw-rate line of thesis Section 8.3.
  double structural_notch_hz = 0.0;
  double structural_notch_bandwidth_hz = 3.0;
  bool structural_notch_gyro = true;    ///< the fixed notch on the three gyro channels
  bool structural_notch_accel = false;  ///< the fixed notch on the three accelerometer channels
  bool accel = true;                    ///< the flapping notches on the accelerometer too
  bool lead_compensation = true;        ///< zero group delay at DC (see above)
};

/// The section's parameters: key, range, unit, meaning (`rig params sensing.imu_prefilter`).
const ParamTable<ImuPrefilterConfig>& imu_prefilter_params();

class ImuPrefilter {
 public:
  /// `sample_rate_hz`: the IMU's rate (sensing.imu.sample_rate_hz).
  /// @throws std::invalid_argument for values outside the table's ranges.
  ImuPrefilter(const ImuPrefilterConfig& config, double sample_rate_hz);

  /// The wing pairs' flapping frequencies [rad/s] measured at rig time `utime` [us] (ACTUATOR_FB),
  /// in increasing time. Non-finite values are ignored.
  void set_flap_frequencies(double left_radps, double right_radps, std::int64_t utime);

  /// The filtered sample, taken at rig time `rig_utime` [us] (the lines' frequencies are
  /// evaluated then; the intervals come from the samples' own stamps). Not enabled: `raw`.
  ImuSample filter(const ImuSample& raw, std::int64_t rig_utime);

  /// The gyro p chain's group delay at DC before the lead, at the last sample [s]: the sum of
  /// wB / w0^2 over its lines.
  double dc_group_delay_s() const { return dc_delay_s_; }
  const ImuPrefilterConfig& config() const { return config_; }
  /// What the lines left in the last sample, per channel [gyro p q r (rad/s)^2, accelerometer
  /// x y z (m/s^2)^2]: each line's remainder demodulated (the output times e^{-j theta},
  /// low-passed twice with kResidualTimeS) summed as a variance. Large while the lines are
  /// learnt (at the start; when the wing pairs' frequencies part, since while they are equal
  /// only the sum of their lines can be known). The estimator gives it to the EKF as the input
  /// noise of the sample where it exceeds the configured one.
  const Eigen::Matrix<double, 6, 1>& residual_var() const { return residual_var_; }
  /// True once the lines have been learnt over the start (kStartS of samples), or when off: the
  /// estimator starts its EKF on the filtered samples only from then on.
  bool settled() const { return !config_.enabled || (started_ && 1e-6 * static_cast<double>(last_utime_ - first_utime_) >= kStartS); }

 private:
  /// One line: its frequency and reference (shared by the six channels).
  struct Line {
    double w = 0.0;      ///< [rad/s]; 0: bypassed
    double theta = 0.0;  ///< reference phase, wrapped into [0, 2 pi)
    std::complex<double> ref{1.0, 0.0};  ///< e^{j theta}
  };
  /// One measured pair of flapping frequencies.
  struct Feedback {
    std::int64_t utime;
    double left, right;  ///< [rad/s]
  };
  /// A wing pair's flapping frequency at `utime` [rad/s]: the newest measurement, carried on along
  /// the slope of the last two for at most two of their intervals (delta_f moves by up to
  /// 400 Hz/s in the manoeuvres; held, a 100 Hz feedback is 0.16 Hz off in RMS, carried on 0.05).
  double flap_radps(bool left, std::int64_t utime) const;

  ImuPrefilterConfig config_;
  double fs_;
  double wb_flap_, wb_structural_;  ///< 2 pi x the widths [rad/s]
  Feedback feedback_[2];            ///< the last two measurements, oldest first
  /// k f_left, k f_right for k = 1..flap_harmonics, then the structural line.
  std::vector<Line> lines_;
  /// Per channel and line: the line's complex amplitude.
  std::array<std::vector<std::complex<double>>, 6> amp_;
  std::array<double, 6> last_out_{};  ///< the chain's previous output, for the lead
  std::array<double, 6> level_{};     ///< each channel's level m (see filter())
  double dc_delay_s_ = 0.0;           ///< the gyro p chain's delay at DC at the last sample [s]
  /// Per channel and line: the demodulated remainder through the first and second low-pass.
  std::array<std::vector<std::complex<double>>, 6> demod_;
  Eigen::Matrix<double, 6, 1> residual_var_ = Eigen::Matrix<double, 6, 1>::Zero();
  /// Time constant of the residual's demodulation low-passes [s]: a beat with the motion (at
  /// least 11 - 7 = 4 Hz away from a line) is damped by (1 + (2 pi 4 x 0.05)^2), 16 in power.
  static constexpr double kResidualTimeS = 0.05;
  /// The start [s] over which m is each channel's running mean (then held) and the gains fall from
  /// a running mean's: several periods of the lowest line (11 Hz; a running mean over t leaves
  /// another line Dw away at about 1 / (Dw t) of its amplitude: 10 % for 11 against 17 Hz).
  static constexpr double kStartS = 0.25;
  std::int64_t first_utime_ = 0, last_utime_ = 0;
  bool started_ = false;
};

}  // namespace nimble
