#pragma once
/// The rig-side values its processes exchange, as plain data: what each stream message of the
/// contract carries (lcmtypes/), without the transport. The cores produce and consume these;
/// contract/messages.h converts each to its message and back, written once, and every process,
/// the run monitor and the log readers go through it.
///
///   Truth             truth_state_t          TRUTH               plant
///   ImuSample         imu_sample_t           IMU                 plant
///   MocapPose         mocap_pose_t           MOCAP_POSE          mocap
///   ActuatorCommand   actuator_command_t     ACTUATOR_CMD[_CAN]  controller, can_rig
///   ActuatorFeedback  actuator_feedback_t    ACTUATOR_FB[_CAN]   plant, can_flight
///   AttitudeSetpoint  attitude_setpoint_t    ATTITUDE_SP         controller
///   Estimate          estimator_state_t      ESTIMATE            estimator
///   ControllerStatus  controller_status_t    CONTROLLER_STATUS   controller
///   CanHealth         can_health_t           CAN_HEALTH          can_flight, can_rig
///   FaultEvent        fault_event_t          FAULT               every process, the launcher
///
/// Units are in the names (SI; angles in rad, flapping frequencies in rad/s, throttle in % of
/// full scale). utime is the rig's time of the value [us]; seq the publisher's sequence number.
/// The lockstep clock's and the processes' own messages (RIG_CLOCK, STEP_ACK, RUN_CONTROL,
/// HEARTBEAT, TIMING_HEALTH) belong to the transport (transport/node.h) and have no value type
/// here.
///
/// The IMU sample and the motion-capture pose are what the emulated sensors (sensors/, on the
/// truth side) produce and the estimator (estimator/, under test) consumes: neither side's model
/// is needed to read them. Axes as in lcmtypes/README.md: body x forward, y right wing, z down;
/// world frame NED.

#include <cstdint>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace nimble {

/// Bits of ImuSample::saturation_flags (identical to imu_sample_t::SAT_*).
enum ImuSaturationBit : std::uint8_t {
  kSatGyroX = 1,
  kSatGyroY = 2,
  kSatGyroZ = 4,
  kSatAccelX = 8,
  kSatAccelY = 16,
  kSatAccelZ = 32,
};

/// One IMU sample; mirrors imu_sample_t.
struct ImuSample {
  /// Sampling instant, rig time [us].
  std::int64_t utime = 0;
  /// Sample counter of the producing IMU [-]: 0 for the first sample.
  std::int64_t seq = 0;
  /// Measured angular rate, body axes [rad/s], order p q r.
  Eigen::Vector3d gyro_radps = Eigen::Vector3d::Zero();
  /// Measured specific force, body axes [m/s^2].
  Eigen::Vector3d accel_mps2 = Eigen::Vector3d::Zero();
  /// Die temperature [degC].
  double temperature_degc = 0.0;
  /// Bitmask of ImuSaturationBit [-]; 0 when no axis is clamped.
  std::uint8_t saturation_flags = 0;
};

/// One motion-capture frame; mirrors mocap_pose_t plus its publication time.
struct MocapPose {
  /// Middle of the camera exposure, rig time [us].
  std::int64_t utime = 0;
  /// Message counter of the producing emulator [-]: 0 for the first frame, +1 per frame.
  std::int64_t seq = 0;
  /// Frame counter [-], consecutive.
  std::int64_t frame_number = 0;
  /// Latency from mid-exposure to publication [us].
  std::int32_t latency_us = 0;
  /// Rigid-body identifier [-].
  std::int32_t rigid_body_id = 1;
  /// Measured position in NED [m]; zero when tracking_valid is false.
  Eigen::Vector3d position_ned_m = Eigen::Vector3d::Zero();
  /// Measured attitude q_body_to_ned (w >= 0); identity when tracking_valid is false.
  Eigen::Quaterniond q_body_to_ned = Eigen::Quaterniond::Identity();
  /// False during an occlusion.
  bool tracking_valid = false;
  /// Size of this frame's 3-D position error [m] (the emulator's stand-in for the fit residual).
  double mean_marker_error_m = 0.0;
  /// Markers seen [-]: the rigid body's markers when tracked, 0 when occluded.
  std::int16_t num_markers = 0;
  /// Rig time at which the frame is published [us] = utime + latency_us.
  std::int64_t publish_utime = 0;
};

/// The plant's true state at time_s (TRUTH).
struct Truth {
  double time_s = 0.0;
  Eigen::Vector3d position_ned_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_body_mps = Eigen::Vector3d::Zero();  ///< u v w
  Eigen::Vector3d euler_rad = Eigen::Vector3d::Zero();          ///< phi theta psi
  Eigen::Vector4d quaternion_wxyz = Eigen::Vector4d(1, 0, 0, 0);
  Eigen::Vector3d omega_body_radps = Eigen::Vector3d::Zero();  ///< p q r
  Eigen::Vector3d specific_force_body_mps2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d angular_accel_body_radps2 = Eigen::Vector3d::Zero();
  double flap_freq_left_radps = 0.0;
  double flap_freq_right_radps = 0.0;
  double delta_f_radps = 0.0;
  double throttle_pct = 0.0;  ///< actual delta_t (deviation from trim) [%]
  double dihedral_rad = 0.0;
  double wing_root_rad = 0.0;
  double gust_v_mps = 0.0;  ///< side gust the aerodynamics see; not on the bus
};

