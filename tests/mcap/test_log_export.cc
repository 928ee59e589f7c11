/// export_log_to_mcap on a small hand-made LCM log: which messages go where, their log times
/// (rig time; the newest rig time for wall-clock messages), publish times and sequences, the
/// undecodable and unknown-channel counts, --raw, the "rig" metadata, a damaged log refused and
/// salvaged. The file is read back by the independent reader of mcap_check.h.

#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <nimble/fault_event_t.hpp>
#include <nimble/heartbeat_t.hpp>
#include <nimble/truth_state_t.hpp>
#include <string>
#include <vector>

#include "ident/flight_data.h"
#include "mcap/log_export.h"
#include "tests/mcap/mcap_check.h"
#include "contract/channels.h"
#include "tests/support/scratch.h"

// Channel names come from the contract (functional.contract checks that no file spells them).
using nimble::contract::channels::kFault;
using nimble::contract::channels::kHeartbeat;
using nimble::contract::channels::kTruth;

namespace fs = std::filesystem;
namespace check = nimble::test::mcap_check;
using nimble::mcap::export_log_to_mcap;
using nimble::mcap::ExportOptions;

namespace {

std::string scratch(const std::string& name) { return nimble::test::scratch_file("mcap_export", name); }

template <typename T>
std::string encoded(const T& m) {
  std::string b(static_cast<std::size_t>(m.getEncodedSize()), '\0');
  REQUIRE(m.encode(b.data(), 0, static_cast<int>(b.size())) == static_cast<int>(b.size()));
  return b;
}

nimble::truth_state_t truth(int64_t utime) {
  nimble::truth_state_t t{};
  t.utime = utime;
  t.seq = utime / 1000;
  t.euler_rad[0] = 0.25;
  return t;
}

struct Event {
  std::string channel, data;
  int64_t timestamp_us;
};

/// The log of the tests: TRUTH at rig times 1, 2, 3 ms, a heartbeat (wall clock) after the
/// first, garbage on TRUTH, an unknown channel, a fault with rig_utime -1.
std::vector<Event> sample_events() {
  nimble::heartbeat_t hb{};
  hb.utime = 1795662219827889;  // wall clock
  hb.process = "plant";
  nimble::fault_event_t fault{};
  fault.utime = 1795662219900000;
  fault.rig_utime = -1;
  return {
      {kTruth, encoded(truth(1000)), 11},
      {kHeartbeat, encoded(hb), 12},
      {kTruth, "not a truth message", 13},
      {kTruth, encoded(truth(2000)), 14},
      {"NOT_A_RIG_CHANNEL", std::string("\x01\x02\x00\x03", 4), 15},
      {kFault, encoded(fault), 16},
      {kTruth, encoded(truth(3000)), 17},
  };
}

std::string write_log(const std::string& path, const std::vector<Event>& events) {
  fs::remove(path);
  lcm::LogFile log(path, "w");
  REQUIRE(log.good());
  for (std::size_t i = 0; i < events.size(); ++i) {
    lcm::LogEvent ev{};
    ev.eventnum = static_cast<int64_t>(i);
    ev.timestamp = events[i].timestamp_us;
    ev.channel = events[i].channel;
    ev.datalen = static_cast<int32_t>(events[i].data.size());
    ev.data = const_cast<char*>(events[i].data.data());
    REQUIRE(log.writeEvent(&ev) == 0);
  }
  return path;
}

std::map<std::string, uint16_t> topics(const check::McapFile& f) {
  std::map<std::string, uint16_t> out;
  for (const auto& kv : f.channels) out[kv.second.topic] = kv.first;
  return out;
}

std::vector<check::Message> on(const check::McapFile& f, uint16_t id) {
  std::vector<check::Message> out;
  for (const auto& m : f.messages) {
    if (m.channel_id == id) out.push_back(m);
  }
  return out;
}

}  // namespace

TEST_CASE("export: JSON channels, rig log times, undecodable and unknown messages counted", "[mcap]") {
  const std::string log = write_log(scratch("small.lcmlog"), sample_events());
  { std::ofstream(log + ".scenario.yaml") << "name: small\nduration_s: 0.003\n"; }
  const std::string out = scratch("small.mcap");
  ExportOptions o;
  o.compression = GENERATE(nimble::mcap::Compression::kNone, nimble::mcap::Compression::kZstd);
  const auto stats = export_log_to_mcap(log, out, o);

  CHECK(stats.events == 7);
  CHECK(stats.messages == 5);  // 3 TRUTH, HEARTBEAT, FAULT
  CHECK(stats.undecodable == 1);
  CHECK(stats.channels.at(kTruth).undecodable == 1);
  CHECK(stats.channels.at(kTruth).json == 3);
  CHECK(stats.channels.at(kTruth).type == "nimble.truth_state_t");
  CHECK(stats.unknown_events == 1);
  REQUIRE(stats.unknown_channels == std::vector<std::string>{"NOT_A_RIG_CHANNEL"});
  CHECK(stats.channels.at("NOT_A_RIG_CHANNEL").type.empty());
  CHECK(stats.start_time_ns == 1000000);
  CHECK(stats.end_time_ns == 3000000);
  CHECK(stats.bytes_out == fs::file_size(out));
  CHECK(stats.bytes_in == fs::file_size(log));

  const auto f = check::check(check::slurp_binary(out));
  INFO(check::problems_text(f));
  REQUIRE(f.problems.empty());
  CHECK(f.library.rfind("nimble-rig ", 0) == 0);
  const auto t = topics(f);
  REQUIRE(t.size() == 3);  // TRUTH, HEARTBEAT, FAULT: the unknown channel has no JSON channel
  CHECK(f.channels.at(t.at(kTruth)).message_encoding == "json");
  const auto& schema = f.schemas.at(f.channels.at(t.at(kTruth)).schema_id);
  CHECK(schema.name == "nimble.truth_state_t");
  CHECK(schema.encoding == "jsonschema");
  CHECK(schema.data.find("\"euler_rad\"") != std::string::npos);

  const auto truths = on(f, t.at(kTruth));
  REQUIRE(truths.size() == 3);
  CHECK(truths[0].log_time == 1000000);
  CHECK(truths[0].publish_time == 11000);
  CHECK(truths[0].sequence == 0);
  CHECK(truths[1].log_time == 2000000);
  CHECK(truths[1].sequence == 3);  // the log's event number: the garbage was event 2
  CHECK(truths[2].log_time == 3000000);
  CHECK(truths[0].data.find("\"utime\":1000") != std::string::npos);
  CHECK(truths[0].data.find("\"euler_rad\":[0.25,0") != std::string::npos);
  // Wall-clock messages take the newest rig time before them.
  const auto hb = on(f, t.at(kHeartbeat));
  REQUIRE(hb.size() == 1);
  CHECK(hb[0].log_time == 1000000);
  CHECK(hb[0].publish_time == 12000);
  const auto fault = on(f, t.at(kFault));
  REQUIRE(fault.size() == 1);
  CHECK(fault[0].log_time == 2000000);

  REQUIRE(f.metadata.count("rig") == 1);
  CHECK(f.metadata.at("rig").at("log") == "small.lcmlog");
  CHECK(f.metadata.at("rig").at("scenario") == "name: small\nduration_s: 0.003\n");
  CHECK(f.metadata.at("rig").count("damage") == 0);
}

