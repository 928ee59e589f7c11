#include "contract/faults.h"

#include <cstdio>

#include "contract/channels.h"

namespace nimble::contract {
namespace {

void add(ValueFields& out, const std::string& name, double* values, int n) {
  for (int i = 0; i < n; ++i) out.emplace_back(name + "[" + std::to_string(i) + "]", values + i);
}
void add(ValueFields& out, const std::string& name, double* value) { out.emplace_back(name, value); }

template <typename T>
std::vector<std::string> names_of() {
  T m{};
  std::vector<std::string> out;
  for (const auto& f : value_fields(m)) out.push_back(f.first);
  return out;
}

}  // namespace

const std::vector<FaultKindInfo>& fault_kinds() {
  static const std::vector<FaultKindInfo> kinds = {
      {FaultKind::kOff, "off", FaultTarget::kChannel, ""},
      {FaultKind::kStuck, "stuck", FaultTarget::kChannel, ""},
      {FaultKind::kGarbage, "garbage", FaultTarget::kChannel, "mode (bytes | nan), field"},
      {FaultKind::kWrong, "wrong", FaultTarget::kChannel, "scale, bias, field"},
      {FaultKind::kSlow, "slow", FaultTarget::kChannel, "divisor"},
      {FaultKind::kDelayed, "delayed", FaultTarget::kChannel, "delay_ms"},
      {FaultKind::kIntermittent, "intermittent", FaultTarget::kChannel, "probability"},
      {FaultKind::kCanLoss, "loss", FaultTarget::kCanLink, "probability"},
      {FaultKind::kCanCorrupt, "corrupt", FaultTarget::kCanLink, "probability"},
      {FaultKind::kCanBusOff, "bus_off", FaultTarget::kCanLink, ""},
  };
  return kinds;
}

const char* fault_kind_name(FaultKind kind) {
  for (const FaultKindInfo& k : fault_kinds()) {
    if (k.kind == kind) return k.name;
  }
  return "?";
}

std::string fault_code_name(int32_t code) {
  // fault_event_t's CODE_* constants, by value.
  static const char* const kNames[] = {
      "OTHER",          "COMMAND_TIMEOUT",   "MESSAGE_MALFORMED", "QUEUE_DROP",
      "DEADLINE_MISS",  "PROCESS_EXIT",      "CAN_ERROR_FRAME",   "CONFIG_ERROR",
      "ESTIMATOR_DIVERGED", "HEARTBEAT_LOST", "STEP_ACK_TIMEOUT", "TRACKING_LOST",
      "REALTIME_UNAVAILABLE", "COMMAND_CLAMPED", "INPUT_STALE",   "MEASUREMENT_OUT_OF_WINDOW",
      "FAULT_INJECTED", "SENSOR_STUCK",      "FAILSAFE",
  };
  if (code >= 0 && code < static_cast<int32_t>(sizeof kNames / sizeof kNames[0])) return kNames[code];
  return "code " + std::to_string(code);
}

const std::vector<std::string>& fault_channel_targets() {
  static const std::vector<std::string> targets = {channels::kImu, channels::kMocapPose, channels::kEstimate,
                                                   channels::kActuatorCommand, channels::kActuatorFeedback};
  return targets;
}

std::string FaultSpec::describe() const {
  char window[96];
  if (end_us == std::numeric_limits<int64_t>::max()) {
    std::snprintf(window, sizeof window, "from %.3f s", 1e-6 * static_cast<double>(start_us));
  } else {
    std::snprintf(window, sizeof window, "%.3f-%.3f s", 1e-6 * static_cast<double>(start_us),
                  1e-6 * static_cast<double>(end_us));
  }
  std::string what = target + " " + fault_kind_name(kind);
  char param[128] = "";
  switch (kind) {
    case FaultKind::kGarbage: std::snprintf(param, sizeof param, " (%s)", garbage_nan ? "nan" : "bytes"); break;
    case FaultKind::kWrong:
      std::snprintf(param, sizeof param, " (%s * %g %+g)", field.empty() ? "every value" : field.c_str(), scale, bias);
      break;
    case FaultKind::kSlow: std::snprintf(param, sizeof param, " (1 in %d)", divisor); break;
    case FaultKind::kDelayed: std::snprintf(param, sizeof param, " %g ms", 1e-3 * static_cast<double>(delay_us)); break;
    case FaultKind::kIntermittent:
    case FaultKind::kCanLoss:
    case FaultKind::kCanCorrupt: std::snprintf(param, sizeof param, " (p = %g)", probability); break;
    case FaultKind::kOff:
    case FaultKind::kStuck:
    case FaultKind::kCanBusOff: break;  // no parameter
  }
  return "fault " + std::to_string(index) + " (" + what + param + ", " + window + ")";
}

ValueFields value_fields(imu_sample_t& m) {
  ValueFields out;
  add(out, "gyro_radps", m.gyro_radps, 3);
  add(out, "accel_mps2", m.accel_mps2, 3);
  add(out, "temperature_degc", &m.temperature_degc);
  return out;
}

ValueFields value_fields(mocap_pose_t& m) {
  ValueFields out;
  add(out, "position_m", m.position_m, 3);
  add(out, "quaternion_wxyz", m.quaternion_wxyz, 4);
  add(out, "mean_marker_error_m", &m.mean_marker_error_m);
  return out;
}

ValueFields value_fields(estimator_state_t& m) {
  ValueFields out;
  add(out, "euler_rad", m.euler_rad, 3);
  add(out, "velocity_body_mps", m.velocity_body_mps, 3);
  add(out, "gyro_bias_radps", m.gyro_bias_radps, 3);
  add(out, "accel_bias_mps2", m.accel_bias_mps2, 3);
  add(out, "omega_body_radps", m.omega_body_radps, 3);
  return out;
}

ValueFields value_fields(actuator_command_t& m) {
  ValueFields out;
  add(out, "flap_freq_left_radps", &m.flap_freq_left_radps);
  add(out, "flap_freq_right_radps", &m.flap_freq_right_radps);
  add(out, "delta_f_radps", &m.delta_f_radps);
  add(out, "flap_freq_collective_radps", &m.flap_freq_collective_radps);
  add(out, "throttle_pct", &m.throttle_pct);
  add(out, "dihedral_rad", &m.dihedral_rad);
  add(out, "wing_root_rad", &m.wing_root_rad);
  return out;
}

ValueFields value_fields(actuator_feedback_t& m) {
  ValueFields out;
  add(out, "flap_freq_left_radps", &m.flap_freq_left_radps);
  add(out, "flap_freq_right_radps", &m.flap_freq_right_radps);
  add(out, "delta_f_radps", &m.delta_f_radps);
  add(out, "dihedral_rad", &m.dihedral_rad);
  add(out, "wing_root_rad", &m.wing_root_rad);
  add(out, "throttle_pct", &m.throttle_pct);
  return out;
}

std::vector<std::string> value_field_names(const std::string& channel) {
  if (channel == channels::kImu) return names_of<imu_sample_t>();
  if (channel == channels::kMocapPose) return names_of<mocap_pose_t>();
  if (channel == channels::kEstimate) return names_of<estimator_state_t>();
  if (channel == channels::kActuatorCommand) return names_of<actuator_command_t>();
  if (channel == channels::kActuatorFeedback) return names_of<actuator_feedback_t>();
  return {};
}

bool field_selected(const std::string& selector, const std::string& name) {
  if (selector.empty() || selector == name) return true;
  // "gyro_radps" selects "gyro_radps[0]".."gyro_radps[2]".
  return name.size() > selector.size() && name.compare(0, selector.size(), selector) == 0 &&
         name[selector.size()] == '[';
}

}  // namespace nimble::contract
