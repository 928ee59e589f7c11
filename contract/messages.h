#pragma once
/// Conversions between the rig's messages (lcmtypes/) and the plain data of the cores that
/// produce and consume them, written once: every process converts at the bus through these,
/// and tests/functional/test_messages.cc checks that each round trip is exact.
///
///   imu_sample_t      <-> ImuSample        (sensors/sensor_types.h)  plant -> estimator
///   mocap_pose_t      <-> MocapPose        (sensors/sensor_types.h)  mocap -> estimator
///   truth_state_t     <-> plant::Truth     (plant/plant_model.h)     plant -> mocap, controller, tools
///   actuator_command_t -> plant::ActuatorCommand (plant/actuator_interface.h)  -> plant
///
/// What a message carries beyond the core type (utime, seq, step of a truth message) is an
/// argument of to_message(); what a core type holds beyond the message (the truth's side gust,
/// not on the bus) comes back as its default.

#include <cstdint>

#include <nimble/actuator_command_t.hpp>
#include <nimble/imu_sample_t.hpp>
#include <nimble/mocap_pose_t.hpp>
#include <nimble/truth_state_t.hpp>

#include "plant/actuator_interface.h"
#include "plant/plant_model.h"
#include "sensors/sensor_types.h"

namespace nimble::contract {

imu_sample_t to_message(const ImuSample& sample);
ImuSample from_message(const imu_sample_t& message);

mocap_pose_t to_message(const MocapPose& pose);
/// The pose with its publication time: utime + latency_us.
MocapPose from_message(const mocap_pose_t& message);

/// `utime` [us] and `seq` of the message; `step` the plant's lockstep step (-1 in real time).
truth_state_t to_message(const plant::Truth& truth, int64_t utime, int64_t seq, int64_t step);
/// The truth at the message's time (time_s = utime / 1e6); gust_v_mps 0 (not carried).
plant::Truth from_message(const truth_state_t& message);

/// The fields of a command the plant's actuator interface reads.
plant::ActuatorCommand from_message(const actuator_command_t& message);

}  // namespace nimble::contract
