#pragma once
/// Conversions between the rig's stream messages (lcmtypes/) and the plain values the cores
/// produce and consume (core/rig_values.h), written once: every process,
/// the run monitor and the log readers convert at the bus through these, and
/// tests/functional/test_messages.cc checks that each round trip is exact.
///
///   truth_state_t       <-> Truth             plant -> mocap, controller, tools
///   imu_sample_t        <-> ImuSample         plant -> estimator
///   mocap_pose_t        <-> MocapPose         mocap -> estimator, controller (pilot)
///   actuator_command_t  <-> ActuatorCommand   controller, can_rig -> plant, can_flight
///   actuator_feedback_t <-> ActuatorFeedback  plant, can_flight -> can_rig, tools
///   attitude_setpoint_t <-> AttitudeSetpoint  controller -> tools
///   estimator_state_t   <-> Estimate          estimator -> controller, tools
///   controller_status_t <-> ControllerStatus  controller -> launcher, tools
///   can_health_t        <-> CanHealth         can_flight, can_rig -> launcher
///   fault_event_t       <-> FaultEvent        every process, launcher -> launcher
///
/// What a message carries beyond the value (utime, seq, step of a truth message) is an argument
/// of to_message(); what a value holds beyond the message (the truth's side gust, not on the
/// bus) comes back as its default.
///
/// A value whose fields have its message's names (the pairs from the actuator command on) is
/// bound field by field through the generated list (nimble/rig_message_list.hpp, from the .lcm
/// file): its pair is two lines here, and a field added to the .lcm that the value lacks does not
/// compile, naming the field. The IMU sample, the pose and the truth hold vectors and a quaternion where their
/// messages hold arrays; their conversions are written out in messages.cc.

#include <cstdint>

#include <nimble/rig_message_list.hpp>

#include "core/rig_values.h"

namespace nimble::contract {

imu_sample_t to_message(const ImuSample& sample);
ImuSample from_message(const imu_sample_t& message);

mocap_pose_t to_message(const MocapPose& pose);
/// The pose with its publication time: utime + latency_us.
MocapPose from_message(const mocap_pose_t& message);

/// `utime` [us] and `seq` of the message; `step` the plant's lockstep step (-1 in real time).
truth_state_t to_message(const Truth& truth, int64_t utime, int64_t seq, int64_t step);
/// The truth at the message's time (time_s = utime / 1e6); gust_v_mps 0 (not carried).
Truth from_message(const truth_state_t& message);

namespace detail {

/// One field of a value to its message's field or back: the same type, a number of another width
/// (LCM's boolean is int8_t), or a fixed-size vector and its array.
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

/// The message of a value with the message's field names, every field copied.
template <class Message, class Value>
Message message_of(const Value& value) {
  Message m{};
  nimble::bind_fields(
      value, m, [](const char*, const auto& value_field, auto& message_field) { assign(message_field, value_field); });
  return m;
}

/// The value of a message, every field of the message copied.
template <class Value, class Message>
Value value_of(const Message& m) {
  Value value;
  nimble::bind_fields(
      value, m, [](const char*, auto& value_field, const auto& message_field) { assign(value_field, message_field); });
  return value;
}

}  // namespace detail

inline actuator_command_t to_message(const ActuatorCommand& v) { return detail::message_of<actuator_command_t>(v); }
inline ActuatorCommand from_message(const actuator_command_t& m) { return detail::value_of<ActuatorCommand>(m); }

inline actuator_feedback_t to_message(const ActuatorFeedback& v) { return detail::message_of<actuator_feedback_t>(v); }
inline ActuatorFeedback from_message(const actuator_feedback_t& m) { return detail::value_of<ActuatorFeedback>(m); }

inline attitude_setpoint_t to_message(const AttitudeSetpoint& v) { return detail::message_of<attitude_setpoint_t>(v); }
inline AttitudeSetpoint from_message(const attitude_setpoint_t& m) { return detail::value_of<AttitudeSetpoint>(m); }

inline estimator_state_t to_message(const Estimate& v) { return detail::message_of<estimator_state_t>(v); }
inline Estimate from_message(const estimator_state_t& m) { return detail::value_of<Estimate>(m); }

inline controller_status_t to_message(const ControllerStatus& v) { return detail::message_of<controller_status_t>(v); }
inline ControllerStatus from_message(const controller_status_t& m) { return detail::value_of<ControllerStatus>(m); }

inline can_health_t to_message(const CanHealth& v) { return detail::message_of<can_health_t>(v); }
inline CanHealth from_message(const can_health_t& m) { return detail::value_of<CanHealth>(m); }

inline fault_event_t to_message(const FaultEvent& v) { return detail::message_of<fault_event_t>(v); }
inline FaultEvent from_message(const fault_event_t& m) { return detail::value_of<FaultEvent>(m); }

}  // namespace nimble::contract
