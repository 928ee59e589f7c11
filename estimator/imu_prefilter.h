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
///    and/or the accelerometer.
///
/// How: a Kalman filter per group of channels with the same lines over the lines'
/// amplitudes and a level. Each line is a_i cos theta_i - b_i sin theta_i, theta_i the integral
/// of its measured frequency over the samples' own intervals (the rig's IMU samples at 512 Hz on
/// the plant's 1 kHz steps: 1 and 2 ms apart), so a line keeps its amplitude and phase however
/// fast its frequency moves (delta_f swings the wing pairs by +-10 Hz in the paper's manoeuvres);
/// the level (a random walk of bandwidth level_bandwidth_hz) takes what the motion is, so that
/// the amplitudes learn from what the motion leaves. The amplitudes are random walks whose steady
/// gain makes each line a notch of -3 dB width B (flap_notch_bandwidth_hz,
/// structural_notch_bandwidth_hz) and which fall back to their prior where nothing is learnt about
/// them. The output is the input minus the lines computed with the amplitudes low-passed over
/// amplitude_smoothing_s: what the motion shakes into an amplitude beats at about the line's
/// frequency and is smoothed away, so the motion passes without delay (at 0.5-5 Hz under 0.3 ms;
/// a plain notch of these widths delays the slow part by B / (2 pi f0^2), 10 ms over the chain,
/// 3° of attitude at 5 rad/s).
///
/// Why a filter over all lines at once, with a covariance: while the wing pairs flap in step
/// (delta_f = 0, every hover) only the sum of their two lines can be seen; when they part, the
/// split, which nothing has shown yet, shows at once. A covariance knows that: the filter learns
/// the split within a few periods of the lines' relative phase, and residual_var() reports the
/// uncertainty beforehand, for the EKF to widen its input noise by it (estimator/ekf.h predict()).
/// (A cascade of single notches, each adapted alone, took 0.3-0.5 s and left 0.6 rad/s on p over
/// the identification train.)
///
/// Start: the amplitudes start at zero with their prior; settled() after kStartS, when the
/// estimator starts its EKF. A line at or above 0.45 x the IMU's rate, or at zero, is left out.
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
  /// Lines at k x each wing pair's flapping frequency, k = 1..flap_harmonics (0: none).
  int flap_harmonics = 2;
  /// -3 dB width of each flapping line's notch [Hz].
  double flap_notch_bandwidth_hz = 4.0;
  /// Flapping frequency assumed before the first actuator feedback [Hz]; the thesis's 17 Hz.
  double initial_flap_freq_hz = 17.0;
  /// Fixed line [Hz] (0: none): the fuselage's yaw-rate line of thesis Section 8.3.
  double structural_notch_hz = 0.0;
  double structural_notch_bandwidth_hz = 3.0;
  /// The fixed line on each gyro channel: thesis Section 8.3 sees it in the yaw rate only (on p
  /// it would take out the roll motion near 11 Hz for nothing: Lp identified 2.5-3.5 % high).
  bool structural_notch_p = false, structural_notch_q = false, structural_notch_r = true;
  bool structural_notch_accel = false;  ///< the fixed line on the three accelerometer channels
  bool accel = true;                    ///< the flapping lines on the accelerometer too
  /// Bandwidth of the level that takes the motion [Hz]: above the manoeuvres' (to 7 Hz).
  double level_bandwidth_hz = 30.0;
  /// Time constant of the amplitudes' low-pass for the output [s]: longer than the beat of the
  /// motion with the lowest line (11 - 7 Hz), shorter than the lines' learning.
  double amplitude_smoothing_s = 0.02;
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

  const ImuPrefilterConfig& config() const { return config_; }
  /// True once the lines have been learnt over the start (kStartS of samples), or when off: the
  /// estimator starts its EKF on the filtered samples only from then on.
  bool settled() const {
    return !config_.enabled || (started_ && 1e-6 * static_cast<double>(last_utime_ - first_utime_) >= kStartS);
  }
  /// What the lines may still hold in the last sample beyond their usual uncertainty, per
  /// channel, as a per-sample variance [gyro p q r (rad/s)^2, accelerometer x y z (m/s^2)^2]:
  /// (S h)^T P (S h), S each amplitude element's prior standard deviation from the lines learnt,
  /// above its lower envelope. Large while the lines are learnt and when two wing pairs' lines
  /// part after flapping in step. The estimator gives it to the EKF as the sample's input noise
  /// where it exceeds the configured one.
  const Eigen::Matrix<double, 6, 1>& residual_var() const { return residual_var_; }

 private:
  /// One line: its frequency and reference (shared by the six channels).
  struct Line {
    double w = 0.0;                      ///< [rad/s]; 0: left out
    double theta = 0.0;                  ///< reference phase, wrapped into [0, 2 pi)
    std::complex<double> ref{1.0, 0.0};  ///< e^{j theta}
  };
  /// One measured pair of flapping frequencies.
  struct Feedback {
    std::int64_t utime;
    double left, right;  ///< [rad/s]
  };
  /// The lines a group of channels carries and the covariance of their amplitudes and level,
  /// shared by the group's channels (those with the same lines): it depends only on the
  /// references (in units of one amplitude element's prior).
  struct LineSet {
    std::vector<int> channels;   ///< 0-2 gyro p q r, 3-5 accelerometer x y z
    std::vector<int> lines;      ///< indices into lines_
    Eigen::MatrixXd P;           ///< (2n + 1)^2: [a_i b_i] per line, then the level
    Eigen::VectorXd alpha_rate;  ///< per element, per second: the random walks (amplitudes: per unit rho)
    double rho = kRhoMax;        ///< what else the channels carry against one element's prior
  };
  /// A wing pair's flapping frequency at `utime` [rad/s]: the newest measurement, carried on along
  /// the slope of the last two for at most two of their intervals (delta_f moves by up to
  /// 400 Hz/s in the manoeuvres; held, a 100 Hz feedback is 0.16 Hz off in RMS, carried on 0.05).
  double flap_radps(bool left, std::int64_t utime) const;
  /// Sets the lines' frequencies for rig time `utime` and moves their references on by `dt_s`.
  void advance_lines(std::int64_t utime, double dt_s);
  /// One step of `set` on its channels: the covariance, then each channel.
  void step_set(LineSet& set, const std::array<double, 6>& in, double dt_s, std::array<double, 6>* out);

  ImuPrefilterConfig config_;
  double fs_;
  Feedback feedback_[2];  ///< the last two measurements, oldest first
  /// k f_left, k f_right for k = 1..flap_harmonics, then the structural line.
  std::vector<Line> lines_;
  std::vector<LineSet> sets_;
  /// Per channel: its lines' amplitudes [a_i b_i] and level, and the amplitudes' low-pass.
  std::array<Eigen::VectorXd, 6> amp_, smooth_;
  Eigen::Matrix<double, 6, 1> residual_var_ = Eigen::Matrix<double, 6, 1>::Zero();
  /// rho, the ratio of what else a group's channels carry (the motion, the white noise) to one
  /// amplitude element's prior (the line power per element), sets how much of a surprise goes to
  /// a line whose amplitude is still unknown and scales the covariance into the predicted error.
  /// It is measured (the innovations' mean square over kNoiseTimeS against the line power) within
  /// [kRhoMin, kRhoMax]; it starts at kRhoMax, as noisy as the lines are strong, before the lines
  /// are known. The steady gains, and so the notches' widths, do not depend on it.
  static constexpr double kRhoMin = 1e-5, kRhoMax = 1.0;
  static constexpr double kNoiseTimeS = 0.5;
  /// How long a raised error variance takes to count as usual [s]: longer than the wing pairs' parting
  /// (the split is learnt within about 0.2 s).
  static constexpr double kUsualTimeS = 0.1;
  std::array<double, 6> innovation_ms_{};  ///< each channel's innovations' mean square
  std::array<double, 6> usual_{};          ///< each channel's lower envelope of its lines' error variance / rho
  /// The level's prior variance, in the same units: unknown (the accelerometer's gravity).
  static constexpr double kLevelPrior = 1e6;
  /// The start [s] before settled(): several periods of the lowest line (11 Hz).
  static constexpr double kStartS = 0.25;
  std::int64_t first_utime_ = 0, last_utime_ = 0;
  bool started_ = false;
};

}  // namespace nimble
