/// The live view: the contract's channels advertised with their schemas, LCM messages out as JSON
/// stamped with rig time, nothing queued for channels no one subscribes to (without a history),
/// rig/verdict, and the history a late subscriber gets before the live messages.

#include <catch2/catch.hpp>

#include <atomic>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include <nimble/heartbeat_t.hpp>
#include <nimble/truth_state_t.hpp>
#include <nlohmann/json.hpp>

#include "contract/channels.h"
#include "foxglove/live_view.h"
#include "tests/foxglove/ws_test_client.h"
#include "tests/support/encoded.h"

using namespace nimble;
using namespace nimble::foxglove;
using namespace nimble::foxglove::test;

namespace {

using nimble::test::encoded;

ServerOptions any_port() {
  ServerOptions o;
  o.port = 0;
  return o;
}

/// TRUTH at rig time `utime` [us], encoded.
std::vector<uint8_t> truth_at(int64_t utime) {
  truth_state_t t{};
  t.utime = utime;
  t.seq = static_cast<int32_t>(utime / 1000);
  return encoded(t);
}

void offer_truth(LiveView& view, int64_t utime) {
  const std::vector<uint8_t> b = truth_at(utime);
  view.offer(contract::channels::kTruth, b.data(), b.size());
}

/// A client of `server`, past serverInfo and advertise, subscribed to `channel` as subscription 1.
void subscribe(TestClient& c, const FoxgloveServer& server, uint32_t channel) {
  REQUIRE_FALSE(c.connect(server.port(), kSubprotocolV1));
  c.read_json();
  c.read_json();
  c.send_text(json{{"op", "subscribe"}, {"subscriptions", {{{"id", 1}, {"channelId", channel}}}}}.dump());
}

/// The utime of every TRUTH message `c` receives until one at `last_us` (or a read times out),
/// each checked against its frame's timestamp.
std::vector<int64_t> truth_times_until(TestClient& c, int64_t last_us) {
  std::vector<int64_t> got;
  std::string frame, payload;
  bool text = false;
  while ((got.empty() || got.back() != last_us) && c.read(&frame, &text, 3.0)) {
    uint32_t sub = 0;
    uint64_t ts = 0;
    if (text || !parse_message_data(frame, &sub, &ts, &payload)) continue;
    const int64_t utime = json::parse(payload)["utime"].get<int64_t>();
    CHECK(ts == static_cast<uint64_t>(utime) * 1000u);
    got.push_back(utime);
  }
  return got;
}

/// Whether `t` runs from `first` by `step` without a gap, a repetition or a step back.
bool contiguous(const std::vector<int64_t>& t, int64_t first, int64_t step) {
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (t[i] != first + static_cast<int64_t>(i) * step) return false;
  }
  return true;
}

/// The channel advertised as `topic` in an advertise message.
json channel_of(const json& advertise, const std::string& topic) {
  for (const auto& c : advertise["channels"]) {
    if (c["topic"] == topic) return c;
  }
  FAIL("no channel " << topic);
  return {};
}

}  // namespace

TEST_CASE("live view: every channel of the contract and rig/verdict advertised with a JSON Schema",
          "[foxglove][live_view]") {
  FoxgloveServer server(any_port());
  LiveView view(server);
  view.start();
  server.start();
  TestClient c;
  REQUIRE_FALSE(c.connect(server.port(), kSubprotocolV1));
  CHECK(c.read_json()["op"] == "serverInfo");
  const json ad = c.read_json();
  CHECK(ad["channels"].size() == contract::channel_table().size() + 1);
  const json truth = channel_of(ad, contract::channels::kTruth);
  CHECK(truth["schemaName"] == "nimble.truth_state_t");
  CHECK(truth["encoding"] == "json");
  const json schema = json::parse(truth["schema"].get<std::string>());
  CHECK(schema["properties"].contains("utime"));
  CHECK(channel_of(ad, kVerdictTopic)["schemaName"] == kVerdictSchemaName);
  CHECK(view.channel_id(contract::channels::kTruth) == truth["id"].get<uint32_t>());
}

