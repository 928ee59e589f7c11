#include "fuzz/node_harness.h"

#include <algorithm>
#include <cstring>
#include <map>

#include <nimble/run_control_t.hpp>

#include "contract/channels.h"
#include "fuzz/fuzz_support.h"
#include "transport/bus.h"

namespace nimble::fuzz {
namespace {

std::unique_ptr<NodeRig> g_rig;
int g_inputs_on_rig = 0;

std::unique_ptr<NodeRig> build_rig(const NodeFactory& factory, bool with_can) {
  auto rig = std::make_unique<NodeRig>();
  factory(*rig);
  if (with_can) rig->can_injector = rig->can_bus.attach("fuzz", true);
  std::vector<std::string> participants;
  for (auto* node : rig->nodes) {
    node->join_inprocess();
    participants.push_back(node->name());
  }
  transport::Bus control(rig->hub);
  run_control_t start{};
  start.utime = 0;
  start.seq = 0;
  start.command = run_control_t::COMMAND_START;
  start.clock_mode = run_control_t::CLOCK_MODE_LOCKSTEP;
  start.t0_monotonic_ns = 0;
  start.duration_ns = 200000000;  // 0.2 s: a RIG_CLOCK tick runs at most this much of each task
  start.run_id = "fuzz";
  start.participants = participants;
  start.num_participants = static_cast<int32_t>(participants.size());
  control.publish(contract::channels::kRunControl, start);
  rig->hub.drain();
  return rig;
}

void inject_frame(can::FramePort& port, const uint8_t* p, std::size_t n) {
  uint8_t b[6] = {0, 0, 0, 0, 0, 0};
  std::memcpy(b, p, std::min<std::size_t>(n, sizeof b));
  const bool fd = (b[0] & 1) != 0;
  uint32_t id = 0;
  std::memcpy(&id, b + 1, 4);
  const uint8_t* payload = n > 6 ? p + 6 : nullptr;
  const std::size_t available = n > 6 ? n - 6 : 0;
  if (fd) {
    canfd_frame f{};
    f.can_id = id;
    f.len = static_cast<uint8_t>(std::min<std::size_t>(b[5], CANFD_MAX_DLEN));
    f.flags = static_cast<uint8_t>(b[0] >> 1);
    if (payload != nullptr) std::memcpy(f.data, payload, std::min<std::size_t>(available, CANFD_MAX_DLEN));
    port.send(f);
  } else {
    can_frame f{};
    f.can_id = id;
    f.len = static_cast<uint8_t>(std::min<std::size_t>(b[5], CAN_MAX_DLEN));
    if (payload != nullptr) std::memcpy(f.data, payload, std::min<std::size_t>(available, CAN_MAX_DLEN));
    port.send(f);
  }
}

}  // namespace

const Scenario& fuzz_scenario(const std::string& file, const std::vector<std::string>& overrides) {
  static std::map<std::string, Scenario> loaded;
  std::string key = file;
  for (const auto& o : overrides) key += " " + o;
  auto it = loaded.find(key);
  if (it == loaded.end()) {
    std::vector<Override> parsed;
    for (const auto& o : overrides) parsed.push_back(parse_override(o));
    it = loaded.emplace(key, load_scenario(source_dir() + "/rig_configs/" + file, parsed)).first;
  }
  return it->second;
}

void fuzz_nodes(const uint8_t* data, std::size_t size, const NodeFactory& factory, bool with_can) {
  if (!g_rig || g_inputs_on_rig >= kInputsPerRig) {
    g_rig.reset();  // the old nodes go before the new ones are built
    g_rig = build_rig(factory, with_can);
    g_inputs_on_rig = 0;
  }
  ++g_inputs_on_rig;
  NodeRig& rig = *g_rig;
  const auto& table = contract::channel_table();
  const std::size_t selectors = table.size() + (with_can ? 1 : 0);

  std::size_t pos = 0;
  while (pos < size) {
    const uint8_t selector = data[pos++];
    std::size_t length = 0;
    if (pos < size) length = data[pos++];
    if (pos < size) length |= static_cast<std::size_t>(data[pos++]) << 8;
    length = std::min(length, size - pos);
    const uint8_t* payload = data + pos;
    pos += length;

    const std::size_t index = selector % selectors;
    if (index == table.size()) {
      inject_frame(*rig.can_injector, payload, length);
      rig.hub.drain();
      continue;
    }
    const std::string& channel = table[index].name;
    const LcmType* type = find_lcm_type(table[index].type);
    require(type != nullptr, "channel " + channel + " has type " + table[index].type + ", not in lcmtypes/");
    const bool decodes = type->decodes(payload, static_cast<int>(length));

    // Malformed counts of the nodes that take this channel, before the message.
    std::vector<std::pair<transport::ProcessNode*, int64_t>> before;
    for (auto* node : rig.nodes) {
      const auto& stats = node->bus().stats();
      const auto s = stats.find(channel);
      if (s != stats.end()) before.emplace_back(node, s->second.malformed);
    }
    rig.hub.publish(channel, payload, static_cast<int>(length));
    rig.hub.drain();
    if (decodes) continue;
    for (const auto& [node, malformed] : before) {
      const int64_t now = node->bus().stats().at(channel).malformed;
      // At least once: what the nodes publish in answer may be refused too (a seq the fuzzer's
      // message broke), so "exactly once" would not hold of the channel's count.
      require(now > malformed, node->name() + " took " + std::to_string(length) + " bytes on " + channel +
                                   " that do not decode as " + table[index].type +
                                   " without counting them as "
                                   "malformed (malformed count stayed " +
                                   std::to_string(now) + ")");
    }
  }
}

}  // namespace nimble::fuzz
