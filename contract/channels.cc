#include "contract/channels.h"

namespace nimble::contract {

using namespace channels;

namespace {

const std::string kEvery = "every process";
const std::string kIdent = "`rig ident` (from the run log)";

}  // namespace

const std::vector<ChannelSpec>& channel_table() {
  static const std::vector<ChannelSpec> table = {
      {kTruth,
       "truth_state_t",
       "`plant.truth_rate_hz` (default 1 kHz)",
       {"plant"},
       {"mocap", "controller (`run.controller_input: truth`)", "launcher", kIdent}},
      {kImu,
       "imu_sample_t",
       "`sensing.imu.sample_rate_hz` (default 512 Hz)",
       {"plant (emulated onboard IMU)"},
       {"estimator", kIdent}},
      {kMocapPose,
       "mocap_pose_t",
       "`sensing.mocap.frame_rate_hz` (default 200 Hz)",
       {"mocap"},
       {"estimator", "controller (`pilot.enabled`: the pilot's height)", "launcher (lateness from `latency_us`)"}},
      {kAttitudeSetpoint,
       "attitude_setpoint_t",
       "`controller.rate_hz` (default 512 Hz)",
       {"controller (manoeuvre player)"},
       {kIdent}},
      {kEstimate,
       "estimator_state_t",
       "one per IMU sample",
       {"estimator"},
       {"controller (`run.controller_input: estimate`)", "launcher", kIdent}},
      {kActuatorCommand,
       "actuator_command_t",
       "`controller.rate_hz` (one per control cycle)",
       {"controller"},
       {"plant (`actuator_link: lcm`)", "can_flight (`actuator_link: can`)", kIdent}},
      {kActuatorCommandCan,
       "actuator_command_t",
       "`controller.rate_hz`",
       {"can_rig (commands decoded from CAN frames)"},
       {"plant (`actuator_link: can`)"}},
      {kActuatorFeedback,
       "actuator_feedback_t",
       "`plant.feedback_rate_hz` (default 100 Hz)",
       {"plant"},
       {"can_rig (`actuator_link: can`)", "estimator (`sensing.imu_prefilter.enabled`)", kIdent}},
      {kActuatorFeedbackCan,
       "actuator_feedback_t",
       "`plant.feedback_rate_hz`",
       {"can_flight (feedback decoded from CAN frames)"},
       {}},
      {kCanHealth,
       "can_health_t",
       "`can_bridge.health_rate_hz` per side (default 2 Hz, wall clock) and at exit",
       {"can_flight", "can_rig"},
       {"launcher"},
       true},
      {kControllerStatus,
       "controller_status_t",
       "`controller.rate_hz` (one per control cycle)",
       {"controller"},
       {kIdent}},
      {kRigClock,
       "rig_clock_t",
       "at each plant step where a participant is due (lockstep only)",
       {"plant"},
       {"every lockstep participant", "launcher (its logger is a participant)"}},
      {kStepAck,
       "step_ack_t",
       "once per step at which the participant is due (lockstep only)",
       {"every lockstep participant", "launcher (every `lockstep.logger_period_ms` of simulated time)"},
       {"plant"}},
      {kRunControl, "run_control_t", "on start and stop", {"launcher"}, {kEvery}, true},
      {kHeartbeat, "heartbeat_t", "2 Hz per process (10 Hz before the start)", {kEvery}, {"launcher"}, true},
      {kTimingHealth, "timing_health_t", "1 Hz per process", {kEvery}, {"launcher"}, true},
      {kFault, "fault_event_t", "on event (rate-limited per code)", {kEvery}, {"launcher"}, true},
  };
  return table;
}

const std::vector<std::string>& types_without_channel() {
  static const std::vector<std::string> types = {};
  return types;
}

const ChannelSpec* find_channel(const std::string& name) {
  for (const auto& c : channel_table()) {
    if (c.name == name) return &c;
  }
  return nullptr;
}

bool due_in_sim_time(const std::string& name) {
  const ChannelSpec* spec = find_channel(name);
  return spec != nullptr && !spec->wall_clock && name != channels::kRigClock && name != channels::kStepAck;
}

bool single_publisher(const std::string& name) {
  const ChannelSpec* spec = find_channel(name);
  return spec != nullptr && spec->publishers.size() == 1 && spec->publishers[0].find("every") == std::string::npos;
}

std::vector<std::string> wall_clock_channels() {
  std::vector<std::string> out;
  for (const auto& c : channel_table()) {
    if (c.wall_clock) out.push_back(c.name);
  }
  return out;
}

const std::string& plant_command_channel(bool can_link) { return can_link ? kActuatorCommandCan : kActuatorCommand; }

std::string markdown_row(const ChannelSpec& spec) {
  const auto join = [](const std::vector<std::string>& items) {
    if (items.empty()) return std::string("—");
    std::string out;
    for (const auto& item : items) out += (out.empty() ? "" : ", ") + item;
    return out;
  };
  return "| `" + spec.name + "` | `" + spec.type + "` | " + spec.rate + " | " + join(spec.publishers) + " | " +
         join(spec.subscribers) + " |";
}

}  // namespace nimble::contract