TEST_CASE("live view: a subscribed channel's messages as JSON at their rig time, others not queued",
          "[foxglove][live_view]") {
  FoxgloveServer server(any_port());
  LiveViewOptions no_history;  // with a history every message is kept (the tests below)
  no_history.history_s = 0;
  LiveView view(server, no_history);
  view.start();
  server.start();
  TestClient c;
  REQUIRE_FALSE(c.connect(server.port(), kSubprotocolSdk));
  c.read_json();
  c.read_json();

  truth_state_t t{};
  t.utime = 1234567;
  t.seq = 3;
  t.euler_rad[0] = 0.25;
  t.omega_body_radps[0] = -1.5;
  const std::vector<uint8_t> bytes = encoded(t);
  // No subscriber yet: nothing is queued or decoded.
  view.offer(contract::channels::kTruth, bytes.data(), bytes.size());
  CHECK(view.stats().offered == 0);
  CHECK(view.newest_rig_time_us() == 1234567);

  const uint32_t truth_id = view.channel_id(contract::channels::kTruth);
  const uint32_t hb_id = view.channel_id(contract::channels::kHeartbeat);
  c.send_text(json{{"op", "subscribe"},
                   {"subscriptions", {{{"id", 1}, {"channelId", truth_id}}, {{"id", 2}, {"channelId", hb_id}}}}}
                  .dump());
  REQUIRE(eventually([&] { return server.has_subscribers(truth_id) && server.has_subscribers(hb_id); }));
  view.offer(contract::channels::kTruth, bytes.data(), bytes.size());
  // A wall-clock channel's message is stamped with the newest rig time seen.
  heartbeat_t hb{};
  hb.utime = 99;  // wall clock
  hb.process = "plant";
  hb.config_digest = "d";
  const std::vector<uint8_t> hb_bytes = encoded(hb);
  view.offer(contract::channels::kHeartbeat, hb_bytes.data(), hb_bytes.size());
  // Not a message of its type: counted, not sent.
  const std::string junk = "not an LCM message";
  view.offer(contract::channels::kTruth, junk.data(), junk.size());
  view.offer("NOT_A_CHANNEL", junk.data(), junk.size());
  REQUIRE(view.flush());

  std::map<uint32_t, std::pair<uint64_t, json>> got;
  for (int i = 0; i < 2; ++i) {
    std::string frame, payload;
    bool text = true;
    REQUIRE(c.read(&frame, &text));
    REQUIRE_FALSE(text);
    uint32_t sub = 0;
    uint64_t ts = 0;
    REQUIRE(parse_message_data(frame, &sub, &ts, &payload));
    got[sub] = {ts, json::parse(payload)};
  }
  REQUIRE(got.count(1) == 1);
  CHECK(got[1].first == 1234567000ull);
  CHECK(got[1].second["utime"] == 1234567);
  CHECK(got[1].second["euler_rad"][0] == 0.25);
  CHECK(got[1].second["omega_body_radps"][0] == -1.5);
  REQUIRE(got.count(2) == 1);
  CHECK(got[2].second["process"] == "plant");
  CHECK(got[2].first == 1234567000ull);  // heartbeat_t has no rig time: the newest TRUTH's
  const LiveViewStats s = view.stats();
  CHECK(s.offered == 3);
  CHECK(s.undecodable == 1);
  CHECK(s.published == 2);
  CHECK(s.dropped == 0);
}

TEST_CASE("live view: rig/verdict carries the state, repeated for late subscribers", "[foxglove][live_view]") {
  FoxgloveServer server(any_port());
  LiveView view(server);
  view.start();
  server.start();
  view.set_state("done", "controlled", 2.5);  // before anyone subscribes
  TestClient c;
  REQUIRE_FALSE(c.connect(server.port(), kSubprotocolV1));
  c.read_json();
  c.read_json();
  c.send_text(json{{"op", "subscribe"}, {"subscriptions", {{{"id", 9}, {"channelId", view.channel_id(kVerdictTopic)}}}}}
                  .dump());
  std::string frame, payload;
  bool text = true;
  REQUIRE(c.read(&frame, &text, 3.0));
  uint32_t sub = 0;
  uint64_t ts = 0;
  REQUIRE(parse_message_data(frame, &sub, &ts, &payload));
  CHECK(sub == 9);
  const json v = json::parse(payload);
  CHECK(v["state"] == "done");
  CHECK(v["verdict"] == "controlled");
  CHECK(v["t_s"] == 2.5);
}

