// Garbage that decodes is named, and no verdict comes from no data: a log with one TRUTH
// event's payload scrambled after its fingerprint and time (every value of it garbage, the
// message still decoding) goes through every reader that turns log messages into numbers
// (rig export as CSV and MCAP, identify, validate, discrepancy, view); each applies the vehicle
// file's physical bounds through core/data_bounds.h and names the channel, field, time and count.
// An export warns and leaves the message out (no value beyond the bounds reaches the CSV), or
// refuses it with --strict; an analysis refuses the log. A record of zeros is refused by every
// analysis with one message, and no nan is printed. The Python module's readers:
// test_garbled_payload.py.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "contract/channels.h"
#include "core/data_bounds.h"
#include "core/vehicle.h"
#include "lcmlog/lcm_log.h"
#include "tests/support/run_rig.h"
#include "tests/support/scratch.h"

namespace fs = std::filesystem;
using nimble::test::RigResult;
using nimble::test::run_rig;

namespace {

const std::string kSource = RIG_SOURCE_DIR;
const std::string kModel = kSource + "/rig_configs/models/nimble_lateral_set1.yaml";

/// A flown log with one TRUTH event's values scrambled: where it is and what it claims.
struct Garbled {
  std::string log;
  std::int64_t event = -1;
  double t_s = 0.0;  ///< its rig time (kept: the scramble starts after utime)
};

std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

/// Flies rig_configs/hover.yaml for 3 s in process (once per test process) and reverses the bytes
/// of the middle TRUTH event after its fingerprint and utime: seq, step and every double.
const Garbled& garbled() {
  static const Garbled g = [] {
    const std::string dir = nimble::test::scratch_dir("garbled");
    const std::string clean = dir + "/hover.lcmlog";
    const RigResult run =
        run_rig("run " + kSource + "/rig_configs/hover.yaml --clock inprocess --set duration_s=3 --log " + clean);
    REQUIRE(run.exit_code == 0);
    std::vector<nimble::lcmlog::LogEventRecord> truth;
    nimble::lcmlog::LcmLogReader reader(clean);
    nimble::lcmlog::LogEventRecord ev;
    while (reader.next(&ev)) {
      if (ev.channel == nimble::contract::channels::kTruth) truth.push_back(ev);
    }
    REQUIRE(truth.size() > 100);
    const nimble::lcmlog::LogEventRecord& victim = truth[truth.size() / 2];
    std::string bytes = read_bytes(clean);
    const std::size_t payload = static_cast<std::size_t>(victim.offset) + 28 + victim.channel.size();
    REQUIRE(bytes.compare(payload, victim.data.size(), std::string(victim.data.begin(), victim.data.end())) == 0);
    std::reverse(bytes.begin() + static_cast<long>(payload + 16),
                 bytes.begin() + static_cast<long>(payload + victim.data.size()));
    Garbled out;
    out.log = dir + "/garbled.lcmlog";
    std::ofstream(out.log, std::ios::binary) << bytes;
    std::int64_t utime = 0;
    for (int i = 0; i < 8; ++i)
      utime = (utime << 8) | static_cast<unsigned char>(victim.data[8 + static_cast<std::size_t>(i)]);
    out.event = victim.event_number;
    out.t_s = static_cast<double>(utime) * 1e-6;
    return out;
  }();
  return g;
}

std::string at_text(double t_s) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "at t = %.4f s", t_s);
  return buf;
}

/// The largest |value| of each column of a CSV file written by rig export, beyond its bound.
std::vector<std::string> columns_beyond_bounds(const std::string& csv) {
  std::ifstream in(csv);
  std::string line;
  std::vector<std::string> header, beyond;
  const nimble::DataBounds bounds;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> cells;
    std::stringstream s(line);
    for (std::string c; std::getline(s, c, ',');) cells.push_back(c);
    if (header.empty()) {
      header = cells;
      continue;
    }
    for (std::size_t j = 1; j < cells.size() && j < header.size(); ++j) {
      const double x = std::stod(cells[j]);
      const auto b = nimble::quantity_bound(header[j], bounds);
      if (!std::isfinite(x) || (b && std::fabs(x) > b->value)) beyond.push_back(header[j] + " = " + cells[j]);
    }
  }
  return beyond;
}

/// The scrambled message named by channel, a field, its time and event, and its count.
void check_named(const std::string& text) {
  const Garbled& g = garbled();
  INFO(text);
  CHECK(text.find("TRUTH ") != std::string::npos);
  CHECK(text.find("beyond the physical bound") != std::string::npos);
  CHECK(text.find(at_text(g.t_s)) != std::string::npos);
  CHECK(text.find("vehicle file " + kSource + "/rig_configs/vehicles/nimble_no_wifi.yaml") != std::string::npos);
}

}  // namespace

