/// The rig's MCAP files read by the format's own reader (@mcap/core, through
/// tests/mcap/node/read_mcap.mjs, with CRCs checked, the indexed and the streaming reader):
/// a synthetic file from the writer in both compressions, a rig flight exported by
/// `rig export --format mcap` and `rig run --mcap` compared with its LCM log, and a damaged log
/// refused and salvaged.

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <nimble/truth_state_t.hpp>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "contract/decode.h"
#include "lcmlog/lcm_log.h"
#include "mcap/mcap_writer.h"
#include "tests/support/rig_runs.h"
#include "contract/channels.h"

// Channel names come from the contract (functional.contract checks that no file spells them).
using nimble::contract::channels::kTruth;

namespace fs = std::filesystem;
using nimble::test::RigResult;
using nimble::test::run_program;
using nimble::test::run_rig;
using nlohmann::json;

namespace {

/// Runs read_mcap.mjs on `file` with `args`; its JSON report.
json read_with_node(const std::string& file, const std::string& args = "") {
  const std::string npm = NPM_DIR;
  if (!fs::exists(npm + "/node_modules/@mcap/core")) {
    FAIL("the npm packages are not installed in " << npm << "/node_modules: run scripts/setup.sh");
  }
  const RigResult r = run_program(NODE_BIN, npm + "/read_mcap.mjs " + file + " " + args);
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  return json::parse(r.out);
}

uint64_t ns(const json& text) { return std::stoull(text.get<std::string>()); }

const json& channel(const json& report, const std::string& topic) {
  for (const auto& c : report.at("channels")) {
    if (c.at("topic") == topic) return c;
  }
  FAIL("no channel " << topic << " in the report");
  throw std::logic_error("unreachable");
}

/// A double of the rig as read back from JSON (NaN is written as null).
double number(const json& v) { return v.is_null() ? NAN : v.get<double>(); }

void check_truth(const json& m, const nimble::truth_state_t& t) {
  CHECK(m.at("utime").get<int64_t>() == t.utime);
  CHECK(m.at("seq").get<int64_t>() == t.seq);
  for (int i = 0; i < 3; ++i) {
    CHECK(number(m.at("position_ned_m")[i]) == t.position_ned_m[i]);
    CHECK(number(m.at("velocity_body_mps")[i]) == t.velocity_body_mps[i]);
    CHECK(number(m.at("euler_rad")[i]) == t.euler_rad[i]);
    CHECK(number(m.at("omega_body_radps")[i]) == t.omega_body_radps[i]);
  }
  for (int i = 0; i < 4; ++i) CHECK(number(m.at("quaternion_wxyz")[i]) == t.quaternion_wxyz[i]);
}

}  // namespace

TEST_CASE("node: a synthetic MCAP file reads back in @mcap/core, both compressions", "[mcap][node]") {
  const auto compression = GENERATE(nimble::mcap::Compression::kNone, nimble::mcap::Compression::kZstd);
  const std::string dir = nimble::test::scratch_dir(std::string("mcap_node_") + nimble::mcap::to_string(compression));
  const std::string file = dir + "/synthetic.mcap";
  nimble::mcap::WriterOptions o;
  o.compression = compression;
  o.chunk_size = 64 * 1024;
  const int n = 5000;
  {
    nimble::mcap::McapWriter w(file, o);
    const uint16_t schema =
        w.add_schema("test.sample_t", "jsonschema",
                     R"({"$schema":"http://json-schema.org/draft-07/schema#","type":"object","required":["i","x"],)"
                     R"("properties":{"i":{"type":"integer","x-unit":"-"},"x":{"type":["number","null"]}}})");
    const uint16_t a = w.add_channel(schema, "A", "json");
    const uint16_t b = w.add_channel(schema, "B", "json");
    for (int i = 0; i < n; ++i) {
      const std::string text = "{\"i\":" + std::to_string(i) + ",\"x\":" + std::to_string(i * 0.5) + "}";
      // B every third step, at the same log time as A's message of that step.
      const uint64_t t = 1000000000ull + 2000000ull * static_cast<uint64_t>(i);
      w.add_message(a, static_cast<uint32_t>(i), t, t + 1, text.data(), text.size());
      if (i % 3 == 0) w.add_message(b, static_cast<uint32_t>(i), t, t + 2, text.data(), text.size());
    }
    w.add_metadata("rig", {{"log", "synthetic"}});
    w.close();
  }
  const json r = read_with_node(file, "--sample A:0 --sample A:2500 --sample A:-1 --sample B:7");
  CHECK(r.at("library") == "nimble-rig");
  CHECK(r.at("dataSectionCrcOk") == true);
  CHECK(channel(r, "A").at("count") == n);
  CHECK(channel(r, "B").at("count") == (n + 2) / 3);
  CHECK(r.at("messages") == n + (n + 2) / 3);
  CHECK(ns(r.at("startTime")) == 1000000000ull);
  CHECK(ns(r.at("endTime")) == 1000000000ull + 2000000ull * (n - 1));
  const json& s = r.at("statistics");
  CHECK(s.at("messageCount") == r.at("messages"));
  CHECK(s.at("channelMessageCounts").at("A") == n);
  CHECK(ns(s.at("messageStartTime")) == ns(r.at("startTime")));
  CHECK(ns(s.at("messageEndTime")) == ns(r.at("endTime")));
  CHECK(s.at("metadataCount") == 1);
  CHECK(s.at("chunkCount").get<int>() > 1);
  CHECK(r.at("schemas").at("compiled") == 1);
  CHECK(r.at("validation").at("valid") == r.at("messages"));
  const json& samples = r.at("samples");
  CHECK(samples.at("A:0").at("message").at("i") == 0);
  CHECK(samples.at("A:2500").at("message").at("x") == 1250.0);
  CHECK(ns(samples.at("A:2500").at("logTime")) == 1000000000ull + 2000000ull * 2500);
  CHECK(ns(samples.at("A:2500").at("publishTime")) == 1000000000ull + 2000000ull * 2500 + 1);
  CHECK(samples.at("A:-1").at("message").at("i") == n - 1);
  CHECK(samples.at("B:7").at("message").at("i") == 21);
  CHECK(samples.at("B:7").at("sequence") == 21);
  CHECK(r.at("stream").at("counts").at("A") == n);
  CHECK(r.at("stream").at("counts").at("B") == (n + 2) / 3);
  CHECK(r.at("metadata")[0].at("metadata").at("log") == "synthetic");
}

