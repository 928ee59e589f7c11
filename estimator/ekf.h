#pragma once
/// Attitude and body-velocity EKF fusing the IMU (input) with motion capture (measurement),
/// thesis Section 8.1, Eqs 8.1 and 8.2. Transport-free core: predict(imu) at the
/// IMU rate, add_measurement(pose) when a mocap measurement arrives.
///
/// Model: see ekf_model.h. State [phi theta psi u v w b_p b_q b_r b_ax b_ay b_az].
///
/// Prediction (per IMU sample, from the previous sample time to this one): Heun's method with the
/// input linear between the two samples (second order; the samples are instantaneous values), and
///   P+ = Phi (P + dt/2 Qc0) Phi^T + dt/2 Qc1,   Qc = G S G^T + diag(0, 0, q_bg, q_ba),
/// the trapezoidal rule for the integral of the continuous noise, with Phi the exact Jacobian of
/// the Heun step, G = df/du_m at the interval's start (0) and end (1), S the power spectral
/// density of the IMU input noise and q_bg, q_ba the bias random-walk intensities. Intervals longer
/// than max_step_s are split into substeps.
///
/// Process noise interpretation (thesis Eq 8.2 Q = diag(7.60, 2.60, 12.07, 26.99, 36.66, 56.12)):
/// the covariance of the process noise w = [w_p w_q w_r w_ax w_ay w_az] of Eq 8.1, i.e. of the
/// noise on the IMU input, read as per-sample variances at the 512 Hz rate of the fused data, in SI
/// units: (rad/s)^2 for the gyros, (m/s^2)^2 for the accelerometers (sigma 2.8, 1.6, 3.5 rad/s and
/// 5.2, 6.1, 7.5 m/s^2: the flapping vibration of the real flight data, not the MPU-6000 noise).
/// Per-sample variance sigma^2 at rate f_ref corresponds to the PSD S = sigma^2 / f_ref; the filter
/// uses S, so at 512 Hz the discrete noise equals the thesis's G Q G^T dt^2, and at another IMU rate
/// the same PSD (not the same per-sample variance) is kept.
/// Measurement noise (Eq 8.2 R = diag(0.125, 0.057, 0.037, 0.113, 0.216, 0.135) e-3): variances of
/// the mocap Euler angles [rad^2] and of the differentiated body velocities [(m/s)^2] per
/// measurement (sigma 0.64, 0.43, 0.35 deg and 0.011 to 0.015 m/s, the size of the residuals the
/// thesis reports). R is not rescaled with the rate: each frame is used once at its own time.
///
/// Differentiated velocity (velocity_measurement = kWindowMean): the mocap velocity
///   z_v = R(q_c)^T (r(t_e) - r(t_s)) / (t_e - t_s) = R(q_c)^T mean over [t_s, t_e] of v_ned,
/// the mean of the world velocity over the difference's window, seen in the body axes of the
/// middle frame. The filter applies it at t_c as a measurement of v_body(t_c) plus a known offset
///   c = R(x_c)^T mean_[t_s, t_e](R(x) v_body) - v_body(x_c),
/// computed once, when the measurement arrives, from the filter's own trajectory over the window
/// (the history nodes, trapezoidal rule, ends interpolated): its short-term shape comes from the
/// integrated accelerometer, which resolves what the 60 ms difference averages away. The
/// measurement waits until the IMU has reached t_e; if the history does not cover the window the
/// offset is taken as zero and counted (velocity_window_uncovered; windows that start before the
/// filter was initialised are not counted).
///
/// Gating: a measurement whose NIS = y^T S^-1 y exceeds the chi-square quantile of
/// gate_probability for its dimension (3 or 6) is rejected and counted. Angle innovations are
/// wrapped into (-pi, pi].
///
/// Latency: the filter keeps, for history_s, one node per IMU sample (time, input, state and
/// covariance after every measurement up to that time) and the accepted measurements. A measurement
/// stamped in the past is inserted at its own time: the filter restores the node before it,
/// predicts to the measurement time (input interpolated), updates, and re-predicts through the
/// stored IMU inputs (re-applying later stored measurements) up to the present. A measurement
/// older than the history is counted and dropped; one stamped ahead of the newest IMU sample (up to
/// history_s ahead) waits until the IMU catches up. add_measurements() takes the measurements of
/// one frame together: one re-propagation for those in the past, the same result bit for bit.
/// latency_mode naive applies every measurement to the current state regardless of its time
/// (for comparison only).
/// Optionally (latency.replay_relinearise_* > 0; default 0, the exact replay) a replay
/// re-propagates the state exactly (Heun's method through the stored inputs) but the covariance
/// with the linearisation (Phi and the input noise of the Heun step) the filter made when it last
/// propagated over the same interval, kept for each history node, while the state at the
/// interval's start lies within those tolerances of the state that linearisation was made at;
/// beyond, or for an interval split differently (a new measurement inside it), it linearises
/// again. The covariance is then that of the exact replay to first order in the correction the
/// replay applies (see EkfConfig), and a replayed step costs two evaluations of f and the
/// covariance products instead of the linearisation.
/// Without measurements (dropout) the filter keeps predicting and its covariance grows.
///
/// Update: Joseph form P = (I - K H) P (I - K H)^T + K R K^T, then symmetrised.
/// Nothing in predict() or add_measurement() throws: problems are counted (EkfCounters).

