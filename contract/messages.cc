#include "contract/messages.h"

namespace nimble::contract {

namespace {

Eigen::Vector3d vec3(const double (&a)[3]) { return Eigen::Vector3d(a[0], a[1], a[2]); }

void put(const Eigen::Vector3d& v, double (&a)[3]) {
  for (int i = 0; i < 3; ++i) a[i] = v[i];
}

// One assignment of a value's field to its message's field or back: the same type, a number of
// another width (LCM's boolean is int8_t), or a fixed-size vector and its array.
template <class To, class From>
void assign(To& to, const From& from) {
  to = static_cast<To>(from);
}
template <int N>
void assign(Eigen::Matrix<double, N, 1>& to, const double (&from)[N]) {
  for (int i = 0; i < N; ++i) to[i] = from[i];
}
template <int N>
void assign(double (&to)[N], const Eigen::Matrix<double, N, 1>& from) {
  for (int i = 0; i < N; ++i) to[i] = from[i];
}

// Each pair's fields, listed once for both directions: a Bind functor's bind(value, message,
// copy) calls copy(value.f, message.f) for every field f. to_message() copies message <- value,
// from_message() value <- message.
struct ToMessage {
  template <class V, class M>
  void operator()(const V& value_field, M& message_field) const {
    assign(message_field, value_field);
  }
};
struct FromMessage {
  template <class V, class M>
  void operator()(V& value_field, const M& message_field) const {
    assign(value_field, message_field);
  }
};

template <class Message, class Value, class Bind>
Message message_of(const Value& v, Bind bind) {
  Message m{};
  bind(v, m, ToMessage{});
  return m;
}

template <class Value, class Message, class Bind>
Value value_of(const Message& m, Bind bind) {
  Value v;
  bind(v, m, FromMessage{});
  return v;
}

struct BindCommand {
  template <class V, class M, class Copy>
  void operator()(V& v, M& m, Copy copy) const {
    copy(v.utime, m.utime);
    copy(v.seq, m.seq);
    copy(v.mode, m.mode);
    copy(v.flap_freq_left_radps, m.flap_freq_left_radps);
    copy(v.flap_freq_right_radps, m.flap_freq_right_radps);
    copy(v.delta_f_radps, m.delta_f_radps);
    copy(v.flap_freq_collective_radps, m.flap_freq_collective_radps);
    copy(v.throttle_pct, m.throttle_pct);
    copy(v.dihedral_rad, m.dihedral_rad);
    copy(v.wing_root_rad, m.wing_root_rad);
    copy(v.input_utime, m.input_utime);
    copy(v.rolling_counter, m.rolling_counter);
    copy(v.source, m.source);
  }
};

struct BindFeedback {
  template <class V, class M, class Copy>
  void operator()(V& v, M& m, Copy copy) const {
    copy(v.utime, m.utime);
    copy(v.seq, m.seq);
    copy(v.flap_freq_left_radps, m.flap_freq_left_radps);
    copy(v.flap_freq_right_radps, m.flap_freq_right_radps);
    copy(v.delta_f_radps, m.delta_f_radps);
    copy(v.dihedral_rad, m.dihedral_rad);
    copy(v.wing_root_rad, m.wing_root_rad);
    copy(v.throttle_pct, m.throttle_pct);
    copy(v.cmd_seq, m.cmd_seq);
    copy(v.cmd_age_us, m.cmd_age_us);
    copy(v.safe_state, m.safe_state);
  }
};

struct BindSetpoint {
  template <class V, class M, class Copy>
  void operator()(V& v, M& m, Copy copy) const {
    copy(v.utime, m.utime);
    copy(v.seq, m.seq);
    copy(v.roll_sp_rad, m.roll_sp_rad);
    copy(v.pitch_sp_rad, m.pitch_sp_rad);
    copy(v.yaw_rate_sp_radps, m.yaw_rate_sp_radps);
    copy(v.throttle_pct, m.throttle_pct);
    copy(v.throttle_factor, m.throttle_factor);
    copy(v.manoeuvre, m.manoeuvre);
    copy(v.segment_index, m.segment_index);
    copy(v.segment_name, m.segment_name);
    copy(v.gain_set, m.gain_set);
  }
};

struct BindEstimate {
  template <class V, class M, class Copy>
  void operator()(V& v, M& m, Copy copy) const {
    copy(v.utime, m.utime);
    copy(v.seq, m.seq);
    copy(v.imu_utime, m.imu_utime);
    copy(v.euler_rad, m.euler_rad);
    copy(v.velocity_body_mps, m.velocity_body_mps);
    copy(v.gyro_bias_radps, m.gyro_bias_radps);
    copy(v.accel_bias_mps2, m.accel_bias_mps2);
    copy(v.omega_body_radps, m.omega_body_radps);
    copy(v.cov_diag, m.cov_diag);
    copy(v.poses_accepted, m.poses_accepted);
    copy(v.poses_rejected, m.poses_rejected);
    copy(v.poses_missing, m.poses_missing);
    copy(v.last_nis, m.last_nis);
    copy(v.poses_too_old, m.poses_too_old);
    copy(v.poses_too_new, m.poses_too_new);
    copy(v.velocity_windows_uncovered, m.velocity_windows_uncovered);
    copy(v.imu_rejected, m.imu_rejected);
    copy(v.imu_gaps, m.imu_gaps);
  }
};

struct BindStatus {
  template <class V, class M, class Copy>
  void operator()(V& v, M& m, Copy copy) const {
    copy(v.utime, m.utime);
    copy(v.seq, m.seq);
    copy(v.gain_set, m.gain_set);
    copy(v.kp, m.kp);
    copy(v.kd, m.kd);
    copy(v.roll_ref_rad, m.roll_ref_rad);
    copy(v.roll_rate_ref_radps, m.roll_rate_ref_radps);
    copy(v.roll_error_rad, m.roll_error_rad);
    copy(v.roll_cmd_norm, m.roll_cmd_norm);
    copy(v.pitch_cmd_norm, m.pitch_cmd_norm);
    copy(v.delta_f_cmd_radps, m.delta_f_cmd_radps);
    copy(v.throttle_pct, m.throttle_pct);
    copy(v.saturated, m.saturated);
    copy(v.input_source, m.input_source);
    copy(v.input_age_us, m.input_age_us);
    copy(v.failsafe, m.failsafe);
  }
};

struct BindCanHealth {
  template <class V, class M, class Copy>
  void operator()(V& v, M& m, Copy copy) const {
    copy(v.utime, m.utime);
    copy(v.seq, m.seq);
    copy(v.process, m.process);
    copy(v.role, m.role);
    copy(v.interface_name, m.interface_name);
    copy(v.messages_to_can, m.messages_to_can);
    copy(v.messages_to_lcm, m.messages_to_lcm);
    copy(v.frames_sent, m.frames_sent);
    copy(v.frames_received, m.frames_received);
    copy(v.send_enobufs, m.send_enobufs);
    copy(v.send_retries, m.send_retries);
    copy(v.send_dropped, m.send_dropped);
    copy(v.receive_dropped, m.receive_dropped);
    copy(v.rejected_unknown_id, m.rejected_unknown_id);
    copy(v.rejected_wrong_length, m.rejected_wrong_length);
    copy(v.rejected_bad_checksum, m.rejected_bad_checksum);
    copy(v.rejected_stale_counter, m.rejected_stale_counter);
    copy(v.rejected_out_of_range, m.rejected_out_of_range);
    copy(v.counter_gaps, m.counter_gaps);
    copy(v.saturated_values, m.saturated_values);
    copy(v.error_frames, m.error_frames);
    copy(v.bus_state, m.bus_state);
    copy(v.last_error, m.last_error);
    copy(v.candump_file, m.candump_file);
    copy(v.candump_lines, m.candump_lines);
    copy(v.fd, m.fd);
    copy(v.fd_frames_sent, m.fd_frames_sent);
    copy(v.fd_frames_received, m.fd_frames_received);
  }
};

struct BindFault {
  template <class V, class M, class Copy>
  void operator()(V& v, M& m, Copy copy) const {
    copy(v.utime, m.utime);
    copy(v.seq, m.seq);
    copy(v.rig_utime, m.rig_utime);
    copy(v.process, m.process);
    copy(v.severity, m.severity);
    copy(v.code, m.code);
    copy(v.channel, m.channel);
    copy(v.message, m.message);
  }
};

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

actuator_command_t to_message(const ActuatorCommand& v) { return message_of<actuator_command_t>(v, BindCommand{}); }
ActuatorCommand from_message(const actuator_command_t& m) { return value_of<ActuatorCommand>(m, BindCommand{}); }

actuator_feedback_t to_message(const ActuatorFeedback& v) { return message_of<actuator_feedback_t>(v, BindFeedback{}); }
ActuatorFeedback from_message(const actuator_feedback_t& m) { return value_of<ActuatorFeedback>(m, BindFeedback{}); }

attitude_setpoint_t to_message(const AttitudeSetpoint& v) { return message_of<attitude_setpoint_t>(v, BindSetpoint{}); }
AttitudeSetpoint from_message(const attitude_setpoint_t& m) { return value_of<AttitudeSetpoint>(m, BindSetpoint{}); }

estimator_state_t to_message(const Estimate& v) { return message_of<estimator_state_t>(v, BindEstimate{}); }
Estimate from_message(const estimator_state_t& m) { return value_of<Estimate>(m, BindEstimate{}); }

controller_status_t to_message(const ControllerStatus& v) { return message_of<controller_status_t>(v, BindStatus{}); }
ControllerStatus from_message(const controller_status_t& m) { return value_of<ControllerStatus>(m, BindStatus{}); }

can_health_t to_message(const CanHealth& v) { return message_of<can_health_t>(v, BindCanHealth{}); }
CanHealth from_message(const can_health_t& m) { return value_of<CanHealth>(m, BindCanHealth{}); }

fault_event_t to_message(const FaultEvent& v) { return message_of<fault_event_t>(v, BindFault{}); }
FaultEvent from_message(const fault_event_t& m) { return value_of<FaultEvent>(m, BindFault{}); }

}  // namespace nimble::contract
