#pragma once
/// The rig's channels: their names (the only place they are spelled), the type each carries,
/// its nominal rate, publishers and subscribers. lcmtypes/README.md shows the same table;
/// tests/functional/test_contract.cc fails when the two differ.

#include <string>
#include <vector>

namespace nimble::contract {

/// Channel names of the rig.
namespace channels {
inline const std::string kTruth = "TRUTH";
inline const std::string kImu = "IMU";
inline const std::string kMocapPose = "MOCAP_POSE";
inline const std::string kAttitudeSetpoint = "ATTITUDE_SP";
inline const std::string kEstimate = "ESTIMATE";
inline const std::string kActuatorCommand = "ACTUATOR_CMD";
inline const std::string kActuatorFeedback = "ACTUATOR_FB";
/// Commands as the rig side of the CAN link decoded them (actuator_link: can): the plant's input.
inline const std::string kActuatorCommandCan = "ACTUATOR_CMD_CAN";
/// Feedback as the flight-board side of the CAN link decoded it (actuator_link: can).
inline const std::string kActuatorFeedbackCan = "ACTUATOR_FB_CAN";
inline const std::string kCanHealth = "CAN_HEALTH";
inline const std::string kControllerStatus = "CONTROLLER_STATUS";
inline const std::string kRigClock = "RIG_CLOCK";
inline const std::string kStepAck = "STEP_ACK";
inline const std::string kRunControl = "RUN_CONTROL";
inline const std::string kHeartbeat = "HEARTBEAT";
inline const std::string kTimingHealth = "TIMING_HEALTH";
inline const std::string kFault = "FAULT";
}  // namespace channels

/// One channel of the contract. Publishers and subscribers are process names (`plant`,
/// `controller`, `estimator`, `mocap`, `can_flight`, `can_rig`, `launcher`), "every process"
/// (every rig process), or a reader of the run log, each with an optional condition in
/// parentheses. The launcher records and counts every channel; it is listed as a subscriber
/// only where it uses the content.
struct ChannelSpec {
  std::string name;
  std::string type;  ///< LCM type of package nimble, e.g. "truth_state_t"
  std::string rate;  ///< nominal rate and the configuration key that sets it
  std::vector<std::string> publishers;
  std::vector<std::string> subscribers;
  bool wall_clock = false;  ///< paced by the wall clock: its rate counts per wall second
};

/// Every channel of the rig, in the order of lcmtypes/README.md.
const std::vector<ChannelSpec>& channel_table();

/// The message types of lcmtypes/ that no channel carries, declared so: every other type has a
/// row in channel_table(), and functional.message_list fails for a type that has neither. None
/// today.
const std::vector<std::string>& types_without_channel();

/// The channel called `name`, or nullptr.
const ChannelSpec* find_channel(const std::string& name);

/// True if `name` is a stream the rig publishes at its simulated time (utime): in real time each
/// message is due at t0 + utime (a motion-capture pose latency_us later), and can be late. Not
/// the wall-clock channels, nor the lockstep clock's RIG_CLOCK and STEP_ACK.
bool due_in_sim_time(const std::string& name);

/// True if `name` has exactly one publishing process (its seq is one sequence).
bool single_publisher(const std::string& name);

/// Names of the channels whose publishers pace themselves by the wall clock.
std::vector<std::string> wall_clock_channels();

/// The channel the plant takes its actuator commands from: ACTUATOR_CMD_CAN over the CAN
/// link (`actuator_link: can`), ACTUATOR_CMD otherwise.
const std::string& plant_command_channel(bool can_link);

/// The row of lcmtypes/README.md's channel table for `spec` (Markdown, no line break).
std::string markdown_row(const ChannelSpec& spec);

}  // namespace nimble::contract