#include <cstdint>
#include <deque>
#include <functional>
#include <vector>

#include <Eigen/Core>

#include "contract/default_rates.h"
#include "core/param_table.h"

#include "estimator/ekf_model.h"
#include "estimator/mocap_measurement.h"
#include "core/rig_values.h"

namespace nimble {

/// What the EKF takes a differentiated mocap velocity to measure.
enum class EkfVelocityMeasurement {
  kWindowMean,  ///< the mean velocity over the difference's window (what it is; default)
  kInstant,     ///< the velocity at the middle frame (the thesis's reading)
};

/// How the EKF treats measurements stamped in the past.
enum class EkfLatencyMode {
  kRollback,  ///< insert at the measurement time and re-propagate (default)
  kNaive,     ///< apply to the current state as if current (comparison only)
};

/// Parameters of AttitudeVelocityEkf. Defaults: thesis Eq 8.2 for Q and R; the rest are stated
/// assumptions.
struct EkfConfig {
  /// Gravity [m/s^2]; the value of the thesis's models (9.81).
  double gravity_mps2 = 9.81;
  /// Smallest |cos(theta)| in the Euler kinematics [-], see ekf_model.h.
  double min_abs_cos_theta = 1e-3;

  /// Rate at which the *_var_per_sample values are per-sample variances [Hz]; thesis: data
  /// upsampled to 512 Hz for the fusion.
  double process_noise_reference_rate_hz = contract::kDefaultImuRateHz;
  /// Gyro input noise, variance per sample at the reference rate [(rad/s)^2]; thesis Eq 8.2 Q(1:3).
  Eigen::Vector3d gyro_noise_var_per_sample_rad2ps2 = Eigen::Vector3d(7.60, 2.60, 12.07);
  /// Accelerometer input noise, variance per sample at the reference rate [(m/s^2)^2]; Eq 8.2 Q(4:6).
  Eigen::Vector3d accel_noise_var_per_sample_m2ps4 = Eigen::Vector3d(26.99, 36.66, 56.12);
  /// Gyro bias random walk [rad/s/sqrt(s)]. Not in the thesis (its biases are constant); default
  /// equal to the emulated IMU's (ImuModelConfig).
  Eigen::Vector3d gyro_bias_rw_radps_per_sqrts = Eigen::Vector3d::Constant(2e-4);
  /// Accelerometer bias random walk [m/s^2/sqrt(s)]; default equal to the emulated IMU's.
  Eigen::Vector3d accel_bias_rw_mps2_per_sqrts = Eigen::Vector3d::Constant(2e-3);

  /// Variance of the measured phi, theta, psi [rad^2]; thesis Eq 8.2 R(1:3).
  Eigen::Vector3d attitude_var_rad2 = Eigen::Vector3d(0.125e-3, 0.057e-3, 0.037e-3);
  /// Variance of the measured u, v, w [(m/s)^2]; thesis Eq 8.2 R(4:6).
  Eigen::Vector3d velocity_var_m2ps2 = Eigen::Vector3d(0.113e-3, 0.216e-3, 0.135e-3);

