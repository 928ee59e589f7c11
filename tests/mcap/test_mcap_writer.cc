/// The MCAP writer against an independent reader of the specification (mcap_check.h): the
/// structure of every record, the CRCs, the indexes and the statistics, both compressions,
/// and the `.part` file that only a successful close() renames.

#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "mcap/mcap_writer.h"
#include "tests/mcap/mcap_check.h"
#include "contract/channels.h"
#include "tests/support/scratch.h"

// Channel names come from the contract (functional.contract checks that no file spells them).
using nimble::contract::channels::kImu;
using nimble::contract::channels::kTruth;

namespace fs = std::filesystem;
using nimble::mcap::Compression;
using nimble::mcap::McapWriter;
using nimble::mcap::WriteError;
using nimble::mcap::WriterOptions;
namespace check = nimble::test::mcap_check;

namespace {

std::string scratch(const std::string& name) {
  const fs::path p = nimble::test::scratch_file("mcap_writer", name);
  fs::remove(p);
  fs::remove(p.string() + ".part");
  return p.string();
}

struct Written {
  uint16_t channel;
  uint32_t sequence;
  uint64_t log_time, publish_time;
  std::string data;
};

/// Three channels on two schemas, `n` messages with varied sizes, times not strictly ordered
/// across channels (as a log's wall-clock channels are), and one metadata record.
std::vector<Written> write_sample(const std::string& path, WriterOptions options, int n) {
  McapWriter w(path, options);
  const uint16_t s1 = w.add_schema("nimble.truth_state_t", "jsonschema", R"({"type":"object"})");
  const uint16_t s2 = w.add_schema("nimble.imu_t", "jsonschema", R"({"type":"object","title":"imu"})");
  const uint16_t truth = w.add_channel(s1, kTruth, "json");
  const uint16_t imu = w.add_channel(s2, kImu, "json", {{"rate", "512 Hz"}});
  const uint16_t raw = w.add_channel(0, "TRUTH/lcm", "lcm");
  w.add_metadata("rig", {{"scenario", "name: hover\n"}, {"log", "run.lcmlog"}});
  std::vector<Written> out;
  for (int i = 0; i < n; ++i) {
    const uint16_t ch = i % 3 == 0 ? truth : i % 3 == 1 ? imu : raw;
    const uint64_t t = 1000000ull * static_cast<uint64_t>(i / 3) + (ch == imu ? 7 : 0);
    std::string data =
        "{\"i\":" + std::to_string(i) + ",\"pad\":\"" + std::string(static_cast<std::size_t>(i % 97), 'x') + "\"}";
    if (ch == raw) data.assign(1 + i % 13, static_cast<char>(i));  // binary bytes, NULs included
    out.push_back({ch, static_cast<uint32_t>(i), t, t + 5, data});
    w.add_message(ch, static_cast<uint32_t>(i), t, t + 5, data.data(), data.size());
  }
  w.close();
  return out;
}

}  // namespace