TEST_CASE("node: a rig flight as MCAP holds its log's messages, values and times", "[mcap][node]") {
  const std::string dir = nimble::test::scratch_dir("mcap_node_flight");
  const std::string log = dir + "/run.lcmlog";
  const std::string run_mcap = dir + "/run.mcap";
  // rig run --mcap: the run's log exported at the end of the run (zstd).
  const nimble::test::RunResult run = nimble::test::rig_run(RIG_SOURCE_DIR "/rig_configs/hover.yaml", dir,
                                                            "--clock inprocess --set duration_s=2 --mcap " + run_mcap);
  INFO(run.output);
  REQUIRE(run.exit_code == 0);
  CHECK(run.output.find("mcap       ") != std::string::npos);
  REQUIRE(fs::exists(run_mcap));

  // The LCM log: events per channel, TRUTH decoded by the generated type.
  const std::map<std::string, int> lcm_counts = nimble::test::channel_counts(log);
  std::vector<nimble::truth_state_t> truth;
  {
    lcm::LogFile in(log, "r");
    REQUIRE(in.good());
    while (const lcm::LogEvent* ev = in.readNextEvent()) {
      if (ev->channel != kTruth) continue;
      nimble::truth_state_t t{};
      REQUIRE(nimble::contract::decode_exact(ev->data, ev->datalen, t));
      truth.push_back(t);
    }
  }
  REQUIRE(truth.size() > 100);
  const std::size_t mid = truth.size() / 2;

  for (const std::string compression : {"zstd", "none"}) {
    INFO(compression);
    const std::string out = dir + "/export_" + compression + ".mcap";
    const RigResult e = run_rig("export " + log + " --format mcap --out " + out + " --compression " + compression +
                                " --json " + dir + "/export.json");
    INFO(e.err);
    REQUIRE(e.exit_code == 0);
    CHECK(e.out.find("rig export: ") != std::string::npos);
    CHECK(e.out.find("(" + compression + ")") != std::string::npos);
    const json stats = json::parse(nimble::test::slurp(dir + "/export.json"));
    CHECK(stats.at("undecodable") == 0);
    CHECK(stats.at("unknown_channel_events") == 0);
    if (std::string(compression) == "zstd") {
      // rig run --mcap made the same file from the same log.
      CHECK(nimble::test::slurp(out) == nimble::test::slurp(run_mcap));
      CHECK(fs::file_size(out) < fs::file_size(log));
    }

    const json r = read_with_node(out, "--sample TRUTH:0 --sample TRUTH:" + std::to_string(mid) + " --sample TRUTH:-1");
    CHECK(r.at("dataSectionCrcOk") == true);
    CHECK(r.at("library").get<std::string>().rfind("nimble-rig ", 0) == 0);
    // Every channel of the log, every message (a clean run has nothing undecodable).
    REQUIRE(r.at("channels").size() == lcm_counts.size());
    for (const auto& kv : lcm_counts) {
      INFO(kv.first);
      const json& c = channel(r, kv.first);
      CHECK(c.at("count") == kv.second);
      CHECK(c.at("messageEncoding") == "json");
      CHECK(c.at("schemaEncoding") == "jsonschema");
      CHECK(c.at("schemaName").get<std::string>().rfind("nimble.", 0) == 0);
      CHECK(r.at("stream").at("counts").at(kv.first) == kv.second);
      CHECK(r.at("statistics").at("channelMessageCounts").at(kv.first) == kv.second);
    }
    CHECK(channel(r, kTruth).at("schemaName") == "nimble.truth_state_t");
    CHECK(r.at("schemas").at("compiled") == r.at("schemas").at("jsonschema"));
    CHECK(r.at("schemas").at("failures").empty());
    CHECK(r.at("validation").at("parsed") == r.at("messages"));
    CHECK(r.at("validation").at("valid") == r.at("messages"));
    CHECK(r.at("validation").at("errors").empty());
    CHECK(r.at("stream").at("messages") == r.at("messages"));

    // TRUTH values against the LCM decode, first, middle and last.
    const json& samples = r.at("samples");
    check_truth(samples.at("TRUTH:0").at("message"), truth.front());
    check_truth(samples.at("TRUTH:" + std::to_string(mid)).at("message"), truth[mid]);
    check_truth(samples.at("TRUTH:-1").at("message"), truth.back());
    CHECK(ns(samples.at("TRUTH:-1").at("logTime")) == static_cast<uint64_t>(truth.back().utime) * 1000u);

    // Times: log time is rig time; the run starts at 0 and ends at its last step.
    const uint64_t start = ns(r.at("startTime")), end = ns(r.at("endTime"));
    CHECK(start == 0);
    CHECK(end >= static_cast<uint64_t>(truth.back().utime) * 1000u);
    CHECK(end <= 2100000000ull);
    CHECK(ns(r.at("statistics").at("messageStartTime")) == start);
    CHECK(ns(r.at("statistics").at("messageEndTime")) == end);
    CHECK(stats.at("start_time_ns") == start);
    CHECK(stats.at("end_time_ns") == end);
    CHECK(r.at("statistics").at("messageCount") == r.at("messages"));
    // The rig metadata: the log's name and the resolved scenario beside it.
    REQUIRE(r.at("metadata").size() == 1);
    CHECK(r.at("metadata")[0].at("name") == "rig");
    CHECK(r.at("metadata")[0].at("metadata").at("log") == "run.lcmlog");
    CHECK(r.at("metadata")[0].at("metadata").at("scenario").get<std::string>().find("duration_s: 2") !=
          std::string::npos);
  }
}