TEST_CASE("live view: a full queue drops and counts, offer() stays quick", "[foxglove][live_view]") {
  FoxgloveServer server(any_port());
  LiveViewOptions o;
  o.max_queue_messages = 4;
  LiveView view(server, o);
  view.start();
  server.start();
  TestClient c;
  REQUIRE_FALSE(c.connect(server.port(), kSubprotocolV1));
  c.read_json();
  c.read_json();
  const uint32_t id = view.channel_id(contract::channels::kTruth);
  c.send_text(json{{"op", "subscribe"}, {"subscriptions", {{{"id", 1}, {"channelId", id}}}}}.dump());
  REQUIRE(eventually([&] { return server.has_subscribers(id); }));
  truth_state_t t{};
  const std::vector<uint8_t> bytes = encoded(t);
  for (int i = 0; i < 10000; ++i) view.offer(contract::channels::kTruth, bytes.data(), bytes.size());
  REQUIRE(view.flush());
  const LiveViewStats s = view.stats();
  CHECK(s.offered == 10000);
  CHECK(s.dropped > 0);
  CHECK(s.dropped + s.published == 10000);
}

TEST_CASE(
    "live view: a client that subscribes late gets the last 10 s of a channel in order, then the live "
    "messages without a gap or a repetition",
    "[foxglove][live_view]") {
  FoxgloveServer server(any_port());
  LiveView view(server);  // the default history: 10 s of rig time
  view.start();
  server.start();
  const uint32_t truth = view.channel_id(contract::channels::kTruth);
  constexpr int64_t kStep = 10000;  // 100 Hz [us]
  // 15 s of TRUTH before anyone subscribes: 0 .. 14.99 s.
  for (int64_t t = 0; t < 15000000; t += kStep) offer_truth(view, t);
  REQUIRE(view.flush());

  // A: exactly the last 10 s, 4.99 .. 14.99 s (1001 messages), then the live ones.
  TestClient a;
  subscribe(a, server, truth);
  REQUIRE(eventually([&] { return view.stats().backlogs == 1; }));
  CHECK(view.stats().backlog_messages == 1001);

  // 5 s more, offered from another thread while B subscribes.
  constexpr int64_t kLast = 19990000;
  std::atomic<bool> go{false};
  std::thread publisher([&] {
    while (!go) std::this_thread::yield();
    for (int64_t t = 15000000; t <= kLast; t += kStep) {
      offer_truth(view, t);
      std::this_thread::sleep_for(std::chrono::microseconds(500));
    }
  });
  go = true;
  TestClient b;
  subscribe(b, server, truth);
  publisher.join();
  REQUIRE(view.flush());

  const std::vector<int64_t> ta = truth_times_until(a, kLast);
  REQUIRE(ta.size() == 1501);
  CHECK(contiguous(ta, 4990000, kStep));
  // B: its backlog is the 10 s before the newest rig time when it subscribed, the live
  // messages follow it: one run from there to the last.
  const std::vector<int64_t> tb = truth_times_until(b, kLast);
  REQUIRE_FALSE(tb.empty());
  CHECK(tb.front() >= 4990000);
  CHECK(tb.front() <= kLast - 10000000);
  CHECK(tb.back() == kLast);
  CHECK(contiguous(tb, tb.front(), kStep));
  const LiveViewStats s = view.stats();
  CHECK(s.backlogs == 2);
  CHECK(s.dropped == 0);
  CHECK(s.server.dropped == 0);
}

TEST_CASE("live view: the history is bounded in bytes, and forgotten when rig time starts again",
          "[foxglove][live_view]") {
  FoxgloveServer server(any_port());
  LiveViewOptions o;
  o.history_bytes = 30000;
  LiveView view(server, o);
  view.start();
  server.start();
  const uint32_t truth = view.channel_id(contract::channels::kTruth);
  const std::size_t size = truth_at(0).size();
  for (int64_t t = 0; t < 2000000; t += 10000) offer_truth(view, t);  // 2 s, 200 messages
  REQUIRE(view.flush());
  {
    TestClient c;
    subscribe(c, server, truth);
    const std::vector<int64_t> got = truth_times_until(c, 1990000);
    // The newest that fit 30000 bytes with their bookkeeping, in order.
    CHECK(got.size() * size <= 30000);
    CHECK(got.size() >= 30000 / (size + 128));
    REQUIRE_FALSE(got.empty());
    CHECK(contiguous(got, got.front(), 10000));
    CHECK(got.back() == 1990000);
  }
  // A replay from its start: the client gets only the messages since.
  view.restart();
  for (int64_t t = 0; t <= 50000; t += 10000) offer_truth(view, t);
  REQUIRE(view.flush());
  TestClient c;
  subscribe(c, server, truth);
  const std::vector<int64_t> got = truth_times_until(c, 50000);
  CHECK(got.size() == 6);
  CHECK(contiguous(got, 0, 10000));
}
