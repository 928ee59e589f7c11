/// `rig run`: launching a scenario and recording it.

#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "cmdline/args.h"
#include "core/output_lock.h"
#include "cli/commands.h"
#include "cli/live_view_setup.h"
#include "launcher/launcher.h"
#include "mcap/log_export.h"

namespace nimble::cli {
namespace {

constexpr const char* kRunDescription =
    "Starts every process of the scenario, records all channels to an LCM log (replay it with\n"
    "lcm-logplayer) and prints a summary. realtime and lockstep run each process as its own OS\n"
    "process over LCM; inprocess flies the same processes' code in this process, lockstep\n"
    "semantics, no transport (same log, same truth as lockstep). Real time is judged from what\n"
    "each process reports: more than summary.max_late_fraction of a channel late or\n"
    "summary.max_overrun_fraction of a process's cycles overrun gives 'real-time degraded'.\n"
    "A process the scenario's `participants` section replaces by a Python class runs as\n"
    "run.python -m nimble_rig.node (realtime, lockstep); in process it flies only from Python,\n"
    "nimble_rig.fly() (docs/python.md).";

constexpr const char* kRunFooter =
    "Network: run.network_namespace auto (default) flies realtime and lockstep runs in a private\n"
    "network namespace whose loopback carries multicast; 'rig spy --pid PID' joins it. always:\n"
    "fail if one cannot be made; never: the host's network (see rig check).\n"
    "Exit code: 0 controlled, 1 not controlled, 2 bad input, 3 a process failed, hung\n"
    "(HEARTBEAT_LOST), the run stalled or its log could not be written, 4 real-time degraded (only with "
    "--strict-timing),\n"
    "5 completed in the controller's failsafe, 6 controlled but not tracking (the roll tracking error\n"
    "beyond summary.max_tracking_rms_deg or max_tracking_error_deg, or a sustained or growing roll\n"
    "oscillation), 130 interrupted.";

/// `--mcap F`: the run's own log exported to F after the run, before its summary (whatever the
/// verdict: a failed flight is the one most worth looking at). Its line goes where the summary's
/// text goes (stderr when `--json -` has stdout). Returns "" or what failed: an export that fails
/// after an ok run makes it `failed` (exit 3), in the result line and the exit code alike.
std::string export_run_log(const std::string& log, const std::string& mcap_file, bool json_on_stdout) {
  if (!std::filesystem::exists(log)) return "--mcap " + mcap_file + ": the run wrote no log (" + log + ")";
  try {
    const mcap::ExportStats stats = mcap::export_log_to_mcap(log, mcap_file, {});
    (json_on_stdout ? std::cerr : std::cout) << "mcap       " << mcap::summary_line(stats) << "\n";
  } catch (const std::exception& e) {
    std::cerr << "rig run: --mcap " << mcap_file << ": " << e.what() << "\n";
    return "--mcap " + mcap_file + ": " + e.what();
  }
  return "";
}

}  // namespace

int run_run_command(const std::vector<std::string>& args) {
  launcher::RunOptions o;
  cmdline::CommandLine cl("rig run", kRunDescription);
  cl->footer(kRunFooter);
  cl->add_option("scenario", o.scenario_file, "the scenario file (rig_configs/*.yaml)")->required();
  cl->add_option("--clock", o.clock, "realtime, lockstep or inprocess (default: the scenario's clock)")
      ->check(CLI::IsMember({std::string(launcher::kClockRealtime), std::string(launcher::kClockLockstep),
                             std::string(launcher::kClockInprocess)}));
  cl->add_option("--log", o.log_file,
                 "the LCM log (default rig_logs/<name>-<time>.lcmlog); the resolved scenario and each "
                 "process's output are written next to it")
      ->type_name("FILE");
  cl->add_option("--log-max-bytes", o.log_max_bytes,
                 "the log may take at most N bytes: a run whose log is expected to take more is refused before "
                 "it starts, and one whose log reaches N ends there (failed, the log whole up to it)")
      ->check(CLI::PositiveNumber)
      ->type_name("N");
  cl->add_flag("--no-space-check",
               "fly even if the log's filesystem has less free space than the log is expected to take (a full "
               "disk then ends the run, named, with the log whole up to it)")
      ->each([&o](const std::string&) { o.space_check = false; });
  std::string mcap_file;
  cl->add_option("--mcap", mcap_file,
                 "also the run's log as MCAP (zstd; as rig export --format mcap) for Foxglove, Lichtblick, "
                 "PlotJuggler, written after the run")
      ->type_name("FILE");
  cl.add_json(o.json_file, "the run summary");
  std::string foxglove;
  cl->add_option("--foxglove", foxglove,
                 "serve the run live to Foxglove or Lichtblick (Open connection -> Foxglove WebSocket -> "
                 "ws://HOST:PORT): every channel as JSON, read-only; host 127.0.0.1 unless given, port 0 picks a "
                 "free one (printed on stderr); e.g. --foxglove 8765 (docs/live_view.md)")
      ->type_name("[HOST:]PORT");
  cmdline::each_value(cl->add_option("--set",
                                     "override one scenario value, parsed as YAML; repeatable: --set duration_s=3, "
                                     "--set processes=[plant,controller], --set 'faults=[{target: IMU, kind: off, "
                                     "start_s: 1}]' (quote values with spaces for the shell)")
                          ->type_name("KEY.PATH=VALUE")
                          ->allow_extra_args(false)
                          ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll),
                      [&o](const std::string& v) { o.overrides.push_back(parse_override(v)); });
  cl->add_option("--seed", o.seed, "the run's seed (a whole number >= 0; default: the scenario's seed)")
      ->check(cmdline::kWholeNumber)
      ->type_name("N");
  cl->add_flag("--no-progress", "no progress line on stderr (for logs and scripts)")->each([&o](const std::string&) {
    o.progress = false;
  });
  cl->add_flag("--strict-timing", o.strict_timing, "a real-time degraded run exits 4");
  bool vibration = false;
  cl->add_flag("--vibration", vibration,
               "the real vehicle's flight vibration and its on-board IMU filtering: --set sensing.base=<the source "
               "tree's rig_configs/sensing/nimble_flight_vibration.yaml> (before any --set)");
  if (const auto done = cl.parse(args)) return *done;
  if (vibration) o.overrides.insert(o.overrides.begin(), Override{"sensing.base", NIMBLE_DEFAULT_VIBRATION});
  // The live view (--foxglove) is bound here, before the launcher moves into the run's network
  // namespace: the socket stays on this host's network, where Foxglove can reach it. It is closed
  // when `live` goes, after the run.
  std::unique_ptr<LiveViewSession> live;
  if (!foxglove.empty()) {
    try {
      live = open_live_view("run", foxglove);
    } catch (const std::exception& e) {
      return cl.fail("--foxglove " + foxglove + ": " + e.what());
    }
    tap_run(*live, o);
  }
  if (mcap_file.empty()) return launcher::run_scenario(o);
  if (const std::string problem = launcher::writable_problem(mcap_file); !problem.empty()) {
    return cl.fail("--mcap " + mcap_file + ": " + problem);
  }
  // One writer per MCAP file: it is written as FILE.part and renamed, so the part is taken now,
  // before the flight, and held to the end (the export goes on under this lock).
  const std::string part = mcap::part_file_of(mcap_file);
  const bool part_was_there = std::filesystem::exists(part);
  OutputLock mcap_lock;
  try {
    mcap_lock = OutputLock::file(part, "the MCAP file");
  } catch (const OutputError& e) {
    std::cerr << "rig run: refused: --mcap: " << e.what() << "\n";
    return launcher::kRunBadInput;
  }
  const bool json_on_stdout = o.json_file == "-";
  o.after_log = [&](const std::string& log) { return export_run_log(log, mcap_file, json_on_stdout); };
  const int code = launcher::run_scenario(o);
  // A part this run made and never wrote (refused before the flight) is not left behind.
  std::error_code ec;
  if (!part_was_there && std::filesystem::is_regular_file(part, ec) && std::filesystem::file_size(part, ec) == 0) {
    std::filesystem::remove(part, ec);
  }
  return code;
}

}  // namespace nimble::cli
