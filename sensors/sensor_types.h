#pragma once
/// The plain sensor data both sides of the rig exchange: what the emulated sensors (sensors/,
/// on the truth side) produce and what the estimator (estimator/, under test) consumes. Each
/// mirrors an LCM message (lcmtypes/); the processes convert at the bus. No model, no config,
/// no dependency on either side.
///
/// Axes as in lcmtypes/README.md: body x forward, y right wing, z down; world frame NED.

#include <cstdint>

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

}  // namespace nimble