  /// Initial 1-sigma of the attitude [rad] (initialisation from a mocap attitude). Assumption: 0.02.
  double initial_attitude_sigma_rad = 0.02;
  /// Initial 1-sigma of the body velocity [m/s]. Assumption: 0.1 (vehicle near hover at start).
  double initial_velocity_sigma_mps = 0.1;
  /// Initial 1-sigma of the gyro bias [rad/s]; equal to the emulated IMU's turn-on sigma.
  double initial_gyro_bias_sigma_radps = 0.02;
  /// Initial 1-sigma of the accelerometer bias [m/s^2]; equal to the emulated IMU's turn-on sigma.
  double initial_accel_bias_sigma_mps2 = 0.2;

  /// Innovation gating on/off.
  bool gate_enabled = true;
  /// Probability of the chi-square gate [-] (0.999: a consistent measurement is rejected 1 in 1000).
  double gate_probability = 0.999;

  /// What a differentiated velocity measures. The central difference over the span D is the
  /// mean velocity over the window, not the velocity at its middle: a manoeuvre at f Hz comes
  /// out scaled by sinc(f D) (0.86 at 5 Hz for D = 60 ms), which the instant reading passes on
  /// to the estimate. kWindowMean removes it (see the top of this header).
  EkfVelocityMeasurement velocity_measurement = EkfVelocityMeasurement::kWindowMean;

  /// Treatment of late measurements.
  EkfLatencyMode latency_mode = EkfLatencyMode::kRollback;
  /// Length of the rollback history [s]; measurements older than this are dropped and counted.
  double history_s = 0.1;
  /// A replay may reuse an interval's stored linearisation while the state at the interval's start
  /// differs from the state it was made at by at most these (top of this header). Phi's entries
  /// then move by about g dt delta_attitude (gravity terms), dt delta_velocity (the gyro-bias
  /// columns) and dt delta_gyro_bias (the rate terms). Default 0: every replayed step linearised
  /// again, the exact replay. With 0.02 rad, 0.05 m/s, 0.05 rad/s (each entry of Phi within
  /// 4e-4 per 512 Hz step) the filter costs a sixth to a half less with the rig's sensing, its
  /// state stays within a tenth of its sigma of the exact replay's (0.04 to 0.09 sigma at worst
  /// over bench_ekf's 30 to 60 s flights) and its sigmas within 3 % (bench_ekf, test_ekf.cc);
  /// a flight flown on that estimate then differs from the exact replay's accordingly.
  double replay_relinearise_attitude_rad = 0.0;
  double replay_relinearise_velocity_mps = 0.0;
  double replay_relinearise_gyro_bias_radps = 0.0;
  /// Longest single integration step [s]; longer IMU intervals are split.
  double max_step_s = 0.0025;
  /// IMU interval above which a gap is counted [s].
  double imu_gap_s = 0.02;

