#include "truth_trajectory.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include "core/attitude.h"

namespace nimble {
namespace {

/// Rate of a raised-cosine step of height `height` lasting `ramp` centred at `centre`.
double ramp_rate(double t, double centre, double ramp, double height) {
  const double s = (t - centre) / ramp + 0.5;  // 0 .. 1 over the ramp
  if (s <= 0.0 || s >= 1.0) return 0.0;
  return height * (M_PI / (2.0 * ramp)) * std::sin(M_PI * s);
}

Eigen::Quaterniond to_quaternion(const Eigen::Vector4d& wxyz) {
  return Eigen::Quaterniond(wxyz[0], wxyz[1], wxyz[2], wxyz[3]).normalized();
}

}  // namespace

TruthProfile make_roll_doublet_profile(std::uint64_t seed, double duration_s) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  auto between = [&](double lo, double hi) { return lo + (hi - lo) * uni(rng); };
  TruthProfile p;
  double t = 1.0;
  while (true) {
    RollDoublet d;
    const double amplitude = between(20.0, 30.0) * kDegToRad;
    const double peak_rate = between(6.0, 10.0);
    d.ramp_s = amplitude * M_PI / peak_rate;
    d.period_s = std::max(2.0 * d.ramp_s, between(0.35, 0.9));
    d.amplitude_rad = uni(rng) < 0.5 ? amplitude : -amplitude;
    d.start_s = t;
    if (t + d.period_s + d.ramp_s > duration_s - 0.5) break;
    p.roll_doublets.push_back(d);
    t += d.period_s + d.ramp_s + between(0.6, 1.5);
  }
  p.pitch_rate_amplitude_radps = between(0.2, 0.4);
  p.pitch_rate_frequency_hz = between(0.5, 1.0);
  p.pitch_rate_phase_rad = between(0.0, 2.0 * M_PI);
  p.yaw_rate_amplitude_radps = between(0.2, 0.5);
  p.yaw_rate_frequency_hz = between(0.2, 0.6);
  p.yaw_rate_phase_rad = between(0.0, 2.0 * M_PI);
  p.forward_accel_amplitude_mps2 = between(0.2, 0.8);
  p.forward_accel_frequency_hz = between(0.2, 0.6);
  p.forward_accel_phase_rad = between(0.0, 2.0 * M_PI);
  p.initial_euler_rad = Eigen::Vector3d(between(-0.05, 0.05), between(-0.05, 0.05), between(-M_PI, M_PI));
  return p;
}

ImuTruthInput TruthSample::imu_input() const {
  ImuTruthInput in;
  in.utime = utime;
  in.omega_body_radps = omega_body_radps;
  in.specific_force_body_mps2 = specific_force_body_mps2;
  in.flap_freq_left_radps = flap_freq_left_radps;
  in.flap_freq_right_radps = flap_freq_right_radps;
  return in;
}

MocapTruthInput TruthSample::mocap_input() const {
  MocapTruthInput in;
  in.utime = utime;
  in.position_ned_m = position_ned_m;
  in.q_body_to_ned = q_body_to_ned;
  return in;
}

TruthTrajectory::TruthTrajectory(const TruthProfile& profile, std::int64_t start_utime)
    : profile_(profile), t_s_(1e-6 * static_cast<double>(start_utime)), utime_(start_utime) {
  for (const RollDoublet& d : profile_.roll_doublets) {
    if (!(d.ramp_s > 0.0) || d.ramp_s > 0.5 * d.period_s + 1e-12) {
      throw std::invalid_argument("RollDoublet: need 0 < ramp_s <= period_s / 2");
    }
  }
  if (!(profile_.max_step_s > 0.0)) throw std::invalid_argument("TruthProfile.max_step_s must be > 0");
  const Eigen::Quaterniond q0 = quaternion_from_euler_zyx(profile_.initial_euler_rad);
  q_wxyz_ << q0.w(), q0.x(), q0.y(), q0.z();
  v_b_ = profile_.initial_velocity_body_mps;
  r_ned_ = profile_.initial_position_ned_m;
  fill_sample();
}

Eigen::Vector3d TruthTrajectory::omega_at(double t) const {
  double p = 0.0;
  for (const RollDoublet& d : profile_.roll_doublets) {
    const double c = d.start_s + 0.5 * d.ramp_s;
    p += ramp_rate(t, c, d.ramp_s, d.amplitude_rad);
    p += ramp_rate(t, c + 0.5 * d.period_s, d.ramp_s, -2.0 * d.amplitude_rad);
    p += ramp_rate(t, c + d.period_s, d.ramp_s, d.amplitude_rad);
  }
  const double q = profile_.pitch_rate_amplitude_radps *
                   std::sin(2.0 * M_PI * profile_.pitch_rate_frequency_hz * t + profile_.pitch_rate_phase_rad);
  const double r = profile_.yaw_rate_amplitude_radps *
                   std::sin(2.0 * M_PI * profile_.yaw_rate_frequency_hz * t + profile_.yaw_rate_phase_rad);
  return Eigen::Vector3d(p, q, r);
}

