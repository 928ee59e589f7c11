#pragma once
/// The estimator process: the attitude/velocity EKF (estimator/ekf.h) fusing the onboard
/// IMU and the motion capture, as the lab's fused data. Configured by `sensing`.
///
/// Subscribes:
///   IMU          imu_sample_t    512 Hz   prediction input
///   MOCAP_POSE   mocap_pose_t    200 Hz   measurements (attitude; body velocity from the
///                                         differentiated position)
///   ACTUATOR_FB  actuator_feedback_t 100 Hz  only with sensing.imu_prefilter enabled: the
///                                         measured flapping frequencies that place its notches
///   RUN_CONTROL, RIG_CLOCK                (ProcessNode; lockstep participant at the IMU rate)
/// Publishes:
///   ESTIMATE     estimator_state_t  512 Hz  state, bias-corrected rates, covariance diagonal,
///                                           pose counters
///   FAULT, HEARTBEAT, TIMING_HEALTH, STEP_ACK (ProcessNode)
///
/// With sensing.imu_prefilter enabled each IMU sample passes the on-board filtering
/// (estimator/imu_prefilter.h) before the EKF, its notches at the newest measured flapping
/// frequencies (lockstep: the feedback stamped at or before the sample's rig time among those
/// released, so the result does not depend on process timing), and the filter starts only once
/// the prefilter has learnt its lines (0.25 s of samples; the controller's first-input timeout is
/// 0.5 s). The stuck-IMU check reads the raw samples.
///
/// The filter starts from the first motion-capture measurement. Real time: each IMU sample
/// is predicted and published as it arrives, each pose applied as it arrives (late poses by
/// rollback). Lockstep: at each tick the inputs that became available before the tick are
/// applied in time order and one estimate goes out, stamped with the tick time, so that
/// what the controller sees at a tick does not depend on process timing.
///
/// Bad inputs: a sample or pose with non-finite values is malformed (CODE_MESSAGE_MALFORMED)
/// and not used. An IMU whose six channels repeat bit for bit for kImuStuckSamples samples
/// is stuck (CODE_SENSOR_STUCK, only when the configured IMU noise is not zero: a noisy sensor
/// cannot repeat itself); its samples are not used until they change, so the estimate's
/// imu_utime stops and the controller, which ages an estimate by it, takes its failsafe.
///
/// Clocks: the filter works on the IMU's stamps as they come (the on-board clock, which may
/// differ from the motion capture's by sensing.imu.clock_offset_s and clock_drift_ppm, as in a
/// lab). The node's own bookkeeping keeps to the rig's clock: it reads each stamp back to the
/// rig time of its sample (ImuClock::rig_utime) for the lockstep inbox, the real-time
/// publication and latency, and the estimate's imu_utime, so the controller's input age and the
/// run monitor's comparison with the truth are on the rig's clock whatever the IMU's.

#include <memory>

#include "estimator/divergence_monitor.h"
#include "estimator/ekf.h"
#include "estimator/imu_prefilter.h"
#include "estimator/mocap_measurement.h"
#include "sensors/imu_model.h"
#include "scenario/scenario.h"
#include "core/rig_values.h"
#include "transport/latched_input.h"
#include "transport/node.h"

namespace nimble {

class EstimatorNode {
 public:
  /// @throws ConfigError on bad configuration.
  EstimatorNode(const Scenario& scenario, const transport::NodeOptions& options);
  int run();
  transport::ProcessNode& node() { return *node_; }

  /// Identical IMU samples in a row that make the IMU stuck: 0.1 s at 512 Hz. With the IMU
  /// model's white noise (0.05 deg/s, 0.05 g per sample) one exact repeat of all six channels
  /// already has a probability below 1e-30.
  static constexpr int kImuStuckSamples = 50;
  /// Divergence (DivergenceMonitor): gating decisions per window, 0.2 s of motion capture at
  /// 200 Hz, and the false-alarm probability per window: 1e-9, about one false alarm in 5,000
  /// hours of flight with overlapping windows at 200 Hz. Once diverged the estimator raises
  /// CODE_ESTIMATOR_DIVERGED and publishes no more estimates: the controller's failsafe follows.
  static constexpr int kDivergenceWindow = 40;
  static constexpr double kDivergenceFalseAlarm = 1e-9;

 private:
  /// Predicts with `sample`, taken at rig time `rig_utime` [us].
  void apply_imu(const ImuSample& sample, int64_t rig_utime);
  /// The rig time [us] of the filter's newest time: the rig time of the newest IMU sample
  /// applied when that is the filter's time, else the filter's time (a measurement's).
  int64_t filter_rig_utime() const;
  void apply_pose(const MocapPose& pose);
  void tick(int64_t sim_time_ns);
  void publish(int64_t utime);
  /// FAULT for a measurement the EKF dropped for its time (at most one a second of rig time).
  void report_dropped(const PoseMeasurement& z, EkfMeasurementStatus status);

  /// The IMU sample to use, or false (non-finite: malformed; stuck: repeated).
  bool imu_usable(const ImuSample& sample);
  /// Feeds the gate decisions made since the last call to the divergence monitor.
  void watch_divergence();
  std::unique_ptr<DivergenceMonitor> divergence_;
  int64_t seen_accepted_ = 0, seen_rejected_ = 0;
  bool diverged_ = false;
  bool stuck_check_ = false;  ///< the configured IMU noise is not zero
  ImuSample last_imu_{};
  int imu_repeats_ = 0;
  bool imu_stuck_ = false;
  std::unique_ptr<AttitudeVelocityEkf> ekf_;
  /// The on-board IMU filtering (sensing.imu_prefilter); null when off.
  std::unique_ptr<ImuPrefilter> prefilter_;
  /// Lockstep: the measured flapping frequencies [rad/s] (left, right) by their rig time.
  transport::LatchedInput<std::pair<double, double>> flap_inbox_;
  std::unique_ptr<MocapMeasurementBuilder> builder_;
  std::unique_ptr<transport::ProcessNode> node_;
  /// The IMU's clock (sensing.imu): stamps to rig time.
  ImuClock imu_clock_;
  /// The newest IMU sample applied: its stamp and its rig time [us].
  int64_t last_imu_stamp_ = INT64_MIN, last_imu_rig_utime_ = INT64_MIN;
  /// Lockstep: IMU samples (by the rig time of their sample) and poses (by their publication time) received,
  /// applied from the first tick after that time.
  transport::LatchedInput<ImuSample> imu_inbox_;
  transport::LatchedInput<MocapPose> pose_inbox_;
  int64_t seq_ = 0;
  int64_t poses_missing_ = 0;
  int64_t last_frame_ = -1;
  int64_t last_drop_fault_utime_ = INT64_MIN;
  /// The control loop's stages the estimator times (ProcessNode::add_stage).
  int stage_imu_in_ = -1, stage_estimate_out_ = -1, stage_work_ = -1, stage_filter_ = -1, stage_publish_ = -1,
      stage_pose_ = -1;
};

}  // namespace nimble