  /// Process model constants derived from this config.
  EkfModelParams model_params() const { return {gravity_mps2, min_abs_cos_theta}; }
  /// Initial covariance from the initial_* sigmas (diagonal).
  EkfCovariance initial_covariance() const;
};

/// Checks an EkfConfig.
/// @throws std::invalid_argument naming the field, its value and the allowed range.
void validate(const EkfConfig& config);

/// The `ekf` section's parameters: key (group.key within its sub-mapping), range, unit,
/// meaning; the defaults are EkfConfig's. The loader (estimator/sensing_config.h), validate()
/// and `rig params` use this table; velocity_measurement and latency.mode are read on their own.
const ParamTable<EkfConfig>& ekf_params();

/// Outcome of add_measurement().
enum class EkfMeasurementStatus {
  kAccepted,      ///< applied (now or in the past)
  kRejectedGate,  ///< NIS above the gate
  kPending,  ///< stamped (or its velocity window ends) after the newest IMU sample; applied when the IMU catches up
  kTooOld,   ///< older than the history; dropped
  kTooNew,   ///< more than history_s ahead of the newest IMU sample; dropped
  kNotInitialized,  ///< the filter is not initialised; dropped
  kInvalid,         ///< non-finite values; dropped
};

/// One gating decision (reported once per measurement, when it is first evaluated).
struct EkfUpdateRecord {
  /// Time the measurement refers to [us].
  std::int64_t utime = 0;
  /// Filter time (newest IMU sample) when it was evaluated [us].
  std::int64_t filter_utime = 0;
  /// Frame number it came from [-].
  std::int64_t frame_number = -1;
  /// Measurement dimension (3 or 6) [-].
  int dim = 0;
  /// Normalised innovation squared [-].
  double nis = 0.0;
  /// True if it passed the gate and was applied.
  bool accepted = false;
  /// Innovation z - h(x) (first `dim` entries) [rad, m/s].
  Eigen::Matrix<double, 6, 1> innovation = Eigen::Matrix<double, 6, 1>::Zero();
};

/// Counters of the EKF (published by the estimator process).
struct EkfCounters {
  std::int64_t imu_samples = 0;            ///< IMU samples used for prediction
  std::int64_t imu_rejected = 0;           ///< IMU samples dropped (time not increasing, non-finite, not initialised)
  std::int64_t imu_gaps = 0;               ///< IMU intervals longer than imu_gap_s
  std::int64_t measurements_accepted = 0;  ///< measurements applied
  std::int64_t measurements_rejected_gate = 0;  ///< measurements rejected by the innovation gate
  std::int64_t measurements_too_old = 0;        ///< measurements older than the history
  std::int64_t measurements_too_new = 0;        ///< measurements too far ahead of the IMU
  std::int64_t measurements_invalid = 0;        ///< non-finite or before initialisation
  std::int64_t rollbacks = 0;                   ///< measurements inserted in the past
  std::int64_t velocity_window_uncovered = 0;   ///< velocity windows the history did not cover (no offset applied)
  std::int64_t replay_steps = 0;                ///< Heun steps of replays
  std::int64_t replay_steps_linearised = 0;     ///< of those, steps linearised again (not reused)
};

/// One node of the filter's history: an IMU sample's time and input, and the state and
/// covariance after every measurement up to that time.
struct EkfNode {
  std::int64_t utime = 0;  ///< [us]
  EkfInput u = EkfInput::Zero();
  bool has_input = false;
  /// PSD of the input noise over the interval that ends at this node (the configured one, or
  /// raised for this sample: predict()'s input_var_per_sample); a replay uses it again.
  EkfInput input_psd = EkfInput::Zero();
  EkfState x = EkfState::Zero();
  EkfCovariance P = EkfCovariance::Identity();
};

/// The EKF. See the top of this header.
class AttitudeVelocityEkf {
 public:
  /// @throws std::invalid_argument if `config` is invalid.
  explicit AttitudeVelocityEkf(const EkfConfig& config);

  /// Starts the filter at `utime` [us] with state `x0` and covariance `P0`; clears the history.
  void initialize(std::int64_t utime, const EkfState& x0, const EkfCovariance& P0);
  /// Starts the filter at z.utime from a measurement: attitude (and velocity if present) from z,
  /// zero velocity otherwise, zero biases, covariance config.initial_covariance().
  void initialize_from_measurement(const PoseMeasurement& z);
  /// True after initialize().
  bool initialized() const { return !history_.empty(); }

  /// Propagates to the sample time with the IMU sample as input; returns false (and counts) if the
  /// sample is not used (not initialised, time not after the newest sample, non-finite values).
  /// The first sample at the initialisation time only sets the input.
  /// `input_var_per_sample` (optional): the input noise of this interval as per-sample variances
  /// at process_noise.reference_rate_hz, like the configured ones; each channel takes the larger
  /// of the two (the on-board IMU filtering's own measure of what vibration it left,
  /// ImuPrefilter::residual_var()).
  bool predict(std::int64_t utime, const EkfInput& imu_input, const EkfInput* input_var_per_sample = nullptr);
  /// predict() from an ImuSample ([gyro accel]).
  bool predict(const ImuSample& sample, const EkfInput* input_var_per_sample = nullptr);