TEST_CASE("an MCAP file of three channels reads back whole, in both compressions", "[mcap]") {
  const Compression compression = GENERATE(Compression::kNone, Compression::kZstd);
  CAPTURE(nimble::mcap::to_string(compression));
  const std::string path = scratch(std::string("sample_") + nimble::mcap::to_string(compression) + ".mcap");
  WriterOptions o;
  o.compression = compression;
  o.chunk_size = 8 * 1024;  // many chunks
  const std::vector<Written> written = write_sample(path, o, 3001);
  const std::string bytes = check::slurp_binary(path);
  const check::McapFile f = check::check(bytes);
  INFO(check::problems_text(f));
  REQUIRE(f.problems.empty());

  CHECK(f.profile.empty());
  CHECK(f.library == "nimble-rig");
  REQUIRE(f.chunk_count > 10);
  for (const auto& c : f.compressions) CHECK(c == (compression == Compression::kZstd ? "zstd" : ""));
  // A chunk closes once it reaches the chunk size: at most one message beyond it.
  CHECK(f.max_uncompressed_chunk < o.chunk_size + 512);

  REQUIRE(f.schemas.size() == 2);
  CHECK(f.schemas.at(1).name == "nimble.truth_state_t");
  CHECK(f.schemas.at(2).data == R"({"type":"object","title":"imu"})");
  REQUIRE(f.channels.size() == 3);
  CHECK(f.channels.at(2).topic == kImu);
  CHECK(f.channels.at(2).metadata.at("rate") == "512 Hz");
  CHECK(f.channels.at(3).schema_id == 0);
  CHECK(f.channels.at(3).message_encoding == "lcm");

  REQUIRE(f.messages.size() == written.size());
  for (std::size_t i = 0; i < written.size(); ++i) {
    const auto& m = f.messages[i];
    const auto& w = written[i];
    if (m.channel_id != w.channel || m.sequence != w.sequence || m.log_time != w.log_time ||
        m.publish_time != w.publish_time || m.data != w.data) {
      FAIL("message " << i << " differs from what was written");
    }
  }
  REQUIRE(f.has_statistics);
  CHECK(f.statistics.message_count == 3001);
  CHECK(f.statistics.channel_counts.at(1) == 1001);
  CHECK(f.statistics.channel_counts.at(2) == 1000);
  CHECK(f.statistics.channel_counts.at(3) == 1000);
  CHECK(f.statistics.start == 0);
  CHECK(f.statistics.end == 1000000000ull);  // message 3000 is TRUTH at i/3 = 1000
  CHECK(f.statistics.metadata_count == 1);
  CHECK(f.statistics.chunk_count == f.chunk_count);
  REQUIRE(f.metadata.count("rig") == 1);
  CHECK(f.metadata.at("rig").at("scenario") == "name: hover\n");
  CHECK(f.metadata.at("rig").at("log") == "run.lcmlog");
}

TEST_CASE("zstd chunks are smaller than the same chunks uncompressed", "[mcap]") {
  WriterOptions o;
  o.compression = Compression::kNone;
  const std::string plain = scratch("plain.mcap");
  write_sample(plain, o, 3000);
  o.compression = Compression::kZstd;
  const std::string packed = scratch("packed.mcap");
  write_sample(packed, o, 3000);
  CHECK(fs::file_size(packed) * 3 < fs::file_size(plain));
}

TEST_CASE("the checking reader finds a flipped byte, a wrong length and a cut file", "[mcap]") {
  // The reader of these tests must be able to fail: damage a good file three ways.
  WriterOptions o;
  o.compression = Compression::kNone;
  o.chunk_size = 4096;
  const std::string path = scratch("damage.mcap");
  write_sample(path, o, 300);
  const std::string good = check::slurp_binary(path);
  REQUIRE(check::check(good).problems.empty());

  std::string flipped = good;
  flipped[200] = static_cast<char>(flipped[200] ^ 0x20);  // inside the first chunk's records
  const auto f1 = check::check(flipped);
  CHECK_THAT(check::problems_text(f1), Catch::Contains("CRC"));

  std::string cut = good.substr(0, good.size() / 2) + good.substr(good.size() - 8);
  CHECK_FALSE(check::check(cut).problems.empty());

  // The footer's summary CRC covers the summary offsets: change one group length.
  std::string summary_changed = good;
  summary_changed[good.size() - 8 - 29 - 3] ^= 0x01;  // inside the last Summary Offset record
  CHECK_THAT(check::problems_text(check::check(summary_changed)), Catch::Contains("summary"));
}

TEST_CASE("messages added out of log-time order are indexed in log-time order", "[mcap]") {
  const std::string path = scratch("unordered.mcap");
  WriterOptions o;
  o.compression = Compression::kNone;
  {
    McapWriter w(path, o);
    const uint16_t ch = w.add_channel(0, "X", "json");
    for (const uint64_t t : {50, 10, 30, 10, 20}) w.add_message(ch, static_cast<uint32_t>(t), t, t, "{}", 2);
    w.close();
  }
  const auto f = check::check(check::slurp_binary(path));
  INFO(check::problems_text(f));
  CHECK(f.problems.empty());  // the checking reader requires each index in log-time order
  CHECK(f.statistics.start == 10);
  CHECK(f.statistics.end == 50);
  REQUIRE(f.messages.size() == 5);
  CHECK(f.messages[0].log_time == 50);  // the chunk keeps the order they came in
}

