#pragma once
/// Attitude representations and conversions used by the sensors, the estimator and their tests.
///
/// Conventions (those of lcmtypes/README.md):
///  - Body axes x forward, y right wing, z down; world frame NED.
///  - Euler angles are ZYX (yaw psi, then pitch theta, then roll phi), stored [phi theta psi] in rad:
///      R_body_to_world = Rz(psi) * Ry(theta) * Rx(phi),
///    so that v_world = R_body_to_world * v_body.
///  - Quaternions are Hamilton, unit norm, and rotate body vectors into the world frame:
///    v_world = q_body_to_world * v_body (Eigen's Quaterniond has exactly this meaning).
///    On the wire they are stored [w x y z].
///  - Returned Euler angles have phi, psi in (-pi, pi] and theta in [-pi/2, pi/2].
///
/// Gimbal lock: at theta = +-pi/2 roll and yaw are not separable. When
/// |cos(theta)| < kGimbalLockCosThreshold the conversion to Euler angles sets phi = 0 and puts the
/// whole rotation about the vertical into psi; the returned angles still reproduce the rotation
/// (to about the threshold), only the split between phi and psi is a convention.

#include <array>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace nimble {

/// |cos(theta)| below which euler_zyx_from_rotation() treats the attitude as gimbal-locked [-].
constexpr double kGimbalLockCosThreshold = 1e-7;

/// Wraps an angle into (-pi, pi] [rad]. Non-finite input is returned unchanged.
double wrap_angle_rad(double angle_rad);

/// R_body_to_world = Rz(psi) Ry(theta) Rx(phi) from euler_rad = [phi theta psi] [rad].
Eigen::Matrix3d rotation_from_euler_zyx(const Eigen::Vector3d& euler_rad);

/// Unit quaternion q_body_to_world from ZYX Euler angles [phi theta psi] [rad]; w >= 0.
Eigen::Quaterniond quaternion_from_euler_zyx(const Eigen::Vector3d& euler_rad);

/// ZYX Euler angles [phi theta psi] [rad] of a rotation matrix R_body_to_world (assumed orthonormal).
/// Gimbal lock handled as described at the top of this header.
Eigen::Vector3d euler_zyx_from_rotation(const Eigen::Matrix3d& R_body_to_world);

/// ZYX Euler angles [phi theta psi] [rad] of a quaternion q_body_to_world (normalised internally).
Eigen::Vector3d euler_zyx_from_quaternion(const Eigen::Quaterniond& q_body_to_world);

/// Unit quaternion of a rotation matrix R_body_to_world, sign chosen so that w >= 0.
Eigen::Quaterniond quaternion_from_rotation(const Eigen::Matrix3d& R_body_to_world);

/// Quaternion from wire order [w x y z]; normalised. A zero or non-finite input gives identity.
Eigen::Quaterniond quaternion_from_wxyz(const std::array<double, 4>& wxyz);

/// Wire order [w x y z] of a quaternion.
std::array<double, 4> quaternion_to_wxyz(const Eigen::Quaterniond& q);

/// Skew-symmetric matrix [v]x such that [v]x * a = v x a.
Eigen::Matrix3d skew(const Eigen::Vector3d& v);

/// Unit quaternion of a rotation vector (axis times angle) [rad]; exact for any angle.
Eigen::Quaterniond quaternion_exp(const Eigen::Vector3d& rotation_vector_rad);

/// Rotation vector [rad] (angle in [0, pi]) of a unit quaternion; inverse of quaternion_exp.
Eigen::Vector3d quaternion_log(const Eigen::Quaterniond& q);

/// Matrix W(phi, theta) of the Euler kinematics: d/dt [phi theta psi] = W * omega_body_radps.
///   W = [1  sin(phi) tan(theta)  cos(phi) tan(theta)]
///       [0  cos(phi)             -sin(phi)          ]
///       [0  sin(phi)/cos(theta)  cos(phi)/cos(theta)]
/// Singular at theta = +-pi/2.
Eigen::Matrix3d euler_rate_matrix(double phi_rad, double theta_rad);

}  // namespace nimble