  /// Processes one measurement stamped z.utime (see the top of this header for latency handling).
  EkfMeasurementStatus add_measurement(const PoseMeasurement& z);
  /// Processes measurements in order (those of one motion-capture frame,
  /// MocapMeasurementBuilder::push()); returns their statuses in the same order. The result,
  /// bit for bit, of add_measurement() on each in turn, but the measurements inserted in the past
  /// share one re-propagation to the present (the attitude of a frame rides along with the
  /// velocity measurement it completes).
  std::vector<EkfMeasurementStatus> add_measurements(const std::vector<PoseMeasurement>& zs);

  /// Called once per gating decision (also for measurements that were pending).
  void set_update_observer(std::function<void(const EkfUpdateRecord&)> observer) { observer_ = std::move(observer); }
  /// Called with each history node when it is final: when it leaves the history (no measurement
  /// can reach it any more), and by release_history() for the rest. A fixed-interval smoother
  /// (estimator/smoother.h) collects the filtered trajectory this way.
  void set_node_observer(std::function<void(const EkfNode&)> observer) { node_observer_ = std::move(observer); }
  /// End of data: hands every node still in the history to the node observer, oldest first, and
  /// leaves the filter uninitialised. Measurements still pending are dropped.
  void release_history();
  /// The prediction of the filter from t0 to t1 [us] with the input linear from u0 to u1, as
  /// predict() makes it (substeps included); returns the transition matrix Phi of the whole
  /// interval (the product of the substeps' exact Jacobians). `input_psd`: the interval's input
  /// noise PSD (a history node's EkfNode::input_psd); null: the configured one.
  EkfCovariance predict_between(EkfState* x, EkfCovariance* P, const EkfInput& u0, const EkfInput& u1, std::int64_t t0,
                                std::int64_t t1, const EkfInput* input_psd = nullptr) const;

  /// State at the newest IMU sample.
  const EkfState& state() const { return history_.back().x; }
  /// Covariance at the newest IMU sample.
  const EkfCovariance& covariance() const { return history_.back().P; }
  /// Time of the newest IMU sample (or of the initialisation) [us].
  std::int64_t utime() const { return history_.back().utime; }
  /// Bias-corrected angular rate of the newest IMU sample, body axes [rad/s].
  Eigen::Vector3d corrected_rate_radps() const;
  /// State and covariance of the newest history node at or before `utime`; false if none.
  bool state_at(std::int64_t utime, EkfState* x, EkfCovariance* P) const;
  /// NIS of the most recent gating decision; -1 before the first.
  double last_nis() const { return last_nis_; }
  /// Gate threshold for a measurement of dimension `dim` (3 or 6) [-].
  double gate_threshold(int dim) const { return dim == 6 ? gate6_ : gate3_; }
  /// Counters since construction.
  const EkfCounters& counters() const { return counters_; }
  /// The configuration in use.
  const EkfConfig& config() const { return config_; }
  /// Number of IMU nodes kept in the history [-].
  std::size_t history_size() const { return history_.size(); }

 private:
  using Node = EkfNode;
  using Mat6 = Eigen::Matrix<double, 6, 6>;
  /// The covariance part of one Heun step (propagate()): Phi = [Phi11 Phi12; 0 I] and the input
  /// noise Q(Bg0), Q(Bg1) of the top-left block at the step's two ends.
  struct StepLinearisation {
    Mat6 Phi11, Phi12, Q0, Q1;
  };
  /// A step kept for reuse: its interval [t0, t1] (t1 <= t0: empty) and the state at t0 it was
  /// linearised at.
  struct KeptStep {
    std::int64_t t0 = 0, t1 = 0;
    EkfState x0 = EkfState::Zero();
    StepLinearisation step;
  };
  /// The steps kept for the interval that ends at one history node (history_ and kept_ go
  /// together): the forward prediction's whole interval, then the pieces a measurement inside it
  /// splits it into. Two: a third piece (two measurements in one IMU interval) is linearised
  /// each time.
  struct KeptSteps {
    KeptStep entry[2];
    int next = 0;  ///< the entry the next new step replaces
  };
  /// An accepted measurement kept for re-application; is_new while it waits for its gating decision.
  struct Stored {
    PoseMeasurement z;
    bool is_new = false;
    /// While is_new: where the replay writes the gating decision (or null).
    EkfMeasurementStatus* status = nullptr;
  };

