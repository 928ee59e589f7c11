#pragma once
/// Turns a stream of motion-capture frames into EKF measurements
/// z = [phi_m theta_m psi_m (u* v* w*)] (thesis Eq 8.1).
///
/// Attitude: the ZYX Euler angles of each tracked frame's quaternion; every tracked frame's attitude
/// is used exactly once.
///
/// Body velocity u* v* w* (thesis: "determined by derivation of the position data"): a central
/// difference over a span of d frames (d even), referred to the middle frame c:
///   v_ned(t_c) = (r(t_{c+d/2}) - r(t_{c-d/2})) / (t_{c+d/2} - t_{c-d/2}),
///   [u* v* w*] = R_body_to_ned(q_c)^T v_ned(t_c),
/// where q_c is the measured attitude of the middle frame. The difference is exact for positions
/// quadratic in time; its truncation error is v''(t_c) (d T / 2)^2 / 6 (T frame period). With
/// position noise sigma per axis its noise is sqrt(2) sigma / (d T) per axis, plus |v| times the
/// attitude noise from the rotation into body axes.
/// Pairs start at frames s with s mod m = 0 (m = stride). With d mod m != 0 no frame position is
/// used in two pairs, so successive velocity measurements have independent errors: white
/// measurement noise, as the Kalman filter assumes. (Overlapping differences would give noise
/// that cancels over time and an EKF that overestimates its velocity error.) Velocity therefore
/// comes at frame_rate / m, attitude at the full frame rate.
/// The measurement at a middle frame is held until its end frame arrives (d/2 frames later); it
/// carries the middle frame's timestamp, so the EKF applies it in the past (see ekf.h).
/// If the start or end frame is missing or occluded, the middle frame yields attitude only.

#include <cstdint>
#include <deque>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/rig_values.h"

namespace nimble {

/// One EKF measurement built from motion capture.
struct PoseMeasurement {
  /// Rig time the measurement refers to (mid-exposure of its frame) [us].
  std::int64_t utime = 0;
  /// Measured ZYX Euler angles [rad], order phi theta psi.
  Eigen::Vector3d euler_rad = Eigen::Vector3d::Zero();
  /// True if velocity_body_mps holds a measurement (6-dof measurement), false for attitude only.
  bool has_velocity = false;
  /// Measured velocity relative to the world in body axes [m/s], order u v w.
  Eigen::Vector3d velocity_body_mps = Eigen::Vector3d::Zero();
  /// Mid-exposure times of the start and end frames of the difference [us]. The measured velocity
  /// is the mean of the velocity over this window (see EkfConfig); start >= end (both 0 by
  /// default) means an instantaneous velocity.
  std::int64_t velocity_window_start_utime = 0;
  std::int64_t velocity_window_end_utime = 0;
  /// Frame number of the mocap frame it comes from [-]; -1 if not from a frame.
  std::int64_t frame_number = -1;
};

/// Parameters of the velocity differentiator.
struct VelocityDifferentiatorConfig {
  /// Span d of the central difference in frames [-], even, >= 2. Default 12 (60 ms at 200 Hz): with
  /// the default marker noise (sigma 0.533 mm) its noise is sqrt(2) 0.533 mm / 60 ms = 0.0126 m/s,
  /// the level of thesis Eq 8.2 R for u v w (sigma 0.0106 to 0.0147 m/s).
  int span_frames = 12;
  /// Stride m between pair starts in frames [-], >= 1, with span_frames mod m != 0 (independent
  /// pairs, see header). Default 5: velocity at 40 Hz with 200 Hz frames.
  int stride_frames = 5;
};

/// Checks a VelocityDifferentiatorConfig.
/// @throws std::invalid_argument naming the field, its value and the allowed range.
void validate(const VelocityDifferentiatorConfig& config);

/// 1-sigma per axis of the differentiated velocity due to position noise [m/s]:
/// sqrt(2) position_sigma_m / span_s.
double differentiated_velocity_sigma_mps(double position_sigma_m, double span_s);

/// Builds PoseMeasurement from MocapPose frames (see the top of this header). Transport-free.
class MocapMeasurementBuilder {
 public:
  /// @throws std::invalid_argument if `config` is invalid.
  explicit MocapMeasurementBuilder(const VelocityDifferentiatorConfig& config);

  /// Consumes one frame (frames must come in increasing frame_number; others are dropped and
  /// counted) and returns the measurements that became complete, in time order. Never throws.
  std::vector<PoseMeasurement> push(const MocapPose& pose);

  /// Returns the held middle frames as attitude-only measurements (end of stream).
  std::vector<PoseMeasurement> flush();

  /// Frames consumed [-].
  std::int64_t frames_received() const { return frames_received_; }
  /// Frames with tracking_valid false [-].
  std::int64_t frames_invalid() const { return frames_invalid_; }
  /// Frames never received (gaps in frame_number) [-].
  std::int64_t frames_missing() const { return frames_missing_; }
  /// Frames dropped because their frame_number did not increase [-].
  std::int64_t frames_out_of_order() const { return frames_out_of_order_; }
  /// Measurements emitted with velocity [-].
  std::int64_t velocity_measurements() const { return velocity_measurements_; }
  /// Measurements emitted with attitude only [-].
  std::int64_t attitude_only_measurements() const { return attitude_only_measurements_; }
  /// The configuration in use.
  const VelocityDifferentiatorConfig& config() const { return config_; }

 private:
  struct Frame {
    std::int64_t frame_number = 0;
    std::int64_t utime = 0;
    bool valid = false;
    Eigen::Vector3d position_ned_m = Eigen::Vector3d::Zero();
    Eigen::Quaterniond q_body_to_ned = Eigen::Quaterniond::Identity();
  };
  bool is_middle(std::int64_t n) const;
  bool is_end(std::int64_t n) const;
  const Frame* find(std::int64_t frame_number) const;
  PoseMeasurement attitude_only(const Frame& frame);

  VelocityDifferentiatorConfig config_;
  std::deque<Frame> recent_;  // frames within the last span, increasing frame number
  std::deque<Frame> held_;    // tracked middle frames waiting for their end frame
  bool have_last_ = false;
  std::int64_t last_frame_number_ = 0;
  std::int64_t frames_received_ = 0, frames_invalid_ = 0, frames_missing_ = 0, frames_out_of_order_ = 0;
  std::int64_t velocity_measurements_ = 0, attitude_only_measurements_ = 0;
};

}  // namespace nimble