TEST_CASE(
    "garbled payload: rig export --csv warns naming the message, leaves it out, and writes no value beyond the "
    "bounds, and --strict refuses it",
    "[resource][garbled]") {
  const Garbled& g = garbled();
  const std::string dir = nimble::test::scratch_dir("garbled_csv");
  const RigResult r =
      run_rig("export " + g.log + " --csv " + dir + "/truth.csv --states truth --json " + dir + "/e.json");
  REQUIRE(r.exit_code == 0);
  check_named(r.err);
  CHECK(r.err.find("rig export: warning: " + g.log + ": left out: 1 message with ") != std::string::npos);
  CHECK(r.err.find("(event " + std::to_string(g.event) + ")") != std::string::npos);
  CHECK(columns_beyond_bounds(dir + "/truth.csv").empty());
  const std::string json = nimble::test::slurp(dir + "/e.json");
  CHECK(json.find("\"beyond_bounds\":{\"messages\":1,") != std::string::npos);
  CHECK(json.find("\"channel\":\"TRUTH\"") != std::string::npos);

  const RigResult strict = run_rig("export " + g.log + " --csv " + dir + "/strict.csv --states truth --strict");
  CHECK(strict.exit_code == 2);
  CHECK(strict.err.rfind("rig export: error: refused: " + g.log + ": TRUTH ", 0) == 0);
  check_named(strict.err);
  CHECK_FALSE(fs::exists(dir + "/strict.csv"));
}

TEST_CASE(
    "garbled payload: rig export --format mcap leaves the message out of the JSON channel and names it, and "
    "--strict refuses and leaves no file",
    "[resource][garbled]") {
  const Garbled& g = garbled();
  const std::string dir = nimble::test::scratch_dir("garbled_mcap");
  const RigResult r = run_rig("export " + g.log + " --out " + dir + "/g.mcap --json -");
  REQUIRE(r.exit_code == 0);
  check_named(r.err);
  CHECK(r.err.find("1 beyond the physical bounds left out (TRUTH 1)") != std::string::npos);
  CHECK(r.out.find("\"beyond_bounds_messages\":1") != std::string::npos);
  const std::size_t truth = r.out.find("\"TRUTH\":{");
  REQUIRE(truth != std::string::npos);
  CHECK(r.out.find("\"beyond_bounds\":1", truth) != std::string::npos);

  const RigResult strict = run_rig("export " + g.log + " --out " + dir + "/s.mcap --strict");
  CHECK(strict.exit_code == 2);
  check_named(strict.err);
  CHECK_FALSE(fs::exists(dir + "/s.mcap"));
  CHECK_FALSE(fs::exists(dir + "/s.mcap.part"));
}

TEST_CASE(
    "garbled payload: identify, validate and discrepancy refuse the log with one message naming the channel, "
    "field, time and count",
    "[resource][garbled]") {
  const Garbled& g = garbled();
  std::string first;
  for (const std::string& command :
       {"identify " + g.log + " --states truth", "validate " + kModel + " " + g.log + " --states truth",
        "discrepancy " + g.log + " --model " + kModel + " --states truth"}) {
    const RigResult r = run_rig(command);
    INFO(command << "\n" << r.err);
    CHECK(r.exit_code == 2);
    check_named(r.err);
    const std::size_t refused = r.err.find("refused: " + g.log + ": TRUTH ");
    REQUIRE(refused != std::string::npos);
    const std::string message = r.err.substr(refused);
    CHECK(message.find(" samples beyond the physical bounds of vehicle file ") != std::string::npos);
    if (first.empty()) first = message;
    CHECK(message == first);  // the same message from every analysis
  }
}

TEST_CASE("garbled payload: rig view does not show the message and names it", "[resource][garbled]") {
  const Garbled& g = garbled();
  const RigResult r = run_rig("view " + g.log + " --speed 0 --foxglove 0 --exit-when-done");
  CHECK(r.exit_code == 0);
  check_named(r.err);
  CHECK(r.err.find("rig view: warning: " + g.log + ": left out: 1 message with ") != std::string::npos);
  CHECK((r.out + r.err).find("beyond_bounds 1") != std::string::npos);  // the live view's figures
}

TEST_CASE(
    "a record of zeros: identify, validate and discrepancy (one flight and pooled) refuse it with one message, "
    "and print no nan",
    "[resource][garbled]") {
  const std::string csv = nimble::test::scratch_file("zero_record", "zero.csv");
  {
    std::ofstream out(csv);
    out << "t,p,v,phi,delta_f,delta_t\n";
    for (int k = 0; k < 3072; ++k) out << k / 512.0 << ",0,0,0,0,0\n";
  }
  const std::string expected = "refused: " + csv + ": no excitation: p is zero throughout (3072 samples)";
  for (const std::string& command :
       {"identify " + csv, "validate " + kModel + " " + csv, "validate " + kModel + " " + csv + " --closed-loop",
        "discrepancy " + csv + " --model " + kModel, "discrepancy " + csv + " " + csv + " --model " + kModel,
        "discrepancy " + csv + " --model " + kModel + " --json -"}) {
    const RigResult r = run_rig(command);
    INFO(command << "\n" << r.out << r.err);
    CHECK(r.exit_code == 2);
    CHECK(r.err.find(expected) != std::string::npos);
    CHECK(r.out.find("nan") == std::string::npos);
    CHECK(r.err.find("nan") == std::string::npos);
  }
}
