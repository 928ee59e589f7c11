#pragma once
/// Faults injected into a run from its scenario (`faults:`), after PX4's failure injection.
///
/// A fault acts on one target (a channel, or the CAN link) from start_s for duration_s of
/// simulated time. It is applied in the transport at the publisher (transport/fault_injector.h),
/// so every consumer sees the same fault and a lockstep run stays deterministic. This file is
/// the plain data and the per-type value fields; scenario/fault_section.h reads and validates the
/// section, transport/fault_injector.h applies it.

#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace nimble::contract {

/// What a fault does to its target's messages while it is active.
enum class FaultKind {
  kOff,           ///< nothing is published (a sensor or link that stopped)
  kStuck,         ///< the last message before the fault is repeated with fresh utime and seq
  kGarbage,       ///< malformed bytes (mode bytes) or non-finite values (mode nan)
  kWrong,         ///< value fields scaled and biased: value * scale + bias
  kSlow,          ///< the rate divided: one message in `divisor` is published
  kDelayed,       ///< each message published delay_ms after its time, in order
  kIntermittent,  ///< each message lost with `probability` (a gap in seq)
  kCanLoss,       ///< CAN link: each frame lost with `probability`
  kCanCorrupt,    ///< CAN link: a bit of each frame flipped with `probability`
  kCanBusOff,     ///< CAN link: the transmitting controller goes bus-off (sends nothing, reports it)
};

/// What a kind of fault acts on.
enum class FaultTarget {
  kChannel,  ///< an LCM channel at its publisher (transport/fault_injector.h)
  kCanLink,  ///< the CAN frames between the two sides of the bridge (can_bridge/can_faults.h)
};

/// One kind of fault as the rig knows it. fault_kinds() is the one list of them: the scenario
/// loader takes its names and parameters from it, and every switch over FaultKind that acts on
/// a fault (its parameters in scenario/fault_section.cc, its injection in transport/fault_injector.cc
/// or can_bridge/can_faults.cc, its description) has no `default:`, so that a new kind does not
/// compile until each of them handles it (docs/faults.md, "Adding a fault kind").
struct FaultKindInfo {
  FaultKind kind;
  const char* name;  ///< in a scenario's `kind:`
  FaultTarget target;
  const char* params;  ///< its `params:` keys, as docs/faults.md lists them ("" for none)
};

/// Every kind, in the order of the enumeration.
const std::vector<FaultKindInfo>& fault_kinds();

/// The name of `kind` in a scenario (off, stuck, garbage, wrong, slow, delayed, intermittent,
/// loss, corrupt, bus_off).
const char* fault_kind_name(FaultKind kind);

/// The target that stands for the CAN link (the frames between the two sides of the bridge).
inline const std::string kFaultTargetCan = "CAN";

/// The channels a fault may target, in the order docs/faults.md lists them.
const std::vector<std::string>& fault_channel_targets();

/// One entry of the scenario's `faults` list.
struct FaultSpec {
  int index = 0;       ///< position in the list (names the fault; seeds its random choices)
  std::string target;  ///< a channel of fault_channel_targets(), or kFaultTargetCan
  FaultKind kind = FaultKind::kOff;
  int64_t start_us = 0;                                  ///< simulated time it starts [us]
  int64_t end_us = std::numeric_limits<int64_t>::max();  ///< simulated time it ends [us]
  // Parameters (those of the kind; the others keep their defaults).
  bool garbage_nan = false;  ///< garbage: non-finite values (true) or malformed bytes (false)
  std::string field;         ///< wrong, garbage nan: the value fields touched ("" = all); a name or name[i]
  double scale = 1.0;        ///< wrong
  double bias = 0.0;         ///< wrong, in the field's unit
  int divisor = 2;           ///< slow
  int64_t delay_us = 0;      ///< delayed
  double probability = 0.0;  ///< intermittent, loss, corrupt

  bool active_at(int64_t utime) const { return utime >= start_us && utime < end_us; }
  /// "fault 2 (MOCAP_POSE delayed 50 ms, 1.000-2.000 s)".
  std::string describe() const;
};

/// The name of a fault_event_t code without its prefix ("MESSAGE_MALFORMED"); "code N" if unknown.
std::string fault_code_name(int32_t code);

/// The value fields of a message that faults may change (wrong, garbage nan): physical
/// quantities only, never utime, seq, counters or flags. Name and address of each element.
using ValueFields = std::vector<std::pair<std::string, double*>>;
/// Every double field of message `m` (a scalar, or each element of a fixed-size array, in .lcm
/// order, from the generated list nimble/rig_message_list.hpp), except the few that are
/// statistics of a value rather than a value (faults.cc lists them: the estimate's cov_diag and
/// last_nis). Defined in faults.cc for every message type.
template <class Message>
ValueFields value_fields(Message& m);

/// The value field names of the message on `channel` (a fault target), e.g. "gyro_radps[0]".
std::vector<std::string> value_field_names(const std::string& channel);

/// True if field selector `selector` ("" = all, "gyro_radps" = every element, "gyro_radps[1]")
/// selects the field called `name`.
bool field_selected(const std::string& selector, const std::string& name);

}  // namespace nimble::contract