  /// One Heun step; with `Phi`, also its transition matrix, left-multiplied into *Phi.
  /// `psd`: the input noise's PSD over the step. With `made`, the step's linearisation goes there.
  void propagate(EkfState* x, EkfCovariance* P, const EkfInput& u0, const EkfInput& u1, double dt_s,
                 const EkfInput& psd, EkfCovariance* Phi = nullptr, StepLinearisation* made = nullptr) const;
  /// One Heun step of the state, and the covariance through the given linearisation.
  void propagate_with(EkfState* x, EkfCovariance* P, const EkfInput& u0, const EkfInput& u1, double dt_s,
                      const StepLinearisation& step) const;
  /// P through one step's linearisation.
  void propagate_covariance(EkfCovariance* P, const StepLinearisation& step, double dt_s) const;
  /// True if a step linearised at x0 may be reused from x (EkfConfig::replay_relinearise_*).
  bool reusable(const EkfState& x0, const EkfState& x) const;
  /// Propagates from t0 to t1. With `kept` (the interval's kept steps) a one-step interval reuses
  /// a kept step of the same interval when reusable(), else keeps the one it makes; `reused`
  /// (optional) tells which.
  void propagate_interval(EkfState* x, EkfCovariance* P, const EkfInput& u0, const EkfInput& u1, std::int64_t t0,
                          std::int64_t t1, const EkfInput& psd, EkfCovariance* Phi = nullptr, KeptSteps* kept = nullptr,
                          bool* reused = nullptr) const;
  /// propagate_interval() within a replay, counted.
  void replay_interval(EkfState* x, EkfCovariance* P, const EkfInput& u0, const EkfInput& u1, std::int64_t t0,
                       std::int64_t t1, const EkfInput& psd, KeptSteps* kept);
  bool update(EkfState* x, EkfCovariance* P, const PoseMeasurement& z, bool gate, EkfUpdateRecord* record) const;
  /// Stores z (already prepared, not too old) and replays from the node before it.
  EkfMeasurementStatus insert_in_past(const PoseMeasurement& z);
  /// Stores z as a new measurement whose gating decision goes to `status` at the next replay();
  /// returns the index of the last history node before z, where that replay must start.
  std::size_t store(const PoseMeasurement& z, EkfMeasurementStatus* status);
  /// Restores history node j and re-propagates through the stored inputs to the present, gating
  /// the new stored measurements and re-applying (without gating) the others; overwrites the nodes.
  void replay(std::size_t j);
  /// add_measurement() for n measurements in order (statuses to status[0..n)), one replay for
  /// those stored together.
  void add_batch(const PoseMeasurement* zs, std::size_t n, EkfMeasurementStatus* status);
  /// True if z is older than the history (insert_in_past drops it).
  bool too_old(const PoseMeasurement& z) const;
  /// Filter time from which z can be applied: its own time, or the end of its velocity window.
  std::int64_t ready_utime(const PoseMeasurement& z) const;
  /// Offset c of the header for z's velocity window; false if the history does not cover it.
  bool velocity_window_offset(const PoseMeasurement& z, Eigen::Vector3d* offset) const;
  /// z with the window offset removed from its velocity (kWindowMean), as the filter applies it.
  PoseMeasurement prepared(const PoseMeasurement& z);
  EkfMeasurementStatus apply_now(const PoseMeasurement& z);
  void report(const EkfUpdateRecord& record);
  void trim();

  EkfConfig config_;
  EkfModelParams params_;
  Eigen::Matrix<double, kEkfInputDim, 1> input_psd_;  // S
  Eigen::Matrix<double, 6, 1> bias_rw_psd_;           // q_bg, q_ba
  double gate3_ = 0.0, gate6_ = 0.0;
  std::int64_t history_us_ = 0;
  std::deque<Node> history_;
  std::deque<KeptSteps> kept_;          // one per history node
  std::int64_t initialized_utime_ = 0;  // time of the last initialize()
  std::deque<Stored> accepted_;
  std::vector<PoseMeasurement> pending_;
  EkfCounters counters_;
  double last_nis_ = -1.0;
  std::function<void(const EkfUpdateRecord&)> observer_;
  std::function<void(const EkfNode&)> node_observer_;
};

}  // namespace nimble
