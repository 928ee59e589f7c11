// Unit tests of the in-process carrier: InprocessHub (order, patterns, nesting, pollers), a
// Bus on a hub (typed messages, malformed ones counted), and ProcessNode's in-process
// lockstep (a participant's ticks and acknowledgements through the hub; a missing
// acknowledgement is a fault at once, not after a timeout).

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <catch2/catch.hpp>
#include <nimble/fault_event_t.hpp>
#include <nimble/heartbeat_t.hpp>
#include <nimble/run_control_t.hpp>
#include <nimble/truth_state_t.hpp>

#include "contract/channels.h"
#include "contract/lockstep_schedule.h"
#include "contract/rates.h"
#include "transport/bus.h"
#include "transport/inprocess_hub.h"
#include "transport/node.h"

using nimble::transport::Bus;
using nimble::transport::InprocessHub;
using nimble::transport::NodeOptions;
using nimble::transport::ProcessNode;
namespace ch = nimble::contract::channels;

namespace {

void publish_text(InprocessHub& hub, const std::string& channel, const std::string& text) {
  hub.publish(channel, text.data(), static_cast<int>(text.size()));
}

}  // namespace

TEST_CASE("hub: every message reaches every matching pattern, in publication order", "[transport]") {
  InprocessHub hub;
  std::vector<std::string> all, truth_only;
  hub.subscribe(".*", [&](const std::string& c, const void* d, int n) {
    all.push_back(c + ":" + std::string(static_cast<const char*>(d), n));
  });
  hub.subscribe("ALPHA", [&](const std::string&, const void* d, int n) {
    truth_only.push_back(std::string(static_cast<const char*>(d), n));
  });
  publish_text(hub, "ALPHA", "a");
  publish_text(hub, "BETA", "b");
  publish_text(hub, "ALPHA_X", "c");  // a pattern matches the whole name, not a prefix
  publish_text(hub, "ALPHA", "d");
  CHECK(all.empty());  // nothing is delivered before drain()
  CHECK(hub.waiting() == 4);
  CHECK(hub.drain() == 4);
  CHECK(all == std::vector<std::string>{"ALPHA:a", "BETA:b", "ALPHA_X:c", "ALPHA:d"});
  CHECK(truth_only == std::vector<std::string>{"a", "d"});
  CHECK(hub.published() == 4);
  CHECK(hub.waiting() == 0);
  CHECK(hub.drain() == 0);
}

TEST_CASE("hub: what a handler publishes comes after what was already waiting", "[transport]") {
  InprocessHub hub;
  std::vector<std::string> seen;
  hub.subscribe("A", [&](const std::string&, const void* d, int n) {
    seen.push_back("A" + std::string(static_cast<const char*>(d), n));
    CHECK(hub.drain() == 0);  // a nested drain does nothing
    publish_text(hub, "B", std::string(static_cast<const char*>(d), n));
  });
  hub.subscribe("B", [&](const std::string&, const void* d, int n) {
    seen.push_back("B" + std::string(static_cast<const char*>(d), n));
  });
  publish_text(hub, "A", "1");
  publish_text(hub, "A", "2");
  CHECK(hub.drain() == 4);
  CHECK(seen == std::vector<std::string>{"A1", "A2", "B1", "B2"});
}

TEST_CASE("hub: pollers run when the queue is empty, until nobody has anything", "[transport]") {
  InprocessHub hub;
  int frames = 3;  // a poller's own input, e.g. CAN frames
  std::vector<std::string> seen;
  hub.subscribe(".*", [&](const std::string& c, const void*, int) { seen.push_back(c); });
  hub.add_poller([&] {
    if (frames == 0) return false;
    --frames;
    publish_text(hub, "FROM_POLLER", "x");
    return true;
  });
  publish_text(hub, "FIRST", "x");
  CHECK(hub.drain() == 4);
  CHECK(seen == std::vector<std::string>{"FIRST", "FROM_POLLER", "FROM_POLLER", "FROM_POLLER"});
  CHECK(frames == 0);
}

TEST_CASE("hub: a malformed pattern is refused when subscribing", "[transport]") {
  InprocessHub hub;
  CHECK_THROWS(hub.subscribe("TRUTH(", [](const std::string&, const void*, int) {}));
}

