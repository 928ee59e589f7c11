#pragma once
// Every stream and control message of the contract filled with distinct values in every field
// (fill), and a field-by-field comparison that names the first field that differs
// (require_equal): what the message tests of tests/functional/ build on.

#include <cstddef>
#include <cstdint>
#include <string>

#include <catch2/catch.hpp>

#include <nimble/actuator_command_t.hpp>
#include <nimble/actuator_feedback_t.hpp>
#include <nimble/attitude_setpoint_t.hpp>
#include <nimble/can_health_t.hpp>
#include <nimble/controller_status_t.hpp>
#include <nimble/estimator_state_t.hpp>
#include <nimble/fault_event_t.hpp>
#include <nimble/heartbeat_t.hpp>
#include <nimble/imu_sample_t.hpp>
#include <nimble/mocap_pose_t.hpp>
#include <nimble/rig_clock_t.hpp>
#include <nimble/run_control_t.hpp>
#include <nimble/step_ack_t.hpp>
#include <nimble/timing_health_t.hpp>
#include <nimble/truth_state_t.hpp>

namespace rig_test {

// Produces a different non-zero value on every call, so that a decoded field that was left
// untouched (zero), swapped with another field or truncated cannot compare equal.
class Distinct {
 public:
  double real() {
    const int64_t k = next();
    return sign(k) * (static_cast<double>(k) + 0.125 + static_cast<double>(k) * 1.0e-7);
  }
  int64_t i64() {
    const int64_t k = next();
    return sign(k) * ((k << 40) + 0xABCDEF00 + k);  // exercises the high bytes
  }
  int32_t i32() {
    const int64_t k = next();
    return static_cast<int32_t>(sign(k) * ((k << 20) + 0x1234 + k));
  }
  int16_t i16() { return static_cast<int16_t>(1000 + next()); }
  std::string str() { return "s" + std::to_string(next()) + "-\xc3\xa4\xc3\xb6 x"; }  // UTF-8