/// A command of the flight board to the actuators (ACTUATOR_CMD).
struct ActuatorCommand {
  /// How the command gives the flapping frequencies (actuator_command_t::MODE_*).
  static constexpr int8_t kModeLeftRight = 0;  ///< flap_freq_left_radps and flap_freq_right_radps
  static constexpr int8_t kModeDeltaF = 1;     ///< flap_freq_collective_radps and delta_f_radps
  int64_t utime = 0;
  int64_t seq = 0;
  int8_t mode = kModeLeftRight;
  double flap_freq_left_radps = 0.0;
  double flap_freq_right_radps = 0.0;
  double delta_f_radps = 0.0;  ///< left minus right [rad/s]
  double flap_freq_collective_radps = 0.0;
  double throttle_pct = 0.0;  ///< throttle after tilt compensation [%]
  double dihedral_rad = 0.0;
  double wing_root_rad = 0.0;
  int64_t input_utime = -1;    ///< utime of the state the command was computed from (-1: none)
  int8_t rolling_counter = 0;  ///< 0..15, one step per command
  std::string source;          ///< the publishing process
};

/// What the actuators report back (ACTUATOR_FB).
struct ActuatorFeedback {
  int64_t utime = 0;
  int64_t seq = 0;
  double flap_freq_left_radps = 0.0;
  double flap_freq_right_radps = 0.0;
  double delta_f_radps = 0.0;
  double dihedral_rad = 0.0;
  double wing_root_rad = 0.0;
  double throttle_pct = 0.0;
  int64_t cmd_seq = -1;     ///< seq of the last command applied
  int64_t cmd_age_us = 0;   ///< its age
  bool safe_state = false;  ///< commands timed out: trim frequencies, servos neutral
};

/// The manoeuvre's set-point of one control cycle (ATTITUDE_SP).
struct AttitudeSetpoint {
  int64_t utime = 0;
  int64_t seq = 0;
  double roll_sp_rad = 0.0;
  double pitch_sp_rad = 0.0;
  double yaw_rate_sp_radps = 0.0;
  double throttle_pct = 0.0;     ///< throttle set-point before tilt compensation [%]
  double throttle_factor = 1.0;  ///< THRF [-]
  std::string manoeuvre;
  int32_t segment_index = -1;
  std::string segment_name;
  std::string gain_set;
};

/// The EKF's estimate (ESTIMATE).
struct Estimate {
  int64_t utime = 0;
  int64_t seq = 0;
  int64_t imu_utime = 0;  ///< the newest IMU sample in it
  Eigen::Vector3d euler_rad = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_body_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_bias_radps = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_bias_mps2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d omega_body_radps = Eigen::Vector3d::Zero();  ///< bias-corrected rate
  Eigen::Matrix<double, 12, 1> cov_diag = Eigen::Matrix<double, 12, 1>::Zero();
  int64_t poses_accepted = 0;
  int64_t poses_rejected = 0;
  int64_t poses_missing = 0;
  double last_nis = 0.0;
  int64_t poses_too_old = 0;
  int64_t poses_too_new = 0;
  int64_t velocity_windows_uncovered = 0;
  int64_t imu_rejected = 0;
  int64_t imu_gaps = 0;
};

/// The attitude controller's state of one control cycle (CONTROLLER_STATUS).
struct ControllerStatus {
  /// Where the controller's state came from (controller_status_t::INPUT_*).
  static constexpr int8_t kInputTruth = 0;
  static constexpr int8_t kInputEstimate = 1;
  int64_t utime = 0;
  int64_t seq = 0;
  std::string gain_set;
  double kp = 0.0;
  double kd = 0.0;
  double roll_ref_rad = 0.0;
  double roll_rate_ref_radps = 0.0;
  double roll_error_rad = 0.0;
  double roll_cmd_norm = 0.0;
  double pitch_cmd_norm = 0.0;
  double delta_f_cmd_radps = 0.0;
  double throttle_pct = 0.0;
  bool saturated = false;
  int8_t input_source = kInputTruth;
  int64_t input_age_us = 0;
  bool failsafe = false;
};

/// One side of the CAN actuator link (CAN_HEALTH).
struct CanHealth {
  static constexpr int8_t kRoleFlight = 0;
  static constexpr int8_t kRoleRig = 1;
  static constexpr int8_t kBusActive = 0;
  static constexpr int8_t kBusWarning = 1;
  static constexpr int8_t kBusPassive = 2;
  static constexpr int8_t kBusOff = 3;
  int64_t utime = 0;  ///< wall clock [us]
  int64_t seq = 0;
  std::string process;
  int8_t role = kRoleFlight;
  std::string interface_name;
  int64_t messages_to_can = 0;
  int64_t messages_to_lcm = 0;
  int64_t frames_sent = 0;
  int64_t frames_received = 0;
  int64_t send_enobufs = 0;
  int64_t send_retries = 0;
  int64_t send_dropped = 0;
  int64_t receive_dropped = 0;
  int64_t rejected_unknown_id = 0;
  int64_t rejected_wrong_length = 0;
  int64_t rejected_bad_checksum = 0;
  int64_t rejected_stale_counter = 0;
  int64_t rejected_out_of_range = 0;
  int64_t counter_gaps = 0;
  int64_t saturated_values = 0;
  int64_t error_frames = 0;
  int8_t bus_state = kBusActive;
  std::string last_error;
  std::string candump_file;
  int64_t candump_lines = 0;
  bool fd = false;
  int64_t fd_frames_sent = 0;
  int64_t fd_frames_received = 0;
};

/// Something a process reports (FAULT): severity and code are fault_event_t's SEVERITY_* and
/// CODE_* values (contract/faults.h names them).
struct FaultEvent {
  int64_t utime = 0;  ///< wall clock when it was reported [us]
  int64_t seq = 0;
  int64_t rig_utime = 0;  ///< the rig's time it refers to [us]
  std::string process;    ///< who reports it
  int8_t severity = 0;
  int32_t code = 0;
  std::string channel;  ///< the channel it concerns ("" if none)
  std::string message;  ///< what happened, in words
};

}  // namespace nimble
