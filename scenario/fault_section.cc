#include "scenario/fault_section.h"

#include <algorithm>
#include <cmath>

#include "contract/channels.h"
#include "core/config.h"

namespace nimble {
namespace {

using contract::FaultKind;

/// The process that publishes `channel` in a run: the contract's single publisher (its first
/// word: "plant (emulated onboard IMU)" is the plant).
std::string publisher_of(const std::string& channel) {
  const contract::ChannelSpec* spec = contract::find_channel(channel);
  if (spec == nullptr || spec->publishers.empty()) return "";
  const std::string& p = spec->publishers.front();
  return p.substr(0, p.find(' '));
}

std::string join(const std::vector<std::string>& v) {
  std::string out;
  for (const auto& s : v) out += (out.empty() ? "" : ", ") + s;
  return out;
}

}  // namespace

std::vector<contract::FaultSpec> faults_from(const YAML::Node& faults, const std::string& file,
                                             const std::vector<std::string>& processes, bool can_link,
                                             double duration_s) {
  std::vector<contract::FaultSpec> out;
  if (!faults || faults.IsNull()) return out;
  if (!faults.IsSequence()) {
    throw ConfigError(file, "faults", "", "must be a list of {target, kind, start_s, duration_s, params}");
  }
  for (std::size_t i = 0; i < faults.size(); ++i) {
    const std::string path = "faults[" + std::to_string(i) + "]";
    if (!faults[i].IsMap()) throw ConfigError(file, path, "", "must be a mapping {target, kind, start_s, ...}");
    ConfigMap m(faults[i], file, path);
    contract::FaultSpec f;
    f.index = static_cast<int>(i);
    std::vector<std::string> targets = contract::fault_channel_targets();
    targets.push_back(contract::kFaultTargetCan);
    f.target = m.get_enum("target", targets);
    const bool can = f.target == contract::kFaultTargetCan;
    // The kinds of this target, from the one list of kinds (contract/faults.h).
    const contract::FaultTarget target_class = can ? contract::FaultTarget::kCanLink : contract::FaultTarget::kChannel;
    std::vector<std::string> kind_names;
    for (const contract::FaultKindInfo& k : contract::fault_kinds()) {
      if (k.target == target_class) kind_names.push_back(k.name);
    }
    const std::string kind = m.get_enum("kind", kind_names);
    for (const contract::FaultKindInfo& k : contract::fault_kinds()) {
      if (k.target == target_class && kind == k.name) f.kind = k.kind;
    }

    const double start_s = m.get_double("start_s", Range::non_negative());
    if (start_s >= duration_s) {
      m.fail("start_s", "starts at or after the end of the run (duration_s " + std::to_string(duration_s) + ")");
    }
    f.start_us = static_cast<int64_t>(std::llround(start_s * 1e6));
    if (m.has("duration_s")) {
      const double d = m.get_double("duration_s", Range::positive());
      f.end_us = f.start_us + static_cast<int64_t>(std::llround(d * 1e6));
    }

    if (can) {
      if (!can_link) m.fail("target", "the CAN link is faulted only in a run with actuator_link: can");
    } else {
      const std::string publisher = publisher_of(f.target);
      if (std::find(processes.begin(), processes.end(), publisher) == processes.end()) {
        m.fail("target", f.target + " is published by the " + publisher +
                             ", which this run does not start (processes: " + join(processes) + ")");
      }
    }

    // Parameters of the kind, strictly: a key the kind does not take is an error.
    ConfigMap p =
        m.has("params") ? m.get_map("params") : ConfigMap(YAML::Node(YAML::NodeType::Map), file, path + ".params");
    switch (f.kind) {
      case FaultKind::kGarbage:
        f.garbage_nan = p.has("mode") && p.get_enum("mode", {"bytes", "nan"}) == "nan";
        if (f.garbage_nan && p.has("field")) f.field = p.get_string("field");
        break;
      case FaultKind::kWrong:
        f.scale = p.get_double_or("scale", 1.0, Range::closed(-1e6, 1e6));
        f.bias = p.get_double_or("bias", 0.0, Range::closed(-1e6, 1e6));
        if (p.has("field")) f.field = p.get_string("field");
        if (f.scale == 1.0 && f.bias == 0.0) p.fail("scale", "wrong needs a scale other than 1 or a bias other than 0");
        break;
      case FaultKind::kSlow: f.divisor = static_cast<int>(p.get_int("divisor", Range::closed(2, 1e6))); break;
      case FaultKind::kDelayed:
        f.delay_us = static_cast<int64_t>(std::llround(1e3 * p.get_double("delay_ms", Range{0.0, 60e3, true, false})));
        break;
      case FaultKind::kIntermittent:
      case FaultKind::kCanLoss:
      case FaultKind::kCanCorrupt: f.probability = p.get_double("probability", Range{0.0, 1.0, true, false}); break;
      case FaultKind::kOff:
      case FaultKind::kStuck:
      case FaultKind::kCanBusOff: break;  // no parameters: p.finish() refuses any
    }
    // Over the CAN link the bridge forwards one command per control cycle, and in lockstep its
    // rig side waits for each: a command that is never published (or never decodes) would stall
    // the run. Commands lost on the way are the link's fault.
    const bool withholds = f.kind == FaultKind::kOff || f.kind == FaultKind::kSlow || f.kind == FaultKind::kDelayed ||
                           f.kind == FaultKind::kIntermittent || (f.kind == FaultKind::kGarbage && !f.garbage_nan);
    if (can_link && f.target == contract::channels::kActuatorCommand && withholds) {
      m.fail("kind",
             "over actuator_link: can, commands that do not reach the bridge are a fault of the link: use "
             "target CAN (loss, corrupt, bus_off)");
    }
    if (!f.field.empty()) {
      const std::vector<std::string> names = contract::value_field_names(f.target);
      const bool any = std::any_of(names.begin(), names.end(),
                                   [&](const std::string& n) { return contract::field_selected(f.field, n); });
      if (!any) p.fail("field", "no value field '" + f.field + "' in " + f.target + " (fields: " + join(names) + ")");
    }
    p.finish();
    m.finish();
    out.push_back(f);
  }
  return out;
}

}  // namespace nimble