 private:
  static int64_t sign(int64_t k) { return (k % 2 != 0) ? -1 : 1; }
  int64_t next() { return ++n_; }
  int64_t n_ = 0;
};

template <typename T, std::size_t N>
inline void require_array_equal(const T (&a)[N], const T (&b)[N], const char* name) {
  for (std::size_t i = 0; i < N; ++i) {
    INFO(name << "[" << i << "]");
    REQUIRE(a[i] == b[i]);
  }
}

template <typename T, std::size_t N>
inline void fill_array(T (&a)[N], Distinct& g) {
  for (std::size_t i = 0; i < N; ++i) a[i] = g.real();
}

#define REQUIRE_ARRAY(field) require_array_equal(a.field, b.field, #field)

// --- truth_state_t -------------------------------------------------------------------------
inline void fill(nimble::truth_state_t& m, Distinct& g) {
  m.utime = g.i64();
  m.seq = g.i64();
  m.step = g.i64();
  fill_array(m.position_ned_m, g);
  fill_array(m.velocity_body_mps, g);
  fill_array(m.euler_rad, g);
  fill_array(m.quaternion_wxyz, g);
  fill_array(m.omega_body_radps, g);
  fill_array(m.specific_force_body_mps2, g);
  fill_array(m.angular_accel_body_radps2, g);
  m.flap_freq_left_radps = g.real();
  m.flap_freq_right_radps = g.real();
  m.delta_f_radps = g.real();
  m.throttle_pct = g.real();
  m.dihedral_rad = g.real();
  m.wing_root_rad = g.real();
}
inline void require_equal(const nimble::truth_state_t& a, const nimble::truth_state_t& b) {
  REQUIRE(a.utime == b.utime);
  REQUIRE(a.seq == b.seq);
  REQUIRE(a.step == b.step);
  REQUIRE_ARRAY(position_ned_m);
  REQUIRE_ARRAY(velocity_body_mps);
  REQUIRE_ARRAY(euler_rad);
  REQUIRE_ARRAY(quaternion_wxyz);
  REQUIRE_ARRAY(omega_body_radps);
  REQUIRE_ARRAY(specific_force_body_mps2);
  REQUIRE_ARRAY(angular_accel_body_radps2);
  REQUIRE(a.flap_freq_left_radps == b.flap_freq_left_radps);
  REQUIRE(a.flap_freq_right_radps == b.flap_freq_right_radps);
  REQUIRE(a.delta_f_radps == b.delta_f_radps);
  REQUIRE(a.throttle_pct == b.throttle_pct);
  REQUIRE(a.dihedral_rad == b.dihedral_rad);
  REQUIRE(a.wing_root_rad == b.wing_root_rad);
}

// --- imu_sample_t --------------------------------------------------------------------------
inline void fill(nimble::imu_sample_t& m, Distinct& g) {
  m.utime = g.i64();
  m.seq = g.i64();
  fill_array(m.gyro_radps, g);
  fill_array(m.accel_mps2, g);
  m.temperature_degc = g.real();
  m.saturation_flags = static_cast<int8_t>(nimble::imu_sample_t::SAT_GYRO_Y |
                                           nimble::imu_sample_t::SAT_ACCEL_Z);
}
inline void require_equal(const nimble::imu_sample_t& a, const nimble::imu_sample_t& b) {
  REQUIRE(a.utime == b.utime);
  REQUIRE(a.seq == b.seq);
  REQUIRE_ARRAY(gyro_radps);
  REQUIRE_ARRAY(accel_mps2);
  REQUIRE(a.temperature_degc == b.temperature_degc);
  REQUIRE(a.saturation_flags == b.saturation_flags);
}

// --- mocap_pose_t --------------------------------------------------------------------------
inline void fill(nimble::mocap_pose_t& m, Distinct& g) {
  m.utime = g.i64();
  m.seq = g.i64();
  m.frame_number = g.i64();
  m.latency_us = g.i32();
  m.rigid_body_id = g.i32();
  fill_array(m.position_m, g);
  fill_array(m.quaternion_wxyz, g);
  m.tracking_valid = true;
  m.mean_marker_error_m = g.real();
  m.num_markers = g.i16();
}
inline void require_equal(const nimble::mocap_pose_t& a, const nimble::mocap_pose_t& b) {
  REQUIRE(a.utime == b.utime);
  REQUIRE(a.seq == b.seq);
  REQUIRE(a.frame_number == b.frame_number);
  REQUIRE(a.latency_us == b.latency_us);
  REQUIRE(a.rigid_body_id == b.rigid_body_id);
  REQUIRE_ARRAY(position_m);
  REQUIRE_ARRAY(quaternion_wxyz);
  REQUIRE(a.tracking_valid == b.tracking_valid);
  REQUIRE(a.mean_marker_error_m == b.mean_marker_error_m);
  REQUIRE(a.num_markers == b.num_markers);
}

// --- actuator_command_t --------------------------------------------------------------------
inline void fill(nimble::actuator_command_t& m, Distinct& g) {
  m.utime = g.i64();
  m.seq = g.i64();
  m.mode = nimble::actuator_command_t::MODE_DELTA_F;
  m.flap_freq_left_radps = g.real();
  m.flap_freq_right_radps = g.real();
  m.delta_f_radps = g.real();
  m.flap_freq_collective_radps = g.real();
  m.throttle_pct = g.real();
  m.dihedral_rad = g.real();
  m.wing_root_rad = g.real();
  m.input_utime = g.i64();
  m.rolling_counter = 13;
  m.source = g.str();
}
inline void require_equal(const nimble::actuator_command_t& a, const nimble::actuator_command_t& b) {
  REQUIRE(a.utime == b.utime);
  REQUIRE(a.seq == b.seq);
  REQUIRE(a.mode == b.mode);
  REQUIRE(a.flap_freq_left_radps == b.flap_freq_left_radps);
  REQUIRE(a.flap_freq_right_radps == b.flap_freq_right_radps);
  REQUIRE(a.delta_f_radps == b.delta_f_radps);
  REQUIRE(a.flap_freq_collective_radps == b.flap_freq_collective_radps);
  REQUIRE(a.throttle_pct == b.throttle_pct);
  REQUIRE(a.dihedral_rad == b.dihedral_rad);
  REQUIRE(a.wing_root_rad == b.wing_root_rad);
  REQUIRE(a.input_utime == b.input_utime);
  REQUIRE(a.rolling_counter == b.rolling_counter);
  REQUIRE(a.source == b.source);
}

// --- actuator_feedback_t -------------------------------------------------------------------
inline void fill(nimble::actuator_feedback_t& m, Distinct& g) {
  m.utime = g.i64();
  m.seq = g.i64();
  m.flap_freq_left_radps = g.real();
  m.flap_freq_right_radps = g.real();
  m.delta_f_radps = g.real();
  m.dihedral_rad = g.real();
  m.wing_root_rad = g.real();
  m.throttle_pct = g.real();
  m.cmd_seq = g.i64();
  m.cmd_age_us = g.i64();
  m.safe_state = true;
}
inline void require_equal(const nimble::actuator_feedback_t& a, const nimble::actuator_feedback_t& b) {
  REQUIRE(a.utime == b.utime);
  REQUIRE(a.seq == b.seq);
  REQUIRE(a.flap_freq_left_radps == b.flap_freq_left_radps);
  REQUIRE(a.flap_freq_right_radps == b.flap_freq_right_radps);
  REQUIRE(a.delta_f_radps == b.delta_f_radps);
  REQUIRE(a.dihedral_rad == b.dihedral_rad);
  REQUIRE(a.wing_root_rad == b.wing_root_rad);
  REQUIRE(a.throttle_pct == b.throttle_pct);
  REQUIRE(a.cmd_seq == b.cmd_seq);
  REQUIRE(a.cmd_age_us == b.cmd_age_us);
  REQUIRE(a.safe_state == b.safe_state);
}


// --- can_health_t ---------------------------------------------------------------------------
inline void fill(nimble::can_health_t& m, Distinct& g) {
  m.utime = g.i64();
  m.seq = g.i64();
  m.process = "can_rig";
  m.role = nimble::can_health_t::ROLE_RIG;
  m.interface_name = "vcan0";
  m.messages_to_can = g.i64();
  m.messages_to_lcm = g.i64();
  m.frames_sent = g.i64();
  m.frames_received = g.i64();
  m.send_enobufs = g.i64();
  m.send_retries = g.i64();
  m.send_dropped = g.i64();
  m.receive_dropped = g.i64();
  m.rejected_unknown_id = g.i64();
  m.rejected_wrong_length = g.i64();
  m.rejected_bad_checksum = g.i64();
  m.rejected_stale_counter = g.i64();
  m.rejected_out_of_range = g.i64();
  m.counter_gaps = g.i64();
  m.saturated_values = g.i64();
  m.error_frames = g.i64();
  m.candump_lines = g.i64();
  m.fd = true;
  m.fd_frames_sent = g.i64();
  m.fd_frames_received = g.i64();
  m.bus_state = nimble::can_health_t::BUS_PASSIVE;
  m.last_error = "controller: TX error-passive";
  m.candump_file = "/tmp/run.candump";
}
inline void require_equal(const nimble::can_health_t& a, const nimble::can_health_t& b) {
  REQUIRE(a.utime == b.utime);
  REQUIRE(a.seq == b.seq);
  REQUIRE(a.process == b.process);
  REQUIRE(a.role == b.role);
  REQUIRE(a.interface_name == b.interface_name);
  REQUIRE(a.messages_to_can == b.messages_to_can);
  REQUIRE(a.messages_to_lcm == b.messages_to_lcm);
  REQUIRE(a.frames_sent == b.frames_sent);
  REQUIRE(a.frames_received == b.frames_received);
  REQUIRE(a.send_enobufs == b.send_enobufs);
  REQUIRE(a.send_retries == b.send_retries);
  REQUIRE(a.send_dropped == b.send_dropped);
  REQUIRE(a.receive_dropped == b.receive_dropped);
  REQUIRE(a.rejected_unknown_id == b.rejected_unknown_id);
  REQUIRE(a.rejected_wrong_length == b.rejected_wrong_length);
  REQUIRE(a.rejected_bad_checksum == b.rejected_bad_checksum);
  REQUIRE(a.rejected_stale_counter == b.rejected_stale_counter);
  REQUIRE(a.rejected_out_of_range == b.rejected_out_of_range);
  REQUIRE(a.counter_gaps == b.counter_gaps);
  REQUIRE(a.saturated_values == b.saturated_values);
  REQUIRE(a.error_frames == b.error_frames);
  REQUIRE(a.candump_lines == b.candump_lines);
  REQUIRE(a.fd == b.fd);
  REQUIRE(a.fd_frames_sent == b.fd_frames_sent);
  REQUIRE(a.fd_frames_received == b.fd_frames_received);
  REQUIRE(a.bus_state == b.bus_state);
  REQUIRE(a.last_error == b.last_error);
  REQUIRE(a.candump_file == b.candump_file);
}

// --- attitude_setpoint_t -------------------------------------------------------------------
inline void fill(nimble::attitude_setpoint_t& m, Distinct& g) {
  m.utime = g.i64();
  m.seq = g.i64();
  m.roll_sp_rad = g.real();
  m.pitch_sp_rad = g.real();
  m.yaw_rate_sp_radps = g.real();
  m.throttle_pct = g.real();
  m.throttle_factor = g.real();
  m.manoeuvre = g.str();
  m.segment_index = g.i32();
  m.segment_name = g.str();
  m.gain_set = "slow";
}
inline void require_equal(const nimble::attitude_setpoint_t& a, const nimble::attitude_setpoint_t& b) {
  REQUIRE(a.utime == b.utime);
  REQUIRE(a.seq == b.seq);
  REQUIRE(a.roll_sp_rad == b.roll_sp_rad);
  REQUIRE(a.pitch_sp_rad == b.pitch_sp_rad);
  REQUIRE(a.yaw_rate_sp_radps == b.yaw_rate_sp_radps);
  REQUIRE(a.throttle_pct == b.throttle_pct);
  REQUIRE(a.throttle_factor == b.throttle_factor);
  REQUIRE(a.manoeuvre == b.manoeuvre);
  REQUIRE(a.segment_index == b.segment_index);
  REQUIRE(a.segment_name == b.segment_name);
  REQUIRE(a.gain_set == b.gain_set);
}

// --- estimator_state_t ---------------------------------------------------------------------
inline void fill(nimble::estimator_state_t& m, Distinct& g) {
  m.utime = g.i64();
  m.seq = g.i64();
  m.imu_utime = g.i64();
  fill_array(m.euler_rad, g);
  fill_array(m.velocity_body_mps, g);
  fill_array(m.gyro_bias_radps, g);
  fill_array(m.accel_bias_mps2, g);
  fill_array(m.omega_body_radps, g);
  fill_array(m.cov_diag, g);
  m.poses_accepted = g.i64();
  m.poses_rejected = g.i64();
  m.poses_missing = g.i64();
  m.last_nis = g.real();
  m.poses_too_old = g.i64();
  m.poses_too_new = g.i64();
  m.velocity_windows_uncovered = g.i64();
  m.imu_rejected = g.i64();
  m.imu_gaps = g.i64();
}
inline void require_equal(const nimble::estimator_state_t& a, const nimble::estimator_state_t& b) {
  REQUIRE(a.utime == b.utime);
  REQUIRE(a.seq == b.seq);
  REQUIRE(a.imu_utime == b.imu_utime);
  REQUIRE_ARRAY(euler_rad);
  REQUIRE_ARRAY(velocity_body_mps);
  REQUIRE_ARRAY(gyro_bias_radps);
  REQUIRE_ARRAY(accel_bias_mps2);
  REQUIRE_ARRAY(omega_body_radps);
  REQUIRE_ARRAY(cov_diag);
  REQUIRE(a.poses_accepted == b.poses_accepted);
  REQUIRE(a.poses_rejected == b.poses_rejected);
  REQUIRE(a.poses_missing == b.poses_missing);
  REQUIRE(a.last_nis == b.last_nis);
  REQUIRE(a.poses_too_old == b.poses_too_old);
  REQUIRE(a.poses_too_new == b.poses_too_new);
  REQUIRE(a.velocity_windows_uncovered == b.velocity_windows_uncovered);
  REQUIRE(a.imu_rejected == b.imu_rejected);
  REQUIRE(a.imu_gaps == b.imu_gaps);
}

// --- controller_status_t -------------------------------------------------------------------
inline void fill(nimble::controller_status_t& m, Distinct& g) {
  m.utime = g.i64();
  m.seq = g.i64();
  m.gain_set = "fast";
  m.kp = g.real();
  m.kd = g.real();
  m.roll_ref_rad = g.real();
  m.roll_rate_ref_radps = g.real();
  m.roll_error_rad = g.real();
  m.roll_cmd_norm = g.real();
  m.pitch_cmd_norm = g.real();
  m.delta_f_cmd_radps = g.real();
  m.throttle_pct = g.real();
  m.saturated = true;
  m.input_source = nimble::controller_status_t::INPUT_ESTIMATE;
  m.input_age_us = g.i64();
  m.failsafe = true;
}
inline void require_equal(const nimble::controller_status_t& a, const nimble::controller_status_t& b) {
  REQUIRE(a.utime == b.utime);
  REQUIRE(a.seq == b.seq);
  REQUIRE(a.gain_set == b.gain_set);
  REQUIRE(a.kp == b.kp);
  REQUIRE(a.kd == b.kd);
  REQUIRE(a.roll_ref_rad == b.roll_ref_rad);
  REQUIRE(a.roll_rate_ref_radps == b.roll_rate_ref_radps);
  REQUIRE(a.roll_error_rad == b.roll_error_rad);
  REQUIRE(a.roll_cmd_norm == b.roll_cmd_norm);
  REQUIRE(a.pitch_cmd_norm == b.pitch_cmd_norm);
  REQUIRE(a.delta_f_cmd_radps == b.delta_f_cmd_radps);
  REQUIRE(a.throttle_pct == b.throttle_pct);
  REQUIRE(a.saturated == b.saturated);
  REQUIRE(a.input_source == b.input_source);
  REQUIRE(a.input_age_us == b.input_age_us);
  REQUIRE(a.failsafe == b.failsafe);
}

// --- rig_clock_t ---------------------------------------------------------------------------
inline void fill(nimble::rig_clock_t& m, Distinct& g) {
  m.utime = g.i64();
  m.seq = g.i64();
  m.step = g.i64();
  m.sim_time_ns = g.i64();
  m.dt_ns = g.i64();
  m.run_id = g.str();
}
inline void require_equal(const nimble::rig_clock_t& a, const nimble::rig_clock_t& b) {
  REQUIRE(a.utime == b.utime);
  REQUIRE(a.seq == b.seq);
  REQUIRE(a.step == b.step);
  REQUIRE(a.sim_time_ns == b.sim_time_ns);
  REQUIRE(a.dt_ns == b.dt_ns);
  REQUIRE(a.run_id == b.run_id);
}

// --- step_ack_t ----------------------------------------------------------------------------
inline void fill(nimble::step_ack_t& m, Distinct& g) {
  m.utime = g.i64();
  m.seq = g.i64();
  m.step = g.i64();
  m.next_due_ns = g.i64();
  m.process = g.str();
}
inline void require_equal(const nimble::step_ack_t& a, const nimble::step_ack_t& b) {
  REQUIRE(a.utime == b.utime);
  REQUIRE(a.seq == b.seq);
  REQUIRE(a.step == b.step);
  REQUIRE(a.next_due_ns == b.next_due_ns);
  REQUIRE(a.process == b.process);
}

// --- run_control_t -------------------------------------------------------------------------
inline void fill(nimble::run_control_t& m, Distinct& g) {
  m.utime = g.i64();
  m.seq = g.i64();
  m.command = nimble::run_control_t::COMMAND_STOP;
  m.clock_mode = nimble::run_control_t::CLOCK_MODE_LOCKSTEP;
  m.t0_monotonic_ns = g.i64();
  m.duration_ns = g.i64();
  m.run_id = g.str();
  m.num_participants = 2;
  m.participants = {g.str(), g.str()};
}
inline void require_equal(const nimble::run_control_t& a, const nimble::run_control_t& b) {
  REQUIRE(a.utime == b.utime);
  REQUIRE(a.seq == b.seq);
  REQUIRE(a.command == b.command);
  REQUIRE(a.clock_mode == b.clock_mode);
  REQUIRE(a.t0_monotonic_ns == b.t0_monotonic_ns);
  REQUIRE(a.duration_ns == b.duration_ns);
  REQUIRE(a.run_id == b.run_id);
  REQUIRE(a.num_participants == b.num_participants);
  REQUIRE(a.participants == b.participants);
}

// --- heartbeat_t ---------------------------------------------------------------------------
inline void fill(nimble::heartbeat_t& m, Distinct& g) {
  m.utime = g.i64();
  m.seq = g.i64();
  m.process = g.str();
  m.pid = g.i32();
  m.state = nimble::heartbeat_t::STATE_STOPPING;
  m.config_digest = "0123456789abcdef0123456789abcdef0123456789abcdef0123456789abcdef";
}
inline void require_equal(const nimble::heartbeat_t& a, const nimble::heartbeat_t& b) {
  REQUIRE(a.utime == b.utime);
  REQUIRE(a.seq == b.seq);
  REQUIRE(a.process == b.process);
  REQUIRE(a.pid == b.pid);
  REQUIRE(a.state == b.state);
  REQUIRE(a.config_digest == b.config_digest);
}

// --- timing_health_t -----------------------------------------------------------------------
inline void fill(nimble::timing_health_t& m, Distinct& g, int32_t num_channels) {
  m.utime = g.i64();
  m.seq = g.i64();
  m.process = g.str();
  m.window_us = g.i64();
  m.loop_rate_hz = g.real();
  m.loop_count = g.i64();
  m.overruns = g.i64();
  m.jitter_p50_us = g.real();
  m.jitter_p99_us = g.real();
  m.jitter_max_us = g.real();
  m.latency_count = g.i64();
  m.latency_p50_us = g.real();
  m.latency_p99_us = g.real();
  m.latency_max_us = g.real();
  m.num_channels = num_channels;
  m.channel.clear();
  m.count.clear();
  m.rate_hz.clear();
  m.expected_hz.clear();
  m.drops.clear();
  m.late.clear();
  for (int32_t i = 0; i < num_channels; ++i) {
    m.channel.push_back(g.str());
    m.count.push_back(g.i64());
    m.rate_hz.push_back(g.real());
    m.expected_hz.push_back(g.real());
    m.drops.push_back(g.i64());
    m.late.push_back(g.i64());
  }
}
inline void fill(nimble::timing_health_t& m, Distinct& g) { fill(m, g, 3); }
inline void require_equal(const nimble::timing_health_t& a, const nimble::timing_health_t& b) {
  REQUIRE(a.utime == b.utime);
  REQUIRE(a.seq == b.seq);
  REQUIRE(a.process == b.process);
  REQUIRE(a.window_us == b.window_us);
  REQUIRE(a.loop_rate_hz == b.loop_rate_hz);
  REQUIRE(a.loop_count == b.loop_count);
  REQUIRE(a.overruns == b.overruns);
  REQUIRE(a.jitter_p50_us == b.jitter_p50_us);
  REQUIRE(a.jitter_p99_us == b.jitter_p99_us);
  REQUIRE(a.jitter_max_us == b.jitter_max_us);
  REQUIRE(a.latency_count == b.latency_count);
  REQUIRE(a.latency_p50_us == b.latency_p50_us);
  REQUIRE(a.latency_p99_us == b.latency_p99_us);
  REQUIRE(a.latency_max_us == b.latency_max_us);
  REQUIRE(a.num_channels == b.num_channels);
  REQUIRE(a.channel == b.channel);
  REQUIRE(a.count == b.count);
  REQUIRE(a.rate_hz == b.rate_hz);
  REQUIRE(a.expected_hz == b.expected_hz);
  REQUIRE(a.drops == b.drops);
  REQUIRE(a.late == b.late);
}

// --- fault_event_t -------------------------------------------------------------------------
inline void fill(nimble::fault_event_t& m, Distinct& g) {
  m.utime = g.i64();
  m.seq = g.i64();
  m.rig_utime = g.i64();
  m.process = g.str();
  m.severity = nimble::fault_event_t::SEVERITY_ERROR;
  m.code = nimble::fault_event_t::CODE_DEADLINE_MISS;
  m.channel = g.str();
  m.message = g.str();
}
inline void require_equal(const nimble::fault_event_t& a, const nimble::fault_event_t& b) {
  REQUIRE(a.utime == b.utime);
  REQUIRE(a.seq == b.seq);
  REQUIRE(a.rig_utime == b.rig_utime);
  REQUIRE(a.process == b.process);
  REQUIRE(a.severity == b.severity);
  REQUIRE(a.code == b.code);
  REQUIRE(a.channel == b.channel);
  REQUIRE(a.message == b.message);
}

#undef REQUIRE_ARRAY

}  // namespace rig_test
