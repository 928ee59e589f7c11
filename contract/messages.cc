/// The conversions written out: the IMU sample, the motion-capture pose and the truth, whose
/// values hold vectors and a quaternion where their messages hold arrays (the other pairs are
/// bound through the generated list in messages.h).

#include "contract/messages.h"

namespace nimble::contract {

namespace {

Eigen::Vector3d vec3(const double (&a)[3]) { return Eigen::Vector3d(a[0], a[1], a[2]); }

void put(const Eigen::Vector3d& v, double (&a)[3]) {
  for (int i = 0; i < 3; ++i) a[i] = v[i];
}

}  // namespace

imu_sample_t to_message(const ImuSample& s) {
  imu_sample_t m{};
  m.utime = s.utime;
  m.seq = s.seq;
  put(s.gyro_radps, m.gyro_radps);
  put(s.accel_mps2, m.accel_mps2);
  m.temperature_degc = s.temperature_degc;
  m.saturation_flags = static_cast<int8_t>(s.saturation_flags);
  return m;
}

ImuSample from_message(const imu_sample_t& m) {
  ImuSample s;
  s.utime = m.utime;
  s.seq = m.seq;
  s.gyro_radps = vec3(m.gyro_radps);
  s.accel_mps2 = vec3(m.accel_mps2);
  s.temperature_degc = m.temperature_degc;
  s.saturation_flags = static_cast<std::uint8_t>(m.saturation_flags);
  return s;
}

mocap_pose_t to_message(const MocapPose& p) {
  mocap_pose_t m{};
  m.utime = p.utime;
  m.seq = p.seq;
  m.frame_number = p.frame_number;
  m.latency_us = p.latency_us;
  m.rigid_body_id = p.rigid_body_id;
  put(p.position_ned_m, m.position_m);
  m.quaternion_wxyz[0] = p.q_body_to_ned.w();
  m.quaternion_wxyz[1] = p.q_body_to_ned.x();
  m.quaternion_wxyz[2] = p.q_body_to_ned.y();
  m.quaternion_wxyz[3] = p.q_body_to_ned.z();
  m.tracking_valid = p.tracking_valid;
  m.mean_marker_error_m = p.mean_marker_error_m;
  m.num_markers = p.num_markers;
  return m;
}

MocapPose from_message(const mocap_pose_t& m) {
  MocapPose p;
  p.utime = m.utime;
  p.seq = m.seq;
  p.frame_number = m.frame_number;
  p.latency_us = m.latency_us;
  p.rigid_body_id = m.rigid_body_id;
  p.position_ned_m = vec3(m.position_m);
  p.q_body_to_ned =
      Eigen::Quaterniond(m.quaternion_wxyz[0], m.quaternion_wxyz[1], m.quaternion_wxyz[2], m.quaternion_wxyz[3]);
  p.tracking_valid = m.tracking_valid;
  p.mean_marker_error_m = m.mean_marker_error_m;
  p.num_markers = m.num_markers;
  p.publish_utime = m.utime + m.latency_us;
  return p;
}

truth_state_t to_message(const Truth& t, int64_t utime, int64_t seq, int64_t step) {
  truth_state_t m{};
  m.utime = utime;
  m.seq = seq;
  m.step = step;
  put(t.position_ned_m, m.position_ned_m);
  put(t.velocity_body_mps, m.velocity_body_mps);
  put(t.euler_rad, m.euler_rad);
  put(t.omega_body_radps, m.omega_body_radps);
  put(t.specific_force_body_mps2, m.specific_force_body_mps2);
  put(t.angular_accel_body_radps2, m.angular_accel_body_radps2);
  for (int i = 0; i < 4; ++i) m.quaternion_wxyz[i] = t.quaternion_wxyz[i];
  m.flap_freq_left_radps = t.flap_freq_left_radps;
  m.flap_freq_right_radps = t.flap_freq_right_radps;
  m.delta_f_radps = t.delta_f_radps;
  m.throttle_pct = t.throttle_pct;
  m.dihedral_rad = t.dihedral_rad;
  m.wing_root_rad = t.wing_root_rad;
  return m;
}

Truth from_message(const truth_state_t& m) {
  Truth t;
  t.time_s = static_cast<double>(m.utime) / 1e6;
  t.position_ned_m = vec3(m.position_ned_m);
  t.velocity_body_mps = vec3(m.velocity_body_mps);
  t.euler_rad = vec3(m.euler_rad);
  t.quaternion_wxyz =
      Eigen::Vector4d(m.quaternion_wxyz[0], m.quaternion_wxyz[1], m.quaternion_wxyz[2], m.quaternion_wxyz[3]);
  t.omega_body_radps = vec3(m.omega_body_radps);
  t.specific_force_body_mps2 = vec3(m.specific_force_body_mps2);
  t.angular_accel_body_radps2 = vec3(m.angular_accel_body_radps2);
  t.flap_freq_left_radps = m.flap_freq_left_radps;
  t.flap_freq_right_radps = m.flap_freq_right_radps;
  t.delta_f_radps = m.delta_f_radps;
  t.throttle_pct = m.throttle_pct;
  t.dihedral_rad = m.dihedral_rad;
  t.wing_root_rad = m.wing_root_rad;
  return t;
}

}  // namespace nimble::contract