TEST_CASE("export --raw: every event's exact bytes on <CHANNEL>/lcm, with the .lcm source as schema", "[mcap]") {
  const std::vector<Event> events = sample_events();
  const std::string log = write_log(scratch("raw.lcmlog"), events);
  fs::remove(log + ".scenario.yaml");
  const std::string out = scratch("raw.mcap");
  ExportOptions o;
  o.raw = true;
  const auto stats = export_log_to_mcap(log, out, o);
  CHECK(stats.messages == 5 + 7);
  CHECK(stats.channels.at(kTruth).raw == 4);  // the garbage too: raw is what was recorded

  const auto f = check::check(check::slurp_binary(out));
  INFO(check::problems_text(f));
  REQUIRE(f.problems.empty());
  CHECK(f.metadata.at("rig").count("scenario") == 0);
  const auto t = topics(f);
  REQUIRE(t.count("TRUTH/lcm") == 1);
  REQUIRE(t.count("NOT_A_RIG_CHANNEL/lcm") == 1);
  CHECK(t.count("NOT_A_RIG_CHANNEL") == 0);
  const auto& raw_channel = f.channels.at(t.at("TRUTH/lcm"));
  CHECK(raw_channel.message_encoding == "lcm");
  const auto& raw_schema = f.schemas.at(raw_channel.schema_id);
  CHECK(raw_schema.encoding == "lcm");
  CHECK(raw_schema.name == "nimble.truth_state_t");
  CHECK(raw_schema.data.find("struct truth_state_t") != std::string::npos);
  CHECK(f.channels.at(t.at("NOT_A_RIG_CHANNEL/lcm")).schema_id == 0);

  const auto raw_truth = on(f, t.at("TRUTH/lcm"));
  REQUIRE(raw_truth.size() == 4);
  CHECK(raw_truth[0].data == events[0].data);
  CHECK(raw_truth[1].data == "not a truth message");
  CHECK(raw_truth[1].log_time == 1000000);  // no rig time of its own
  CHECK(raw_truth[3].data == events[6].data);
  const auto unknown = on(f, t.at("NOT_A_RIG_CHANNEL/lcm"));
  REQUIRE(unknown.size() == 1);
  CHECK(unknown[0].data == events[4].data);
}

TEST_CASE("export: a damaged log is refused with its offset, --salvage exports what is before it", "[mcap]") {
  const std::string whole = write_log(scratch("whole.lcmlog"), sample_events());
  const std::string cut = scratch("cut.lcmlog");
  fs::remove(cut);
  fs::copy_file(whole, cut);
  fs::resize_file(cut, fs::file_size(whole) - 10);  // inside the last event
  const std::string out = scratch("cut.mcap");
  fs::remove(out);
  try {
    export_log_to_mcap(cut, out, {});
    FAIL("a damaged log was exported");
  } catch (const nimble::ident::DataError& e) {
    CHECK_THAT(e.what(), Catch::Contains("damaged at byte") && Catch::Contains("event"));
  }
  CHECK_FALSE(fs::exists(out));
  CHECK_FALSE(fs::exists(out + ".part"));

  ExportOptions o;
  o.salvage = true;
  const auto stats = export_log_to_mcap(cut, out, o);
  CHECK(stats.events == 6);
  CHECK_THAT(stats.damage, Catch::Contains("damaged at byte"));
  const auto f = check::check(check::slurp_binary(out));
  INFO(check::problems_text(f));
  REQUIRE(f.problems.empty());
  CHECK(on(f, topics(f).at(kTruth)).size() == 2);
  CHECK_THAT(f.metadata.at("rig").at("damage"), Catch::Contains("damaged at byte"));
}

TEST_CASE("export: the log itself is never the output", "[mcap]") {
  const std::string log = write_log(scratch("self.lcmlog"), sample_events());
  const auto size = fs::file_size(log);
  CHECK_THROWS_WITH(export_log_to_mcap(log, log, {}), Catch::Contains("is the log itself"));
  CHECK(fs::file_size(log) == size);
}
