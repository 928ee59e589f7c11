#include "plant/actuator_interface.h"

#include <cmath>
#include <utility>

namespace nimble::plant {
namespace {

/// `x` rounded to a multiple of `resolution` (unchanged for 0). Computed as the CAN decoder
/// computes a physical value, raw * factor, so that a value that crossed the CAN link is
/// left exactly as it is.
double quantize(double x, double resolution) {
  if (!(resolution > 0.0)) return x;
  return static_cast<double>(std::llround(x / resolution)) * resolution;
}

double clamp(double x, double lo, double hi, bool& clamped) {
  if (x < lo) {
    clamped = true;
    return lo;
  }
  if (x > hi) {
    clamped = true;
    return hi;
  }
  return x;
}

}  // namespace

ActuatorInterface::ActuatorInterface(const PlantConfig& config, const ActuatorInput& trim)
    : timeout_s_(config.command_timeout_s),
      timeout_ns_(std::llround(config.command_timeout_s * 1e9)),
      flap_resolution_radps_(config.flap_command_resolution_radps),
      servo_resolution_rad_(config.servo_command_resolution_rad),
      trim_(trim),
      command_(trim) {}

ActuatorInterface::Result ActuatorInterface::command(const ActuatorCommand& cmd, int64_t now_ns) {
  Result result;
  const auto reject = [&](const std::string& why) {
    ++counters_.rejected;
    result.events.push_back(
        {ActuatorEvent::Kind::kRejected, "rejected actuator command seq " + std::to_string(cmd.seq) + ": " + why});
    return result;
  };
  double left = cmd.flap_freq_left_radps, right = cmd.flap_freq_right_radps;
  if (cmd.mode == static_cast<int8_t>(CommandMode::kDeltaF)) {
    left = cmd.flap_freq_collective_radps + 0.5 * cmd.delta_f_radps;
    right = cmd.flap_freq_collective_radps - 0.5 * cmd.delta_f_radps;
  } else if (cmd.mode != static_cast<int8_t>(CommandMode::kLeftRight)) {
    return reject("unknown mode " + std::to_string(cmd.mode));
  }
  for (const auto& [name, value] : {std::pair<const char*, double>{"flap_freq_left_radps", left},
                                    {"flap_freq_right_radps", right},
                                    {"dihedral_rad", cmd.dihedral_rad},
                                    {"wing_root_rad", cmd.wing_root_rad}}) {
    if (!std::isfinite(value)) return reject(std::string(name) + " is not finite");
  }
  bool clamped = false;
  const double rf = flap_resolution_radps_, rs = servo_resolution_rad_;
  command_.flap_freq_left_radps = quantize(clamp(left, 0.0, kMaxFlapRadps, clamped), rf);
  command_.flap_freq_right_radps = quantize(clamp(right, 0.0, kMaxFlapRadps, clamped), rf);
  command_.dihedral_rad = quantize(clamp(cmd.dihedral_rad, -kMaxServoRad, kMaxServoRad, clamped), rs);
  command_.wing_root_rad = quantize(clamp(cmd.wing_root_rad, -kMaxServoRad, kMaxServoRad, clamped), rs);
  if (clamped) {
    ++counters_.clamped;
    result.events.push_back({ActuatorEvent::Kind::kClamped,
                             "clamped actuator command seq " + std::to_string(cmd.seq) + " to the actuator range"});
  }
  result.accepted = true;
  have_command_ = true;
  last_command_ns_ = now_ns;
  last_command_seq_ = cmd.seq;
  if (safe_state_) {
    safe_state_ = false;
    result.events.push_back({ActuatorEvent::Kind::kResumed, "actuator commands resumed; leaving the safe state"});
  }
  return result;
}

std::optional<ActuatorEvent> ActuatorInterface::update(int64_t now_ns) {
  if (safe_state_ || now_ns - last_command_ns_ <= timeout_ns_) return std::nullopt;
  safe_state_ = true;
  return ActuatorEvent{ActuatorEvent::Kind::kTimeout,
                       std::string("no actuator command for ") + std::to_string(timeout_s_) + " s" +
                           (have_command_ ? "" : " since the start") +
                           ": holding the safe state (trim flapping frequencies, servos neutral)"};
}

}  // namespace nimble::plant
