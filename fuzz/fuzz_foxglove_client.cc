// Fuzz target: what a Foxglove WebSocket client may send the live view's server
// (foxglove/protocol.h ClientSession), frame by frame. The input is a sequence of frames, each a
// kind byte (bit 0: binary), a 16-bit little-endian length and that many bytes (cut short at the
// input's end). Properties: nothing throws; every reply is a JSON status error; each reply is
// counted once (as refused or as a protocol error); the subscriptions stay one per id and one per
// channel, on channels that exist, and a changed channel is one that exists.

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "foxglove/protocol.h"
#include "fuzz/fuzz_support.h"

using namespace nimble::foxglove;
using nimble::fuzz::require;

namespace {
constexpr uint32_t kChannels = 20;  // the server advertises channels 1..20
bool exists(uint32_t id) { return id >= 1 && id <= kChannels; }
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  ClientSession session(exists);
  std::size_t at = 0;
  while (at < size) {
    const bool binary = (data[at] & 1u) != 0;
    std::size_t len = 0;
    if (at + 3 <= size) len = static_cast<std::size_t>(data[at + 1]) | (static_cast<std::size_t>(data[at + 2]) << 8);
    at = at + 3 <= size ? at + 3 : size;
    if (len > size - at) len = size - at;
    const std::string_view frame(reinterpret_cast<const char*>(data + at), len);
    at += len;

    const SessionCounters before = session.counters();
    std::vector<std::string> replies;
    std::vector<uint32_t> changed;
    if (binary)
      session.on_binary(frame, &replies);
    else
      changed = session.on_text(frame, &replies);
    const SessionCounters after = session.counters();
    require(static_cast<int64_t>(replies.size()) ==
                (after.refused - before.refused) + (after.protocol_errors - before.protocol_errors),
            "a reply without its count, or a count without its reply");
    for (const auto& r : replies) {
      const auto j = nlohmann::json::parse(r, nullptr, false);
      require(!j.is_discarded() && j.is_object() && j.value("op", "") == "status" && j.value("level", -1) == 2,
              "a reply that is not a JSON status error: " + r);
    }
    for (uint32_t c : changed) require(exists(c), "a changed channel that does not exist");
    std::vector<bool> seen(kChannels + 1, false);
    for (const auto& kv : session.subscriptions()) {
      require(exists(kv.second), "a subscription of a channel that does not exist");
      require(!seen[kv.second], "two subscriptions of one channel");
      seen[kv.second] = true;
      uint32_t sub = 0;
      require(session.subscription_of(kv.second, &sub) && sub == kv.first, "the two maps disagree");
    }
  }
  return 0;
}