TEST_CASE("bus on a hub: typed messages round-trip, malformed ones are counted and reported", "[transport]") {
  InprocessHub hub;
  Bus sender(hub), receiver(hub);
  CHECK(sender.hub() == &hub);
  CHECK(sender.fileno() == -1);
  std::vector<nimble::truth_state_t> got;
  std::vector<std::string> malformed;
  receiver.subscribe<nimble::truth_state_t>(ch::kTruth, [&](const nimble::truth_state_t& t) { got.push_back(t); });
  receiver.on_malformed([&](const std::string& c, const std::string& what) { malformed.push_back(c + ": " + what); });
  nimble::truth_state_t t{};
  t.utime = 1234;
  t.seq = 7;
  t.euler_rad[0] = 0.25;
  sender.publish(ch::kTruth, t);
  const char garbage[5] = {1, 2, 3, 4, 5};
  hub.publish(ch::kTruth, garbage, sizeof garbage);
  t.seq = 9;  // a gap of one in seq: one drop
  sender.publish(ch::kTruth, t);
  CHECK(receiver.drain() == 3);
  REQUIRE(got.size() == 2);
  CHECK(got[0].utime == 1234);
  CHECK(got[0].euler_rad[0] == 0.25);
  CHECK(receiver.stats().at(ch::kTruth).received == 2);
  CHECK(receiver.stats().at(ch::kTruth).malformed == 1);
  CHECK(receiver.stats().at(ch::kTruth).drops == 1);
  REQUIRE(malformed.size() == 1);
  CHECK(malformed[0].find("truth_state_t") != std::string::npos);
}

TEST_CASE("bus: a string of encoded length 0 and a seq that does not continue are malformed, never delivered",
          "[transport]") {
  InprocessHub hub;
  Bus sender(hub), receiver(hub);
  std::vector<nimble::truth_state_t> truth;
  std::vector<nimble::heartbeat_t> heartbeats;
  std::vector<std::string> malformed;
  receiver.subscribe<nimble::truth_state_t>(ch::kTruth, [&](const nimble::truth_state_t& t) { truth.push_back(t); });
  receiver.subscribe<nimble::heartbeat_t>(ch::kHeartbeat,
                                          [&](const nimble::heartbeat_t& h) { heartbeats.push_back(h); });
  receiver.on_malformed([&](const std::string& c, const std::string& what) { malformed.push_back(c + ": " + what); });
  // A heartbeat whose `process` string has an encoded length of 0 (bytes 24-27): LCM 1.3.1's
  // generated decoder threw std::length_error from std::string::assign; with the rig's decoder
  // checks (cmake/LcmDecodeChecks.cmake) it refuses the bytes.
  nimble::heartbeat_t hb{};
  hb.process = "plant";
  std::vector<unsigned char> bytes(static_cast<std::size_t>(hb.getEncodedSize()));
  hb.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  bytes[24] = bytes[25] = bytes[26] = bytes[27] = 0;
  hub.publish(ch::kHeartbeat, bytes.data(), static_cast<int>(bytes.size()));
  // TRUTH (one publisher): 0, 1, then a stray 2^40, a step back to 0... and the real 2 again.
  nimble::truth_state_t t{};
  for (const int64_t seq : {int64_t{0}, int64_t{1}, int64_t{1} << 40, int64_t{2}}) {
    t.seq = seq;
    sender.publish(ch::kTruth, t);
  }
  CHECK_NOTHROW(receiver.drain());
  CHECK(heartbeats.empty());
  REQUIRE(truth.size() == 3);
  CHECK(truth.back().seq == 2);
  CHECK(receiver.stats().at(ch::kTruth).drops == 0);
  CHECK(receiver.stats().at(ch::kTruth).malformed == 1);
  CHECK(receiver.stats().at(ch::kHeartbeat).malformed == 1);
  REQUIRE(malformed.size() == 2);
  CHECK(malformed[0].find("cannot decode as heartbeat_t") != std::string::npos);
  CHECK(malformed[1].find("does not continue") != std::string::npos);
}

