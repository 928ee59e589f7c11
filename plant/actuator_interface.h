#pragma once
/// ActuatorInterface: the plant's end of the actuator link, without transport.
///
/// Decodes a received command into the plant's ActuatorInput (flapping frequencies given as
/// left/right or as collective and delta_f), rejects an unknown mode or a non-finite value,
/// clamps to the actuators' physical range, rounds to the interface's resolution
/// (plant.command_resolution) and holds the safe state (trim flapping frequencies, servos
/// neutral) when no command has come for plant.command_timeout_s of simulated time, until the
/// next valid command. What it raises comes back as ActuatorEvent values; the plant node
/// publishes them as FAULTs.

#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "plant/plant_model.h"

namespace nimble::plant {

/// How a command gives the flapping frequencies (the values of actuator_command_t::MODE_*).
enum class CommandMode : int8_t {
  kLeftRight = 0,  ///< flap_freq_left_radps and flap_freq_right_radps
  kDeltaF = 1,     ///< flap_freq_collective_radps and delta_f_radps (left - right)
};

/// A received actuator command (core/rig_values.h): the interface reads its seq, mode, flapping
/// frequencies and servo angles.
using nimble::ActuatorCommand;
static_assert(static_cast<int8_t>(CommandMode::kLeftRight) == ActuatorCommand::kModeLeftRight &&
                  static_cast<int8_t>(CommandMode::kDeltaF) == ActuatorCommand::kModeDeltaF,
              "CommandMode is the command's mode");

/// Something the interface reports.
struct ActuatorEvent {
  enum class Kind {
    kRejected,  ///< unknown mode or non-finite value: the command was ignored
    kClamped,   ///< a value outside the actuator range was clamped to it
    kTimeout,   ///< commands stopped: the safe state was entered
    kResumed,   ///< a valid command came in the safe state: the safe state was left
  };
  Kind kind;
  std::string message;  ///< what happened, naming the command's seq where there is one
};

/// Commands the interface did not apply as sent, since the start.
struct ActuatorCounters {
  int64_t rejected = 0;  ///< ignored (unknown mode, non-finite value)
  int64_t clamped = 0;   ///< applied clamped to the actuator range
};

class ActuatorInterface {
 public:
  /// Physical range of a flapping-frequency command [rad/s]: 0 to 40 Hz.
  static constexpr double kMaxFlapRadps = 2.0 * M_PI * 40.0;
  /// Physical range of a servo command, either sign [rad].
  static constexpr double kMaxServoRad = 1.0;

  /// Reads command_timeout_s and the command resolutions of `config`; `trim` is the safe
  /// state and the input until the first command.
  ActuatorInterface(const PlantConfig& config, const ActuatorInput& trim);

  /// What command() did with a command.
  struct Result {
    bool accepted = false;              ///< applied (perhaps clamped); false: ignored
    std::vector<ActuatorEvent> events;  ///< in the order raised
  };
  /// Applies `cmd`, received at simulated time `now_ns`. Never throws.
  Result command(const ActuatorCommand& cmd, int64_t now_ns);

  /// At each plant step (simulated time `now_ns` > 0): enters the safe state, and says so,
  /// when no command has come for command_timeout_s.
  std::optional<ActuatorEvent> update(int64_t now_ns);

  /// The input the plant applies: the last command, or the trim in the safe state.
  const ActuatorInput& input() const { return safe_state_ ? trim_ : command_; }
  bool safe_state() const { return safe_state_; }
  /// seq of the last applied command (-1: none yet).
  int64_t last_command_seq() const { return last_command_seq_; }
  /// Age of the last applied command at `now_ns` [us] (-1: none yet).
  int64_t command_age_us(int64_t now_ns) const { return have_command_ ? (now_ns - last_command_ns_) / 1000 : -1; }
  const ActuatorCounters& counters() const { return counters_; }

 private:
  double timeout_s_;
  int64_t timeout_ns_;
  double flap_resolution_radps_;
  double servo_resolution_rad_;
  ActuatorInput trim_;
  ActuatorInput command_;
  bool have_command_ = false;
  bool safe_state_ = false;
  int64_t last_command_ns_ = 0;
  int64_t last_command_seq_ = -1;
  ActuatorCounters counters_;
};

}  // namespace nimble::plant
