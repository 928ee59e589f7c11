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

#include <cstdint>

#include <nimble/actuator_command_t.hpp>
#include <nimble/actuator_feedback_t.hpp>
#include <nimble/attitude_setpoint_t.hpp>
#include <nimble/can_health_t.hpp>
#include <nimble/controller_status_t.hpp>
#include <nimble/estimator_state_t.hpp>
#include <nimble/fault_event_t.hpp>
#include <nimble/imu_sample_t.hpp>
#include <nimble/mocap_pose_t.hpp>
#include <nimble/truth_state_t.hpp>

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

actuator_command_t to_message(const ActuatorCommand& command);
ActuatorCommand from_message(const actuator_command_t& message);

actuator_feedback_t to_message(const ActuatorFeedback& feedback);
ActuatorFeedback from_message(const actuator_feedback_t& message);

attitude_setpoint_t to_message(const AttitudeSetpoint& setpoint);
AttitudeSetpoint from_message(const attitude_setpoint_t& message);

estimator_state_t to_message(const Estimate& estimate);
Estimate from_message(const estimator_state_t& message);

controller_status_t to_message(const ControllerStatus& status);
ControllerStatus from_message(const controller_status_t& message);

can_health_t to_message(const CanHealth& health);
CanHealth from_message(const can_health_t& message);

fault_event_t to_message(const FaultEvent& fault);
FaultEvent from_message(const fault_event_t& message);

}  // namespace nimble::contract