TEST_CASE("bus on a hub: the rig's own messages skip the encode-back check, raw bytes keep it", "[transport]") {
  InprocessHub hub;
  Bus sender(hub), receiver(hub);
  std::vector<nimble::heartbeat_t> got;
  std::vector<bool> own_when_delivered;
  std::vector<std::string> malformed;
  receiver.subscribe<nimble::heartbeat_t>(ch::kHeartbeat, [&](const nimble::heartbeat_t& h) {
    got.push_back(h);
    own_when_delivered.push_back(hub.delivering_own_encoding());
  });
  receiver.on_malformed([&](const std::string& c, const std::string& what) { malformed.push_back(c + ": " + what); });
  nimble::heartbeat_t hb{};
  hb.process = "plant";
  hb.seq = 0;
  sender.publish(ch::kHeartbeat, hb);
  // The same message as raw bytes with a NUL inside its string: LCM decodes "pl\0nt" but
  // encodes back "pl", so published raw (as fault injection publishes garbage) it is malformed.
  hb.seq = 1;
  std::vector<unsigned char> bytes(static_cast<std::size_t>(hb.getEncodedSize()));
  REQUIRE(hb.encode(bytes.data(), 0, static_cast<int>(bytes.size())) == static_cast<int>(bytes.size()));
  const std::string name = "plant";
  const auto at = std::search(bytes.begin(), bytes.end(), name.begin(), name.end());
  REQUIRE(at != bytes.end());
  std::vector<unsigned char> nul_inside = bytes;
  nul_inside[static_cast<std::size_t>(at - bytes.begin()) + 2] = 0;
  sender.publish_bytes(ch::kHeartbeat, nul_inside.data(), static_cast<int>(nul_inside.size()));
  // Raw bytes that do encode back are delivered, checked in full.
  sender.publish_bytes(ch::kHeartbeat, bytes.data(), static_cast<int>(bytes.size()));
  receiver.drain();
  REQUIRE(got.size() == 2);
  CHECK(own_when_delivered == std::vector<bool>{true, false});
  CHECK(got[1].seq == 1);
  CHECK(got[1].process == "plant");
  CHECK_FALSE(hub.delivering_own_encoding());
  REQUIRE(malformed.size() == 1);
  CHECK(malformed[0].find("a string with a NUL inside") != std::string::npos);
}

namespace {

/// A master with one task at 1 kHz and a participant at 500 Hz on one hub.
struct TwoNodes {
  InprocessHub hub;
  ProcessNode master{NodeOptions{"plant", "", "inprocess", &hub}};
  ProcessNode participant{NodeOptions{"controller", "", "inprocess", &hub}};
  Bus control{hub};
  std::vector<int64_t> master_steps, participant_ticks;
  std::vector<nimble::fault_event_t> faults;

  TwoNodes() {
    master.set_lockstep_master(true);
    master.add_task("plant", 1000.0, [this](int64_t t) { master_steps.push_back(t); });
    participant.add_task("cycle", 500.0, [this](int64_t t) { participant_ticks.push_back(t); });
    control.subscribe<nimble::fault_event_t>(ch::kFault,
                                             [this](const nimble::fault_event_t& f) { faults.push_back(f); });
    participant.join_inprocess();
    nimble::run_control_t start{};
    start.command = nimble::run_control_t::COMMAND_START;
    start.clock_mode = nimble::run_control_t::CLOCK_MODE_LOCKSTEP;
    start.duration_ns = 10000000;  // 10 ms
    start.run_id = "test";
    start.participants = {"controller"};
    start.num_participants = 1;
    control.publish(ch::kRunControl, start);
    hub.drain();
  }
};

}  // namespace

TEST_CASE("in-process lockstep: the master steps, the participant runs at its ticks, no waiting", "[transport]") {
  TwoNodes n;
  CHECK(n.master.inprocess());
  const auto before = std::chrono::steady_clock::now();
  CHECK(n.master.run() == nimble::transport::kExitOk);
  n.participant.finish_inprocess();
  n.hub.drain();
  CHECK(std::chrono::steady_clock::now() - before < std::chrono::seconds(1));
  CHECK(n.master_steps.size() == 11);  // t = 0, 1, ..., 10 ms
  CHECK(n.participant_ticks == std::vector<int64_t>{0, 2000000, 4000000, 6000000, 8000000});
  CHECK(n.faults.empty());
  CHECK_THROWS_AS(n.participant.run(), std::logic_error);  // only the master runs in process
}

