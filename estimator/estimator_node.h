#pragma once
/// The estimator process: the attitude/velocity EKF (estimator/ekf.h) fusing the onboard
/// IMU and the motion capture, as the lab's fused data. Configured by `sensing`.
///
/// Subscribes:
///   IMU          imu_sample_t    512 Hz   prediction input
///   MOCAP_POSE   mocap_pose_t    200 Hz   measurements (attitude; body velocity from the
///                                         differentiated position)
///   RUN_CONTROL, RIG_CLOCK                (ProcessNode; lockstep participant at the IMU rate)
/// Publishes:
///   ESTIMATE     estimator_state_t  512 Hz  state, bias-corrected rates, covariance diagonal,
///                                           pose counters
///   FAULT, HEARTBEAT, TIMING_HEALTH, STEP_ACK (ProcessNode)
///
/// The filter starts from the first motion-capture measurement. Real time: each IMU sample
/// is predicted and published as it arrives, each pose applied as it arrives (late poses by
/// rollback). Lockstep: at each tick the inputs that became available before the tick are
/// applied in time order and one estimate goes out, stamped with the tick time, so that
/// what the controller sees at a tick does not depend on process timing.

#include <memory>

#include "estimator/ekf.h"
#include "estimator/mocap_measurement.h"
#include "scenario/scenario.h"
#include "sensors/sensor_types.h"
#include "transport/latched_input.h"
#include "transport/node.h"

namespace nimble {

class EstimatorNode {
 public:
  /// @throws ConfigError on bad configuration.
  EstimatorNode(const Scenario& scenario, const transport::NodeOptions& options);
  int run();
  transport::ProcessNode& node() { return *node_; }

 private:
  void apply_imu(const ImuSample& sample);
  void apply_pose(const MocapPose& pose);
  void tick(int64_t sim_time_ns);
  void publish(int64_t utime);
  /// FAULT for a measurement the EKF dropped for its time (at most one a second of rig time).
  void report_dropped(const PoseMeasurement& z, EkfMeasurementStatus status);

  std::unique_ptr<AttitudeVelocityEkf> ekf_;
  std::unique_ptr<MocapMeasurementBuilder> builder_;
  std::unique_ptr<transport::ProcessNode> node_;
  /// Lockstep: IMU samples (by their time) and poses (by their publication time) received,
  /// applied from the first tick after that time.
  transport::LatchedInput<ImuSample> imu_inbox_;
  transport::LatchedInput<MocapPose> pose_inbox_;
  int64_t seq_ = 0;
  int64_t poses_missing_ = 0;
  int64_t last_frame_ = -1;
  int64_t last_drop_fault_utime_ = INT64_MIN;
};

}  // namespace nimble