TEST_CASE("node: a damaged log is refused naming the offset, --salvage exports what is before it", "[mcap][node]") {
  const std::string dir = nimble::test::scratch_dir("mcap_node_damaged");
  const nimble::test::RunResult run =
      nimble::test::rig_run(RIG_SOURCE_DIR "/rig_configs/hover.yaml", dir, "--clock inprocess --set duration_s=0.5");
  REQUIRE(run.exit_code == 0);
  const std::string log = dir + "/run.lcmlog";
  // Cut the copy 20 bytes into the event in the middle of the log.
  std::vector<int64_t> offsets;
  {
    nimble::lcmlog::LcmLogReader reader(log);
    nimble::lcmlog::LogEventRecord ev;
    while (reader.next(&ev)) offsets.push_back(ev.offset);
  }
  REQUIRE(offsets.size() > 100);
  const std::size_t half = offsets.size() / 2;
  const std::string cut = dir + "/cut.lcmlog";
  fs::copy_file(log, cut);
  fs::resize_file(cut, static_cast<uintmax_t>(offsets[half] + 20));

  const std::string out = dir + "/cut.mcap";
  const RigResult refused = run_rig("export " + cut + " --format mcap --out " + out);
  CHECK(refused.exit_code == 2);
  CHECK_THAT(refused.err,
             Catch::Contains("damaged at byte " + std::to_string(offsets[half])) && Catch::Contains("--salvage"));
  CHECK_FALSE(fs::exists(out));
  CHECK_FALSE(fs::exists(out + ".part"));

  const RigResult salvaged = run_rig("export " + cut + " --format mcap --out " + out + " --salvage");
  INFO(salvaged.err);
  REQUIRE(salvaged.exit_code == 0);
  CHECK_THAT(salvaged.err, Catch::Contains("warning") && Catch::Contains("damaged at byte"));
  const json r = read_with_node(out);
  CHECK(r.at("messages") == half);
  CHECK(r.at("stream").at("messages") == half);
  CHECK(r.at("metadata")[0].at("metadata").at("damage").get<std::string>().find("damaged at byte") !=
        std::string::npos);
}