Eigen::Vector3d TruthTrajectory::specific_force(double t, const Eigen::Quaterniond& q,
                                                const Eigen::Vector3d& v_b) const {
  const Eigen::Matrix3d R = q.toRotationMatrix();
  const double g = profile_.gravity_mps2;
  const double fx =
      -profile_.drag_u_per_s * v_b.x() +
      profile_.forward_accel_amplitude_mps2 *
          std::sin(2.0 * M_PI * profile_.forward_accel_frequency_hz * t + profile_.forward_accel_phase_rad);
  const double fy = -profile_.drag_v_per_s * v_b.y();
  const double v_down = R.row(2).dot(v_b);
  // Thrust along -z_b chosen so that the NED down acceleration is -damping * v_down.
  const double r22 = std::max(R(2, 2), 0.5);
  const double thrust = (g + R(2, 0) * fx + R(2, 1) * fy + profile_.vertical_damping_per_s * v_down) / r22;
  return Eigen::Vector3d(fx, fy, -thrust);
}

TruthTrajectory::Derivative TruthTrajectory::derivative(double t, const Eigen::Vector4d& q_wxyz,
                                                        const Eigen::Vector3d& v_b) const {
  const Eigen::Quaterniond q = to_quaternion(q_wxyz);
  const Eigen::Vector3d w = omega_at(t);
  Derivative d;
  // q_dot = 1/2 q * (0, w)
  const double qw = q_wxyz[0], qx = q_wxyz[1], qy = q_wxyz[2], qz = q_wxyz[3];
  d.q_dot << 0.5 * (-qx * w.x() - qy * w.y() - qz * w.z()), 0.5 * (qw * w.x() + qy * w.z() - qz * w.y()),
      0.5 * (qw * w.y() - qx * w.z() + qz * w.x()), 0.5 * (qw * w.z() + qx * w.y() - qy * w.x());
  const Eigen::Matrix3d R = q.toRotationMatrix();
  const Eigen::Vector3d gravity_body = R.transpose() * Eigen::Vector3d(0.0, 0.0, profile_.gravity_mps2);
  d.v_dot = specific_force(t, q, v_b) + gravity_body - w.cross(v_b);
  d.r_dot = R * v_b;
  return d;
}

void TruthTrajectory::rk4_step(double h) {
  const Derivative k1 = derivative(t_s_, q_wxyz_, v_b_);
  const Derivative k2 = derivative(t_s_ + 0.5 * h, q_wxyz_ + 0.5 * h * k1.q_dot, v_b_ + 0.5 * h * k1.v_dot);
  const Derivative k3 = derivative(t_s_ + 0.5 * h, q_wxyz_ + 0.5 * h * k2.q_dot, v_b_ + 0.5 * h * k2.v_dot);
  const Derivative k4 = derivative(t_s_ + h, q_wxyz_ + h * k3.q_dot, v_b_ + h * k3.v_dot);
  q_wxyz_ += h / 6.0 * (k1.q_dot + 2.0 * k2.q_dot + 2.0 * k3.q_dot + k4.q_dot);
  v_b_ += h / 6.0 * (k1.v_dot + 2.0 * k2.v_dot + 2.0 * k3.v_dot + k4.v_dot);
  r_ned_ += h / 6.0 * (k1.r_dot + 2.0 * k2.r_dot + 2.0 * k3.r_dot + k4.r_dot);
  q_wxyz_.normalize();
  t_s_ += h;
}

const TruthSample& TruthTrajectory::advance_to(std::int64_t utime) {
  if (utime <= utime_) return sample_;
  const double t_end = 1e-6 * static_cast<double>(utime);
  const double span = t_end - t_s_;
  const int steps = std::max(1, static_cast<int>(std::ceil(span / profile_.max_step_s - 1e-9)));
  const double h = span / steps;
  for (int i = 0; i < steps; ++i) rk4_step(h);
  t_s_ = t_end;
  utime_ = utime;
  fill_sample();
  return sample_;
}

void TruthTrajectory::fill_sample() {
  const Eigen::Quaterniond q = to_quaternion(q_wxyz_);
  sample_.utime = utime_;
  sample_.position_ned_m = r_ned_;
  sample_.velocity_body_mps = v_b_;
  sample_.q_body_to_ned = q.w() < 0.0 ? Eigen::Quaterniond(-q.coeffs()) : q;
  sample_.euler_rad = euler_zyx_from_quaternion(q);
  sample_.omega_body_radps = omega_at(t_s_);
  sample_.specific_force_body_mps2 = specific_force(t_s_, q, v_b_);
  const double h = 1e-5;
  sample_.angular_accel_body_radps2 = (omega_at(t_s_ + h) - omega_at(t_s_ - h)) / (2.0 * h);
  sample_.flap_freq_left_radps = profile_.flap_frequency_radps;
  sample_.flap_freq_right_radps = profile_.flap_frequency_radps;
}

}  // namespace nimble
