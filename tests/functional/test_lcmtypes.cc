// Functional tests of the rig's LCM message contract (lcmtypes/*.lcm, package nimble):
// encode/decode round trips, malformed-message detection and in-process publish/subscribe.

#include <catch2/catch.hpp>

#include <lcm/lcm-cpp.hpp>

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
#include <nimble/step_ack_t.hpp>
#include <nimble/run_control_t.hpp>
#include <nimble/timing_health_t.hpp>
#include <nimble/truth_state_t.hpp>

#include <cstddef>
#include <cstdint>
#include <set>
#include <string>
#include <type_traits>
#include <vector>

#include "contract/channels.h"
#include "contract/decode.h"

using namespace nimble::contract::channels;

namespace {

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
void require_array_equal(const T (&a)[N], const T (&b)[N], const char* name) {
  for (std::size_t i = 0; i < N; ++i) {
    INFO(name << "[" << i << "]");
    REQUIRE(a[i] == b[i]);
  }
}

template <typename T, std::size_t N>
void fill_array(T (&a)[N], Distinct& g) {
  for (std::size_t i = 0; i < N; ++i) a[i] = g.real();
}

#define REQUIRE_ARRAY(field) require_array_equal(a.field, b.field, #field)

// --- truth_state_t -------------------------------------------------------------------------
void fill(nimble::truth_state_t& m, Distinct& g) {
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
void require_equal(const nimble::truth_state_t& a, const nimble::truth_state_t& b) {
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
void fill(nimble::imu_sample_t& m, Distinct& g) {
  m.utime = g.i64();
  m.seq = g.i64();
  fill_array(m.gyro_radps, g);
  fill_array(m.accel_mps2, g);
  m.temperature_degc = g.real();
  m.saturation_flags = static_cast<int8_t>(nimble::imu_sample_t::SAT_GYRO_Y |
                                           nimble::imu_sample_t::SAT_ACCEL_Z);
}
void require_equal(const nimble::imu_sample_t& a, const nimble::imu_sample_t& b) {
  REQUIRE(a.utime == b.utime);
  REQUIRE(a.seq == b.seq);
  REQUIRE_ARRAY(gyro_radps);
  REQUIRE_ARRAY(accel_mps2);
  REQUIRE(a.temperature_degc == b.temperature_degc);
  REQUIRE(a.saturation_flags == b.saturation_flags);
}

// --- mocap_pose_t --------------------------------------------------------------------------
void fill(nimble::mocap_pose_t& m, Distinct& g) {
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
void require_equal(const nimble::mocap_pose_t& a, const nimble::mocap_pose_t& b) {
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
void fill(nimble::actuator_command_t& m, Distinct& g) {
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
void require_equal(const nimble::actuator_command_t& a, const nimble::actuator_command_t& b) {
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
void fill(nimble::actuator_feedback_t& m, Distinct& g) {
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
void require_equal(const nimble::actuator_feedback_t& a, const nimble::actuator_feedback_t& b) {
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
void fill(nimble::can_health_t& m, Distinct& g) {
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
void require_equal(const nimble::can_health_t& a, const nimble::can_health_t& b) {
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
void fill(nimble::attitude_setpoint_t& m, Distinct& g) {
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
void require_equal(const nimble::attitude_setpoint_t& a, const nimble::attitude_setpoint_t& b) {
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
void fill(nimble::estimator_state_t& m, Distinct& g) {
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
void require_equal(const nimble::estimator_state_t& a, const nimble::estimator_state_t& b) {
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
void fill(nimble::controller_status_t& m, Distinct& g) {
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
void require_equal(const nimble::controller_status_t& a, const nimble::controller_status_t& b) {
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
void fill(nimble::rig_clock_t& m, Distinct& g) {
  m.utime = g.i64();
  m.seq = g.i64();
  m.step = g.i64();
  m.sim_time_ns = g.i64();
  m.dt_ns = g.i64();
  m.run_id = g.str();
}
void require_equal(const nimble::rig_clock_t& a, const nimble::rig_clock_t& b) {
  REQUIRE(a.utime == b.utime);
  REQUIRE(a.seq == b.seq);
  REQUIRE(a.step == b.step);
  REQUIRE(a.sim_time_ns == b.sim_time_ns);
  REQUIRE(a.dt_ns == b.dt_ns);
  REQUIRE(a.run_id == b.run_id);
}

// --- step_ack_t ----------------------------------------------------------------------------
void fill(nimble::step_ack_t& m, Distinct& g) {
  m.utime = g.i64();
  m.seq = g.i64();
  m.step = g.i64();
  m.next_due_ns = g.i64();
  m.process = g.str();
}
void require_equal(const nimble::step_ack_t& a, const nimble::step_ack_t& b) {
  REQUIRE(a.utime == b.utime);
  REQUIRE(a.seq == b.seq);
  REQUIRE(a.step == b.step);
  REQUIRE(a.next_due_ns == b.next_due_ns);
  REQUIRE(a.process == b.process);
}

// --- run_control_t -------------------------------------------------------------------------
void fill(nimble::run_control_t& m, Distinct& g) {
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
void require_equal(const nimble::run_control_t& a, const nimble::run_control_t& b) {
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
void fill(nimble::heartbeat_t& m, Distinct& g) {
  m.utime = g.i64();
  m.seq = g.i64();
  m.process = g.str();
  m.pid = g.i32();
  m.state = nimble::heartbeat_t::STATE_STOPPING;
  m.config_digest = "0123456789abcdef0123456789abcdef0123456789abcdef0123456789abcdef";
}
void require_equal(const nimble::heartbeat_t& a, const nimble::heartbeat_t& b) {
  REQUIRE(a.utime == b.utime);
  REQUIRE(a.seq == b.seq);
  REQUIRE(a.process == b.process);
  REQUIRE(a.pid == b.pid);
  REQUIRE(a.state == b.state);
  REQUIRE(a.config_digest == b.config_digest);
}

// --- timing_health_t -----------------------------------------------------------------------
void fill(nimble::timing_health_t& m, Distinct& g, int32_t num_channels) {
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
void fill(nimble::timing_health_t& m, Distinct& g) { fill(m, g, 3); }
void require_equal(const nimble::timing_health_t& a, const nimble::timing_health_t& b) {
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
void fill(nimble::fault_event_t& m, Distinct& g) {
  m.utime = g.i64();
  m.seq = g.i64();
  m.rig_utime = g.i64();
  m.process = g.str();
  m.severity = nimble::fault_event_t::SEVERITY_ERROR;
  m.code = nimble::fault_event_t::CODE_DEADLINE_MISS;
  m.channel = g.str();
  m.message = g.str();
}
void require_equal(const nimble::fault_event_t& a, const nimble::fault_event_t& b) {
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

// Rig channel of each type (lcmtypes/README.md).
const std::string& channel_of(const nimble::truth_state_t*) { return kTruth; }
const std::string& channel_of(const nimble::imu_sample_t*) { return kImu; }
const std::string& channel_of(const nimble::mocap_pose_t*) { return kMocapPose; }
const std::string& channel_of(const nimble::actuator_command_t*) { return kActuatorCommand; }
const std::string& channel_of(const nimble::actuator_feedback_t*) { return kActuatorFeedback; }
const std::string& channel_of(const nimble::attitude_setpoint_t*) { return kAttitudeSetpoint; }
const std::string& channel_of(const nimble::estimator_state_t*) { return kEstimate; }
const std::string& channel_of(const nimble::controller_status_t*) { return kControllerStatus; }
const std::string& channel_of(const nimble::rig_clock_t*) { return kRigClock; }
const std::string& channel_of(const nimble::step_ack_t*) { return kStepAck; }
const std::string& channel_of(const nimble::run_control_t*) { return kRunControl; }
const std::string& channel_of(const nimble::heartbeat_t*) { return kHeartbeat; }
const std::string& channel_of(const nimble::timing_health_t*) { return kTimingHealth; }
const std::string& channel_of(const nimble::fault_event_t*) { return kFault; }
const std::string& channel_of(const nimble::can_health_t*) { return kCanHealth; }

template <typename T>
T make_sample() {
  T m{};
  Distinct g;
  fill(m, g);
  return m;
}

template <typename T>
std::vector<uint8_t> encode(const T& m) {
  const int size = m.getEncodedSize();
  REQUIRE(size > 8);
  std::vector<uint8_t> buf(static_cast<std::size_t>(size));
  REQUIRE(m.encode(buf.data(), 0, size) == size);
  return buf;
}

template <typename T>
class Receiver {
 public:
  void on_message(const lcm::ReceiveBuffer* rbuf, const std::string& channel, const T* msg) {
    ++count;
    last_channel = channel;
    last_size = rbuf->data_size;
    last = *msg;
  }
  int count = 0;
  std::string last_channel;
  uint32_t last_size = 0;
  T last{};
};

}  // namespace

#define RIG_LCM_TYPES                                                                       \
  nimble::truth_state_t, nimble::imu_sample_t, nimble::mocap_pose_t,                        \
      nimble::actuator_command_t, nimble::actuator_feedback_t, nimble::attitude_setpoint_t, \
      nimble::estimator_state_t, nimble::controller_status_t, nimble::rig_clock_t,          \
      nimble::step_ack_t, nimble::run_control_t, nimble::heartbeat_t, nimble::timing_health_t, \
      nimble::fault_event_t, nimble::can_health_t

TEMPLATE_TEST_CASE("encode and decode preserve every field", "[lcmtypes]", RIG_LCM_TYPES) {
  const TestType in = make_sample<TestType>();
  const std::vector<uint8_t> buf = encode(in);
  const int size = static_cast<int>(buf.size());

  TestType out{};
  REQUIRE(out.decode(buf.data(), 0, size) == size);
  require_equal(in, out);

  // Same bytes at a non-zero offset.
  std::vector<uint8_t> shifted(buf.size() + 5, 0xEE);
  REQUIRE(in.encode(shifted.data(), 5, size) == size);
  TestType out2{};
  REQUIRE(out2.decode(shifted.data(), 5, size) == size);
  require_equal(in, out2);
}

TEMPLATE_TEST_CASE("encoding into a too small buffer fails", "[lcmtypes]", RIG_LCM_TYPES) {
  const TestType in = make_sample<TestType>();
  const int size = in.getEncodedSize();
  std::vector<uint8_t> buf(static_cast<std::size_t>(size));
  REQUIRE(in.encode(buf.data(), 0, size - 1) < 0);
}

TEMPLATE_TEST_CASE("decoding a truncated buffer fails", "[lcmtypes]", RIG_LCM_TYPES) {
  const std::vector<uint8_t> buf = encode(make_sample<TestType>());
  for (int len = 0; len < static_cast<int>(buf.size()); ++len) {
    INFO("truncated to " << len << " of " << buf.size() << " bytes");
    TestType out{};
    REQUIRE(out.decode(buf.data(), 0, len) < 0);
  }
}

TEMPLATE_TEST_CASE("decoding with a corrupted fingerprint fails", "[lcmtypes]", RIG_LCM_TYPES) {
  const std::vector<uint8_t> buf = encode(make_sample<TestType>());
  const int size = static_cast<int>(buf.size());
  for (std::size_t i = 0; i < 8; ++i) {  // the fingerprint is the first 8 bytes
    INFO("fingerprint byte " << i << " corrupted");
    std::vector<uint8_t> bad = buf;
    bad[i] = static_cast<uint8_t>(bad[i] ^ 0x01);
    TestType out{};
    REQUIRE(out.decode(bad.data(), 0, size) < 0);
  }
}

TEMPLATE_TEST_CASE("decoding a message of another type fails", "[lcmtypes]", RIG_LCM_TYPES) {
  using Other = typename std::conditional<std::is_same<TestType, nimble::heartbeat_t>::value,
                                          nimble::fault_event_t, nimble::heartbeat_t>::type;
  const std::vector<uint8_t> buf = encode(make_sample<Other>());
  TestType out{};
  REQUIRE(out.decode(buf.data(), 0, static_cast<int>(buf.size())) < 0);
}

TEMPLATE_TEST_CASE("publish and receive over memq://", "[lcmtypes][memq]", RIG_LCM_TYPES) {
  lcm::LCM lcm("memq://");
  REQUIRE(lcm.good());

  const std::string channel = channel_of(static_cast<const TestType*>(nullptr));
  Receiver<TestType> receiver;
  lcm::Subscription* sub = lcm.subscribe(channel, &Receiver<TestType>::on_message, &receiver);
  REQUIRE(sub != nullptr);

  const TestType in = make_sample<TestType>();
  REQUIRE(lcm.publish(channel, &in) == 0);
  REQUIRE(lcm.handleTimeout(100) > 0);

  REQUIRE(receiver.count == 1);
  REQUIRE(receiver.last_channel == channel);
  REQUIRE(static_cast<int>(receiver.last_size) == in.getEncodedSize());
  require_equal(in, receiver.last);

  REQUIRE(lcm.unsubscribe(sub) == 0);
}

TEMPLATE_TEST_CASE("utime and seq are the first fields", "[lcmtypes]", RIG_LCM_TYPES) {
  // Encoded layout: 8-byte fingerprint, then utime and seq as big-endian int64.
  const TestType in = make_sample<TestType>();
  const std::vector<uint8_t> buf = encode(in);
  auto be64 = [&buf](std::size_t offset) {
    uint64_t v = 0;
    for (std::size_t i = 0; i < 8; ++i) v = (v << 8) | buf[offset + i];
    return static_cast<int64_t>(v);
  };
  REQUIRE(be64(8) == in.utime);
  REQUIRE(be64(16) == in.seq);
}

TEST_CASE("timing_health_t with zero channels round-trips", "[lcmtypes]") {
  nimble::timing_health_t in{};
  Distinct g;
  fill(in, g, 0);
  const std::vector<uint8_t> buf = encode(in);
  nimble::timing_health_t out{};
  REQUIRE(out.decode(buf.data(), 0, static_cast<int>(buf.size())) ==
          static_cast<int>(buf.size()));
  require_equal(in, out);
  REQUIRE(out.channel.empty());
}

TEMPLATE_TEST_CASE("decode_exact takes every message the encoder writes", "[lcmtypes][decode]", RIG_LCM_TYPES) {
  const TestType in = make_sample<TestType>();
  const std::vector<uint8_t> buf = encode(in);
  TestType out{};
  std::string error;
  CHECK(nimble::contract::decode_exact(buf.data(), static_cast<int>(buf.size()), out, &error));
  CHECK(error.empty());
  require_equal(in, out);
}

namespace {

/// Puts `count` as the big-endian int32 at `pos` of `buf`.
void put_count(std::vector<uint8_t>& buf, std::size_t pos, uint32_t count) {
  for (int i = 0; i < 4; ++i) buf[pos + static_cast<std::size_t>(i)] = static_cast<uint8_t>(count >> (24 - 8 * i));
}

/// Neither LCM's decoder (with the rig's checks) nor decode_exact() takes `buf` as a T.
template <typename T>
void require_count_refused(const std::vector<uint8_t>& buf) {
  T raw{};
  CHECK(raw.decode(buf.data(), 0, static_cast<int>(buf.size())) < 0);
  T out{};
  CHECK_FALSE(nimble::contract::decode_exact(buf.data(), static_cast<int>(buf.size()), out));
}

}  // namespace

TEST_CASE("an array count larger than the message is refused without allocating it", "[lcmtypes][decode]") {
  // Found by the node fuzz targets: LCM's decoders resized an array to the count in the bytes
  // before reading it, and a 200-byte TIMING_HEALTH with num_channels near 2^31 allocated
  // tens of gigabytes (cmake/LcmDecodeChecks.cmake adds the check). The count sits just before
  // the elements, which end the encoding.
  for (int n : {0, 1, 3}) {
    INFO(n << " elements");
    nimble::run_control_t rc{};
    Distinct g;
    fill(rc, g);
    rc.participants.assign(static_cast<std::size_t>(n), "plant");
    rc.num_participants = n;
    std::vector<uint8_t> buf = encode(rc);
    const std::size_t rc_count_pos = buf.size() - static_cast<std::size_t>(n) * (4 + 6) - 4;
    for (uint32_t bad : {0x7FFFFFFFu, 1000u, 0xFFFFFFFFu}) {
      std::vector<uint8_t> patched = buf;
      put_count(patched, rc_count_pos, bad);
      require_count_refused<nimble::run_control_t>(patched);
    }

    nimble::timing_health_t th{};
    fill(th, g, n);
    for (auto& c : th.channel) c = kTruth;
    buf = encode(th);
    const std::size_t th_count_pos = buf.size() - static_cast<std::size_t>(n) * (4 + kTruth.size() + 1 + 5 * 8) - 4;
    for (uint32_t bad : {0x7FFFFFFFu, 1000u, 0xFFFFFFFFu}) {
      std::vector<uint8_t> patched = buf;
      put_count(patched, th_count_pos, bad);
      require_count_refused<nimble::timing_health_t>(patched);
    }
  }
}

TEST_CASE("a string length below 1 is refused", "[lcmtypes][decode]") {
  // Found by the node fuzz targets: a length of INT32_MIN made `length - 1` in LCM's decoder
  // overflow (undefined behaviour, in practice a 2 GB read); 0 made it throw.
  nimble::heartbeat_t hb{};
  hb.process = "plant";
  hb.config_digest = "d";
  const std::vector<uint8_t> buf = encode(hb);
  for (uint32_t length : {0x80000000u, 0u, 0xFFFFFFFFu}) {
    INFO("length " << length);
    std::vector<uint8_t> bad = buf;
    put_count(bad, 24, length);  // process: after fingerprint, utime and seq
    nimble::heartbeat_t raw{};
    CHECK(raw.decode(bad.data(), 0, static_cast<int>(bad.size())) < 0);
  }
}

TEST_CASE("decode_exact refuses a string the encoder cannot write back", "[lcmtypes][decode]") {
  // Found by fuzz_lcm_decode: LCM's decoder takes a string with a NUL inside, or with another
  // byte where its NUL belongs; the encoder (strlen) cannot write such a message again.
  nimble::fault_event_t fault{};
  fault.process = "plant";
  fault.channel = "C";
  fault.message = "abcdef";
  const std::vector<uint8_t> buf = encode(fault);
  const std::size_t message_end = buf.size() - 1;  // the message is the last field: its NUL ends the bytes
  REQUIRE(buf[message_end] == 0);
  for (const auto& [pos, byte] : std::vector<std::pair<std::size_t, uint8_t>>{{message_end - 3, 0}, {message_end, 'x'}}) {
    INFO("byte " << pos << " set to " << int{byte});
    std::vector<uint8_t> bad = buf;
    bad[pos] = byte;
    nimble::fault_event_t raw{};
    REQUIRE(raw.decode(bad.data(), 0, static_cast<int>(bad.size())) == static_cast<int>(bad.size()));  // LCM takes it
    nimble::fault_event_t out{};
    std::string error;
    CHECK_FALSE(nimble::contract::decode_exact(bad.data(), static_cast<int>(bad.size()), out, &error));
    CHECK(error.find("NUL") != std::string::npos);
  }
}

TEST_CASE("every type has its own fingerprint", "[lcmtypes]") {
  const std::vector<int64_t> hashes = {
      nimble::truth_state_t::getHash(),      nimble::imu_sample_t::getHash(),
      nimble::mocap_pose_t::getHash(),       nimble::actuator_command_t::getHash(),
      nimble::actuator_feedback_t::getHash(), nimble::attitude_setpoint_t::getHash(),
      nimble::estimator_state_t::getHash(),  nimble::controller_status_t::getHash(),
      nimble::rig_clock_t::getHash(),        nimble::step_ack_t::getHash(),
      nimble::run_control_t::getHash(),
      nimble::heartbeat_t::getHash(),        nimble::timing_health_t::getHash(),
      nimble::fault_event_t::getHash(),      nimble::can_health_t::getHash()};
  const std::set<int64_t> unique(hashes.begin(), hashes.end());
  REQUIRE(unique.size() == hashes.size());
}

TEST_CASE("enumeration constants have their documented values", "[lcmtypes]") {
  using nimble::actuator_command_t;
  using nimble::controller_status_t;
  using nimble::fault_event_t;
  using nimble::heartbeat_t;
  using nimble::imu_sample_t;

  CHECK(actuator_command_t::MODE_LEFT_RIGHT == 0);
  CHECK(actuator_command_t::MODE_DELTA_F == 1);

  CHECK(controller_status_t::INPUT_TRUTH == 0);
  CHECK(controller_status_t::INPUT_ESTIMATE == 1);

  CHECK(imu_sample_t::SAT_GYRO_X == 1);
  CHECK(imu_sample_t::SAT_GYRO_Y == 2);
  CHECK(imu_sample_t::SAT_GYRO_Z == 4);
  CHECK(imu_sample_t::SAT_ACCEL_X == 8);
  CHECK(imu_sample_t::SAT_ACCEL_Y == 16);
  CHECK(imu_sample_t::SAT_ACCEL_Z == 32);

  CHECK(heartbeat_t::STATE_STARTING == 0);
  CHECK(heartbeat_t::STATE_READY == 1);
  CHECK(heartbeat_t::STATE_RUNNING == 2);
  CHECK(heartbeat_t::STATE_STOPPING == 3);
  CHECK(heartbeat_t::STATE_FAULT == 4);
  CHECK(heartbeat_t::STATE_FINISHED == 5);

  CHECK(fault_event_t::SEVERITY_INFO == 0);
  CHECK(fault_event_t::SEVERITY_WARNING == 1);
  CHECK(fault_event_t::SEVERITY_ERROR == 2);
  CHECK(fault_event_t::SEVERITY_FATAL == 3);

  CHECK(fault_event_t::CODE_OTHER == 0);
  CHECK(fault_event_t::CODE_COMMAND_TIMEOUT == 1);
  CHECK(fault_event_t::CODE_MESSAGE_MALFORMED == 2);
  CHECK(fault_event_t::CODE_QUEUE_DROP == 3);
  CHECK(fault_event_t::CODE_DEADLINE_MISS == 4);
  CHECK(fault_event_t::CODE_PROCESS_EXIT == 5);
  CHECK(fault_event_t::CODE_CAN_ERROR_FRAME == 6);
  CHECK(fault_event_t::CODE_CONFIG_ERROR == 7);
  CHECK(fault_event_t::CODE_ESTIMATOR_DIVERGED == 8);
  CHECK(fault_event_t::CODE_HEARTBEAT_LOST == 9);
  CHECK(fault_event_t::CODE_STEP_ACK_TIMEOUT == 10);
  CHECK(fault_event_t::CODE_TRACKING_LOST == 11);
  CHECK(fault_event_t::CODE_REALTIME_UNAVAILABLE == 12);
  CHECK(fault_event_t::CODE_COMMAND_CLAMPED == 13);
  CHECK(fault_event_t::CODE_INPUT_STALE == 14);
  CHECK(fault_event_t::CODE_MEASUREMENT_OUT_OF_WINDOW == 15);
}