TEST_CASE("an MCAP file without messages is valid and says so", "[mcap]") {
  const std::string path = scratch("empty.mcap");
  {
    McapWriter w(path);
    w.add_channel(w.add_schema("s", "jsonschema", "{}"), "EMPTY", "json");
    w.close();
    CHECK(w.stats().messages == 0);
    CHECK(w.stats().chunks == 0);
    CHECK(w.stats().bytes == fs::file_size(path));
  }
  const auto f = check::check(check::slurp_binary(path));
  INFO(check::problems_text(f));
  CHECK(f.problems.empty());
  CHECK(f.statistics.message_count == 0);
  CHECK(f.statistics.start == 0);
  CHECK(f.statistics.channel_counts.at(1) == 0);
}

TEST_CASE("the file appears under its name only at a successful close", "[mcap]") {
  const std::string path = scratch("atomic.mcap");
  {
    McapWriter w(path);
    const uint16_t ch = w.add_channel(0, "X", "json");
    for (int i = 0; i < 1000; ++i) w.add_message(ch, 0, i, i, "{}", 2);
    CHECK(fs::exists(path + ".part"));
    CHECK_FALSE(fs::exists(path));
    w.close();
    CHECK(fs::exists(path));
    CHECK_FALSE(fs::exists(path + ".part"));
  }
  CHECK(fs::exists(path));  // the destructor after close() keeps it

  const std::string abandoned = scratch("abandoned.mcap");
  {
    McapWriter w(abandoned);
    const uint16_t ch = w.add_channel(0, "X", "json");
    w.add_message(ch, 0, 1, 1, "{}", 2);
    REQUIRE(fs::exists(abandoned + ".part"));
  }  // destroyed without close()
  CHECK_FALSE(fs::exists(abandoned));
  CHECK_FALSE(fs::exists(abandoned + ".part"));
}

TEST_CASE("a file that cannot be created is an error naming it", "[mcap]") {
  const std::string path = scratch("no_such_dir") + "/sub/out.mcap";
  try {
    McapWriter w(path);
    FAIL("no error");
  } catch (const WriteError& e) {
    CHECK_THAT(e.what(), Catch::Contains(path + ".part") && Catch::Contains("No such file or directory"));
  }
}

TEST_CASE("a write that fails (file size limit) names the file and leaves nothing", "[mcap]") {
  // The file-size limit stands in for a full disk: writes fail with EFBIG instead of ENOSPC.
  const std::string path = scratch("limited.mcap");
  struct rlimit old {};
  REQUIRE(::getrlimit(RLIMIT_FSIZE, &old) == 0);
  ::signal(SIGXFSZ, SIG_IGN);
  struct rlimit small = old;
  small.rlim_cur = 64 * 1024;
  REQUIRE(::setrlimit(RLIMIT_FSIZE, &small) == 0);
  std::string error;
  try {
    WriterOptions o;
    o.compression = Compression::kNone;
    o.chunk_size = 16 * 1024;
    McapWriter w(path, o);
    const uint16_t ch = w.add_channel(0, "X", "json");
    const std::string data(200, 'a');
    for (int i = 0; i < 2000; ++i) w.add_message(ch, 0, i, i, data.data(), data.size());
    w.close();
  } catch (const WriteError& e) {
    error = e.what();
  }
  ::setrlimit(RLIMIT_FSIZE, &old);
  CHECK_THAT(error, Catch::Contains(path) && Catch::Contains("File too large"));
  CHECK_FALSE(fs::exists(path));
  CHECK_FALSE(fs::exists(path + ".part"));
}

TEST_CASE("bad arguments to the writer are refused", "[mcap]") {
  const std::string path = scratch("bad.mcap");
  WriterOptions o;
  o.chunk_size = 0;
  CHECK_THROWS_AS(McapWriter(path, o), std::invalid_argument);
  o.chunk_size = 1024;
  o.zstd_level = 99;
  CHECK_THROWS_WITH(McapWriter(path, o), Catch::Contains("zstd level 99"));
  McapWriter w(path);
  CHECK_THROWS_WITH(w.add_channel(3, "X", "json"), Catch::Contains("no schema 3"));
  CHECK_THROWS_WITH(w.add_message(1, 0, 0, 0, "", 0), Catch::Contains("unknown channel 1"));
  CHECK_THROWS_WITH(nimble::mcap::compression_from_string("lz4"), Catch::Contains("lz4"));
}