TEST_CASE("in-process lockstep: a participant that never acknowledges is a fatal fault at once", "[transport]") {
  TwoNodes n;
  // The participant holds its first acknowledgement and never releases it.
  n.participant.add_task("hold", 500.0, [&](int64_t) { n.participant.hold_ack(); });
  const auto before = std::chrono::steady_clock::now();
  CHECK(n.master.run() == nimble::transport::kExitAckTimeout);
  // Immediately, not after the 2 s acknowledgement timeout of a run over LCM.
  CHECK(std::chrono::steady_clock::now() - before < std::chrono::milliseconds(500));
  n.hub.drain();
  REQUIRE(n.faults.size() == 1);
  CHECK(n.faults[0].code == nimble::fault_event_t::CODE_STEP_ACK_TIMEOUT);
  CHECK(n.faults[0].message.find("'controller'") != std::string::npos);
  CHECK(n.faults[0].message.find("in process") != std::string::npos);
}

TEST_CASE("lockstep schedule: the master's ticks and acknowledgements are the ones the rate model replays",
          "[transport]") {
  InprocessHub hub;
  ProcessNode master{NodeOptions{"plant", "", "inprocess", &hub}};
  master.set_lockstep_master(true);
  master.add_task("plant", 1000.0, [](int64_t) {});
  const std::vector<std::pair<std::string, double>> rates = {
      {"controller", 512.0}, {"mocap", 200.0}, {"estimator", 512.0}};
  std::vector<std::unique_ptr<ProcessNode>> participants;
  for (const auto& [name, hz] : rates) {
    participants.push_back(std::make_unique<ProcessNode>(NodeOptions{name, "", "inprocess", &hub}));
    participants.back()->add_task("task", hz, [](int64_t) {});
    participants.back()->join_inprocess();
  }
  Bus control(hub);
  int64_t ticks = 0, acks = 0;
  hub.subscribe(ch::kRigClock, [&](const std::string&, const void*, int) { ++ticks; });
  hub.subscribe(ch::kStepAck, [&](const std::string&, const void*, int) { ++acks; });
  nimble::run_control_t start{};
  start.command = nimble::run_control_t::COMMAND_START;
  start.clock_mode = nimble::run_control_t::CLOCK_MODE_LOCKSTEP;
  start.duration_ns = 1000000000;
  start.run_id = "schedule";
  for (const auto& [name, hz] : rates) start.participants.push_back(name);
  start.num_participants = static_cast<int32_t>(start.participants.size());
  control.publish(ch::kRunControl, start);
  hub.drain();
  REQUIRE(master.run() == nimble::transport::kExitOk);
  hub.drain();

  std::vector<nimble::contract::ScheduledParticipant> model;
  for (const auto& [name, hz] : rates) model.push_back({std::llround(1e9 / hz), true});
  const auto replayed = nimble::contract::replay_lockstep(1000000, model, 1000000000);
  CHECK(ticks == replayed.ticks);
  CHECK(acks == replayed.acks);
  CHECK(acks == 512 + 200 + 512);  // every due time of every participant, once
  CHECK(ticks < 1000);             // steps where nobody is due send no tick

  // And the expected-rate table of a run with these processes is the same replay.
  nimble::contract::ProcessRates pr;
  pr.plant_hz = 1000.0;
  pr.controller_hz = 512.0;
  pr.mocap_hz = 200.0;
  pr.estimator_hz = 512.0;
  const auto hz = nimble::contract::expected_rates(pr, nimble::contract::RunShape{true, 0.0, 4});
  CHECK(hz.at(ch::kRigClock) == static_cast<double>(ticks));
  CHECK(hz.at(ch::kStepAck) == static_cast<double>(acks));
}

TEST_CASE("bus: drops counted from seq gaps saturate instead of overflowing", "[transport]") {
  // Found by fuzz_node_plant: on a channel with several publishers (HEARTBEAT) a stray seq can
  // be anything; seq gaps near 2^62, one after another, overflowed the drop count.
  InprocessHub hub;
  Bus sender(hub), receiver(hub);
  int received = 0;
  receiver.subscribe<nimble::heartbeat_t>(ch::kHeartbeat, [&](const nimble::heartbeat_t&) { ++received; });
  nimble::heartbeat_t hb{};
  hb.process = "plant";
  for (int i = 0; i < 3; ++i) {
    for (const int64_t seq : {int64_t{0}, int64_t{1} << 62}) {
      hb.seq = seq;
      sender.publish(ch::kHeartbeat, hb);
    }
  }
  receiver.drain();
  CHECK(received == 6);
  CHECK(receiver.stats().at(ch::kHeartbeat).drops == std::numeric_limits<int64_t>::max());
}
