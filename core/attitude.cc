#include "core/attitude.h"

#include <cmath>

namespace nimble {

double wrap_angle_rad(double angle_rad) {
  if (!std::isfinite(angle_rad)) return angle_rad;
  if (angle_rad > -M_PI && angle_rad <= M_PI) return angle_rad;
  double wrapped = std::remainder(angle_rad, 2.0 * M_PI);  // in [-pi, pi]
  if (wrapped <= -M_PI) wrapped += 2.0 * M_PI;
  return wrapped;
}

Eigen::Matrix3d rotation_from_euler_zyx(const Eigen::Vector3d& euler_rad) {
  const double sf = std::sin(euler_rad[0]), cf = std::cos(euler_rad[0]);
  const double st = std::sin(euler_rad[1]), ct = std::cos(euler_rad[1]);
  const double sp = std::sin(euler_rad[2]), cp = std::cos(euler_rad[2]);
  Eigen::Matrix3d R;
  R << cp * ct, cp * st * sf - sp * cf, cp * st * cf + sp * sf, sp * ct, sp * st * sf + cp * cf, sp * st * cf - cp * sf,
      -st, ct * sf, ct * cf;
  return R;
}

Eigen::Quaterniond quaternion_from_euler_zyx(const Eigen::Vector3d& euler_rad) {
  const double hf = 0.5 * euler_rad[0], ht = 0.5 * euler_rad[1], hp = 0.5 * euler_rad[2];
  const double sf = std::sin(hf), cf = std::cos(hf);
  const double st = std::sin(ht), ct = std::cos(ht);
  const double sp = std::sin(hp), cp = std::cos(hp);
  // q = qz(psi) * qy(theta) * qx(phi)
  Eigen::Quaterniond q(cp * ct * cf + sp * st * sf, cp * ct * sf - sp * st * cf, cp * st * cf + sp * ct * sf,
                       sp * ct * cf - cp * st * sf);
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();
  return q.normalized();
}

Eigen::Vector3d euler_zyx_from_rotation(const Eigen::Matrix3d& R) {
  // R(2,0) = -sin(theta); R(2,1) = cos(theta) sin(phi); R(2,2) = cos(theta) cos(phi);
  // R(1,0) = sin(psi) cos(theta); R(0,0) = cos(psi) cos(theta).
  const double cos_theta = std::hypot(R(2, 1), R(2, 2));
  const double theta = std::atan2(-R(2, 0), cos_theta);
  double phi = 0.0, psi = 0.0;
  if (cos_theta < kGimbalLockCosThreshold) {
    // theta = +-pi/2: with phi = 0, R(0,1) = -sin(psi) and R(1,1) = cos(psi) for both signs.
    phi = 0.0;
    psi = std::atan2(-R(0, 1), R(1, 1));
  } else {
    phi = std::atan2(R(2, 1), R(2, 2));
    psi = std::atan2(R(1, 0), R(0, 0));
  }
  return Eigen::Vector3d(wrap_angle_rad(phi), theta, wrap_angle_rad(psi));
}

Eigen::Vector3d euler_zyx_from_quaternion(const Eigen::Quaterniond& q_body_to_world) {
  return euler_zyx_from_rotation(q_body_to_world.normalized().toRotationMatrix());
}

Eigen::Quaterniond quaternion_from_rotation(const Eigen::Matrix3d& R_body_to_world) {
  Eigen::Quaterniond q(R_body_to_world);
  q.normalize();
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();
  return q;
}

Eigen::Quaterniond quaternion_from_wxyz(const std::array<double, 4>& wxyz) {
  Eigen::Quaterniond q(wxyz[0], wxyz[1], wxyz[2], wxyz[3]);
  const double n = q.norm();
  if (!std::isfinite(n) || n < 1e-12) return Eigen::Quaterniond::Identity();
  q.coeffs() /= n;
  return q;
}

std::array<double, 4> quaternion_to_wxyz(const Eigen::Quaterniond& q) { return {q.w(), q.x(), q.y(), q.z()}; }

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d S;
  S << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return S;
}

Eigen::Quaterniond quaternion_exp(const Eigen::Vector3d& rotation_vector_rad) {
  const double angle = rotation_vector_rad.norm();
  const double half = 0.5 * angle;
  // sin(half)/angle with its series near zero.
  const double k = angle < 1e-8 ? 0.5 - angle * angle / 48.0 : std::sin(half) / angle;
  Eigen::Quaterniond q(std::cos(half), k * rotation_vector_rad.x(), k * rotation_vector_rad.y(),
                       k * rotation_vector_rad.z());
  return q.normalized();
}

Eigen::Vector3d quaternion_log(const Eigen::Quaterniond& q_in) {
  Eigen::Quaterniond q = q_in.normalized();
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();
  const Eigen::Vector3d v = q.vec();
  const double s = v.norm();
  if (s < 1e-12) return 2.0 * v;
  const double angle = 2.0 * std::atan2(s, q.w());
  return v * (angle / s);
}

Eigen::Matrix3d euler_rate_matrix(double phi_rad, double theta_rad) {
  const double sf = std::sin(phi_rad), cf = std::cos(phi_rad);
  const double ct = std::cos(theta_rad), tt = std::tan(theta_rad);
  Eigen::Matrix3d W;
  W << 1.0, sf * tt, cf * tt, 0.0, cf, -sf, 0.0, sf / ct, cf / ct;
  return W;
}

}  // namespace nimble
