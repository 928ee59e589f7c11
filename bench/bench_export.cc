/// bench_export: speed and size of `rig export --format mcap`.
///
///   bench_export [LOG.lcmlog] [--runs N] [--duration S] [--level N] [--json FILE|-]
///
/// Without a log, flies rig_configs/hover.yaml in process for S simulated seconds (default 60)
/// and takes its log. Prints:
///  - the export's wall time (median of N runs, default 3) with zstd and without compression
///    (the target: <= 2 s for a 60 s flight), and the file sizes against the LCM log's (the
///    target: zstd no larger than the log);
///  - the machine's floor in the same run: the LCM log read event by event, nothing decoded,
///    and the ratio export / floor; and the JSON decode alone (no MCAP), to show where the time
///    goes.
/// Not a test: the figures depend on the machine; the ratio to the floor is what travels.

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "cmdline/args.h"
#include "core/bench_timing.h"
#include "core/json_line.h"
#include "lcmlog/lcm_log.h"
#include "launcher/inprocess.h"
#include "launcher/run_plan.h"
#include "lcmjson/lcm_json.h"
#include "mcap/log_export.h"

namespace fs = std::filesystem;
using namespace nimble;

namespace {

/// Median wall seconds of `runs` calls of `f`.
double timed(int runs, const std::function<void()>& f) {
  std::vector<double> s;
  for (int i = 0; i < runs; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    s.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  return median(s);
}

/// The floor: every event of the log read (header checks, channel, bytes), nothing decoded.
int64_t read_events(const std::string& log) {
  lcmlog::LcmLogReader reader(log);
  lcmlog::LogEventRecord ev;
  int64_t bytes = 0;
  while (reader.next(&ev)) bytes += static_cast<int64_t>(ev.data.size());
  return bytes;
}

/// The log read and every message of a known channel decoded to JSON, nothing written.
int64_t decode_events(const std::string& log) {
  lcmlog::LcmLogReader reader(log);
  lcmlog::LogEventRecord ev;
  lcmjson::JsonMessage json;
  int64_t bytes = 0;
  while (reader.next(&ev)) {
    if (const lcmjson::LcmStruct* type = lcmjson::rig_type_for_channel(ev.channel)) {
      if (lcmjson::to_json(*type, ev.data.data(), ev.data.size(), &json).empty()) bytes += json.json.size();
    }
  }
  return bytes;
}

}  // namespace

int main(int argc, char** argv) {
  std::string log, json;
  int runs = 3;
  int level = mcap::ExportOptions{}.zstd_level;
  double duration_s = 60.0;
  cmdline::CommandLine cl("bench_export",
                          "Times rig export --format mcap (zstd and none) on a flight's log against the machine's\n"
                          "floor measured in the same run (the log read event by event, nothing decoded), and\n"
                          "prints the sizes.");
  cl->footer("Not a test: the figures depend on the machine; the ratio to the floor travels.");
  cl->add_option("log", log, "an LCM log to export (default: a hover flight of --duration seconds, flown here)")
      ->type_name("LOG.lcmlog");
  cl->add_option("--runs", runs, "runs of each figure (the median is reported)")
      ->check(CLI::Range(1, 1000))
      ->type_name("N")
      ->capture_default_str();
  cl->add_option("--duration", duration_s, "simulated seconds of the flight flown when no log is given")
      ->check(cmdline::kFinite & CLI::Range(0.1, 3600.0))
      ->type_name("S")
      ->capture_default_str();
  cl->add_option("--level", level, "zstd level of the zstd export (the export's own by default)")
      ->check(CLI::Range(1, 19))
      ->type_name("N")
      ->capture_default_str();
  cl.add_json(json, "the figures");
  if (const auto done = cl.parse(argc, argv)) return *done;
  const std::string dir = (fs::temp_directory_path() / ("bench_export_" + std::to_string(::getpid()))).string();
  fs::create_directories(dir);
  std::FILE* text = json == "-" ? stderr : stdout;
  try {
    std::string source = log;
    if (log.empty()) {
      launcher::RunOptions o;
      o.scenario_file = std::string(RIG_SOURCE_DIR) + "/rig_configs/hover.yaml";
      o.clock = launcher::kClockInprocess;
      o.overrides.push_back({"duration_s", std::to_string(duration_s)});
      const launcher::RunPlan plan = launcher::load_run_plan(o);
      launcher::InprocessOptions io;
      io.log_file = log = dir + "/hover.lcmlog";
      launcher::fly_inprocess(plan, io);
      source = "hover, " + std::to_string(static_cast<int>(duration_s)) + " s in process";
    }
    const double log_mb = static_cast<double>(fs::file_size(log)) / 1e6;

    mcap::ExportOptions zstd, none;
    zstd.compression = mcap::Compression::kZstd;
    zstd.zstd_level = level;
    none.compression = mcap::Compression::kNone;
    mcap::ExportStats zstd_stats, none_stats;
    const double zstd_s = timed(runs, [&] { zstd_stats = mcap::export_log_to_mcap(log, dir + "/zstd.mcap", zstd); });
    const double none_s = timed(runs, [&] { none_stats = mcap::export_log_to_mcap(log, dir + "/none.mcap", none); });
    const double floor_s = timed(runs, [&] { read_events(log); });
    const double decode_s = timed(runs, [&] { decode_events(log); });
    const double zstd_mb = static_cast<double>(zstd_stats.bytes_out) / 1e6;
    const double none_mb = static_cast<double>(none_stats.bytes_out) / 1e6;

    std::fprintf(text, "bench_export: %s, %llu events, %d runs each (median), zstd level %d\n", source.c_str(),
                 static_cast<unsigned long long>(zstd_stats.events), runs, level);
    std::fprintf(text, "  %-52s %8.1f MB\n", "LCM log", log_mb);
    std::fprintf(text, "  %-52s %8.3f s  %8.1f MB (%.2f of the log; target <= 1)\n",
                 "export, zstd (target <= 2 s for 60 s)", zstd_s, zstd_mb, zstd_mb / log_mb);
    std::fprintf(text, "  %-52s %8.3f s  %8.1f MB\n", "export, no compression", none_s, none_mb);
    std::fprintf(text, "  %-52s %8.3f s\n", "  of which: log read and JSON decode, nothing written", decode_s);
    std::fprintf(text, "  %-52s %8.3f s\n", "floor: the log read event by event, nothing decoded", floor_s);
    std::fprintf(text, "  ratio export zstd / floor: %.1f   export none / floor: %.1f\n", zstd_s / floor_s,
                 none_s / floor_s);
    if (!json.empty()) {
      OrderedJson j;
      j["source"] = source;
      j["runs"] = runs;
      j["events"] = zstd_stats.events;
      j["log_bytes"] = fs::file_size(log);
      j["zstd"] = {{"seconds", zstd_s}, {"bytes", zstd_stats.bytes_out}, {"level", level}};
      j["none"] = {{"seconds", none_s}, {"bytes", none_stats.bytes_out}};
      j["decode_seconds"] = decode_s;
      j["floor_seconds"] = floor_s;
      j["ratio_zstd_floor"] = zstd_s / floor_s;
      cmdline::write_json(json, json_line(j));
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_export: %s\n", e.what());
    fs::remove_all(dir);
    return 2;
  }
  fs::remove_all(dir);
  return 0;
}
