#include "contract/faults.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <iterator>

#include <nimble/rig_message_list.hpp>

#include "contract/channels.h"

namespace nimble::contract {
namespace {

/// The double fields that are not values a fault may change: statistics of the estimate (its
/// covariance, the last innovation's NIS), which no sensor or link fault would alter on its own.
/// Every other double field of a message is a value field.
constexpr std::pair<const char*, const char*> kNotValueFields[] = {
    {"estimator_state_t", "cov_diag"},
    {"estimator_state_t", "last_nis"},
};

bool is_value_field(const char* type, const char* field) {
  return std::none_of(std::begin(kNotValueFields), std::end(kNotValueFields), [&](const auto& excluded) {
    return std::strcmp(excluded.first, type) == 0 && std::strcmp(excluded.second, field) == 0;
  });
}

/// Collects the value fields of a message of type `type` from its field visitor.
struct ValueFieldCollector {
  const char* type;
  ValueFields& out;

  void operator()(const char* name, double& value) const {
    if (is_value_field(type, name)) out.emplace_back(name, &value);
  }
  template <std::size_t N>
  void operator()(const char* name, double (&values)[N]) const {
    if (!is_value_field(type, name)) return;
    for (std::size_t i = 0; i < N; ++i) out.emplace_back(std::string(name) + "[" + std::to_string(i) + "]", &values[i]);
  }
  /// Not a double or a fixed array of them: utime, seq, counters, flags, strings, variable-length arrays.
  template <class Other>
  void operator()(const char*, Other&) const {}
};

}  // namespace

template <class Message>
ValueFields value_fields(Message& m) {
  ValueFields out;
  for_each_field(m, ValueFieldCollector{Message::getTypeName(), out});
  return out;
}
#define NIMBLE_VALUE_FIELDS_OF(T) template ValueFields value_fields<T>(T&);
NIMBLE_RIG_MESSAGES(NIMBLE_VALUE_FIELDS_OF)
#undef NIMBLE_VALUE_FIELDS_OF

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
      "OTHER",
      "COMMAND_TIMEOUT",
      "MESSAGE_MALFORMED",
      "QUEUE_DROP",
      "DEADLINE_MISS",
      "PROCESS_EXIT",
      "CAN_ERROR_FRAME",
      "CONFIG_ERROR",
      "ESTIMATOR_DIVERGED",
      "HEARTBEAT_LOST",
      "STEP_ACK_TIMEOUT",
      "TRACKING_LOST",
      "REALTIME_UNAVAILABLE",
      "COMMAND_CLAMPED",
      "INPUT_STALE",
      "MEASUREMENT_OUT_OF_WINDOW",
      "FAULT_INJECTED",
      "SENSOR_STUCK",
      "FAILSAFE",
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

std::vector<std::string> value_field_names(const std::string& channel) {
  const std::vector<std::string>& targets = fault_channel_targets();
  const ChannelSpec* spec = find_channel(channel);
  std::vector<std::string> out;
  if (spec == nullptr || std::find(targets.begin(), targets.end(), channel) == targets.end()) return out;
  with_message_type(spec->type, [&out](auto type) {
    typename decltype(type)::type m{};
    for (const auto& f : value_fields(m)) out.push_back(f.first);
  });
  return out;
}

bool field_selected(const std::string& selector, const std::string& name) {
  if (selector.empty() || selector == name) return true;
  // "gyro_radps" selects "gyro_radps[0]".."gyro_radps[2]".
  return name.size() > selector.size() && name.compare(0, selector.size(), selector) == 0 &&
         name[selector.size()] == '[';
}

}  // namespace nimble::contract
