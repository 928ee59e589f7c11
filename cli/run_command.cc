/// `rig run`, `rig check`, `rig spy`: launching and watching the live rig.

#include <fcntl.h>
#include <sched.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "cmdline/args.h"
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
    "summary.max_overrun_fraction of a process's cycles overrun gives 'real-time degraded'.";

constexpr const char* kRunFooter =
    "Network: run.network_namespace auto (default) flies realtime and lockstep runs in a private\n"
    "network namespace whose loopback carries multicast; 'rig spy --pid PID' joins it. always:\n"
    "fail if one cannot be made; never: the host's network (see rig check).\n"
    "Exit code: 0 controlled, 1 not controlled, 2 bad input, 3 a process failed, hung\n"
    "(HEARTBEAT_LOST), the run stalled or its log could not be written, 4 real-time degraded (only with --strict-timing),\n"
    "5 completed in the controller's failsafe, 6 controlled but not tracking (the roll tracking error\n"
    "beyond summary.max_tracking_rms_deg or max_tracking_error_deg, or a sustained or growing roll\n"
    "oscillation), 130 interrupted.";

/// The inode of a namespace link (/proc/<pid>/ns/<kind>), 0 if it cannot be read.
ino_t namespace_inode(const std::string& pid, const std::string& kind) {
  struct stat st{};
  return ::stat(("/proc/" + pid + "/ns/" + kind).c_str(), &st) == 0 ? st.st_ino : 0;
}

/// Joins the namespace `kind` (CLONE_NEWUSER or CLONE_NEWNET) of `pid`; "" or why not.
std::string join_namespace(const std::string& pid, const std::string& kind, int type) {
  const std::string path = "/proc/" + pid + "/ns/" + kind;
  const int fd = ::open(path.c_str(), O_RDONLY);
  if (fd < 0) return "cannot open " + path + ": " + std::strerror(errno);
  const int r = ::setns(fd, type);
  const int err = errno;
  ::close(fd);
  return r == 0 ? "" : "cannot join " + path + ": " + std::strerror(err);
}

std::string self_dir() {
  std::error_code ec;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::string(".") : exe.parent_path().string();
}

/// `--mcap F`: the run's own log exported to F after the run (whatever the verdict: a failed
/// flight is the one most worth looking at). Its line goes where the summary's text goes (stderr
/// when `--json -` has stdout). Returns the run's exit code, or kExitUsage if the export failed
/// after a run that succeeded.
int export_run_log(const std::string& log, const std::string& mcap_file, bool json_on_stdout, int run_code) {
  if (!std::filesystem::exists(log)) {
    std::cerr << "rig run: --mcap " << mcap_file << ": the run wrote no log (" << log << ")\n";
    return run_code != 0 ? run_code : kExitUsage;
  }
  try {
    const mcap::ExportStats stats = mcap::export_log_to_mcap(log, mcap_file, {});
    (json_on_stdout ? std::cerr : std::cout) << "mcap       " << mcap::summary_line(stats) << "\n";
  } catch (const std::exception& e) {
    std::cerr << "rig run: --mcap " << mcap_file << ": " << e.what() << "\n";
    return run_code != 0 ? run_code : kExitUsage;
  }
  return run_code;
}

}  // namespace

int run_run_command(const std::vector<std::string>& args) {
  launcher::RunOptions o;
  CommandLine cl("rig run", kRunDescription);
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
  each_value(cl->add_option("--set", "override one scenario value, parsed as YAML; repeatable: --set duration_s=3, "
                                     "--set processes=[plant,controller], --set 'faults=[{target: IMU, kind: off, "
                                     "start_s: 1}]' (quote values with spaces for the shell)")
                 ->type_name("KEY.PATH=VALUE")
                 ->allow_extra_args(false)
                 ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll),
             [&o](const std::string& v) { o.overrides.push_back(parse_override(v)); });
  cl->add_option("--seed", o.seed, "the run's seed (a whole number >= 0; default: the scenario's seed)")
      ->check(kWholeNumber)
      ->type_name("N");
  cl->add_flag("--no-progress", "no progress line on stderr (for logs and scripts)")
      ->each([&o](const std::string&) { o.progress = false; });
  cl->add_flag("--strict-timing", o.strict_timing, "a real-time degraded run exits 4");
  if (const auto done = cl.parse(args)) return *done;
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
  // The export needs the log's name: the default one is decided here, as the launcher would.
  if (o.log_file.empty()) {
    try {
      o.log_file = launcher::log_file_for(launcher::load_run_plan(o), o);
    } catch (const std::exception&) {
      return launcher::run_scenario(o);  // reports the scenario's error itself
    }
  }
  const int code = launcher::run_scenario(o);
  return export_run_log(o.log_file, mcap_file, o.json_file == "-", code);
}

int run_check_command(const std::vector<std::string>& args) {
  std::string json;
  CommandLine cl("rig check",
                 "Can this host run the rig's LCM multicast, directly or in a private network namespace?\n"
                 "Prints what works and the commands that fix what does not.");
  cl->footer("Exit code: 0 if a run can start, 1 if not, 2 bad usage.");
  cl.add_json(json, "the findings");
  if (const auto done = cl.parse(args)) return *done;
  return launcher::check_host(json);
}

int run_spy_command(const std::vector<std::string>& args) {
  std::string url;
  std::string pid;
  CommandLine cl("rig spy",
                 "Starts lcm-spy with the rig's type jar on its classpath. lcm-spy is a window: it needs a\n"
                 "display (DISPLAY; over ssh: ssh -X; headless: xvfb-run).");
  cl->add_option("--pid", pid,
                 "join the network namespace of a running 'rig run' (it prints its pid at start) to watch it "
                 "live; the user who started the run may (a run started without root lives in a user namespace "
                 "that is joined first)")
      ->check(CLI::PositiveNumber);
  cl->add_option("--url", url, "the LCM URL to watch (a run on the host's network prints it at start)");
  if (const auto done = cl.parse(args)) return *done;
  const std::string jar = std::filesystem::path(self_dir()).parent_path().string() + "/share/java/nimble_lcmtypes.jar";
  if (!std::filesystem::exists(jar)) {
    std::cerr << "rig spy: type jar not found at " << jar << " (build the project first)\n";
    return kExitUsage;
  }
  if (!pid.empty()) {
    if (pid.find_first_not_of("0123456789") != std::string::npos || !std::filesystem::exists("/proc/" + pid)) {
      std::cerr << "rig spy: no process " << pid << " (is 'rig run' still running? it prints its pid at start)\n";
      return kExitUsage;
    }
    if (namespace_inode(pid, "net") == namespace_inode("self", "net")) {
      std::cerr << "rig spy: pid " << pid << " runs on this host's network, not in a namespace of its own: "
                   "watch it with the URL it printed at start (rig spy --url '...')\n";
      return kExitUsage;
    }
    // A run started without root made its network namespace inside a user namespace it owns:
    // join that first (its owner holds every capability there), then the network namespace.
    std::string problem;
    if (::geteuid() != 0 && namespace_inode(pid, "user") != namespace_inode("self", "user")) {
      problem = join_namespace(pid, "user", CLONE_NEWUSER);
    }
    if (problem.empty()) problem = join_namespace(pid, "net", CLONE_NEWNET);
    if (!problem.empty()) {
      std::cerr << "rig spy: cannot watch the run of pid " << pid << ": " << problem
                << " (only its own user, or root, may join it)\n";
      return kExitUsage;
    }
    if (url.empty()) url = "udpm://239.255.76.67:7667?ttl=0";
  }
  const char* display = std::getenv("DISPLAY");
  const char* wayland = std::getenv("WAYLAND_DISPLAY");
  if ((display == nullptr || *display == '\0') && (wayland == nullptr || *wayland == '\0')) {
    std::cerr << "rig spy: no display (DISPLAY is not set): lcm-spy is a window. Run it on a desktop, over "
                 "ssh -X, or headless with xvfb-run rig spy ...\n";
    return kExitUsage;
  }
  std::string classpath = jar + ":/usr/share/java/lcm.jar";
  if (std::filesystem::exists("/usr/share/java/jchart2d.jar")) classpath += ":/usr/share/java/jchart2d.jar";
  const char* old = std::getenv("CLASSPATH");
  if (old && *old) classpath += std::string(":") + old;
  ::setenv("CLASSPATH", classpath.c_str(), 1);
  // Debian's lcm-spy passes -Xincgc, which Java 17 refuses unless told to ignore it.
  ::setenv("JDK_JAVA_OPTIONS", "-XX:+IgnoreUnrecognizedVMOptions", 1);
  std::vector<std::string> argv_s = {"lcm-spy"};
  if (!url.empty()) argv_s.push_back("--lcm-url=" + url);
  std::vector<char*> argv;
  for (auto& s : argv_s) argv.push_back(s.data());
  argv.push_back(nullptr);
  ::execvp("lcm-spy", argv.data());
  std::cerr << "rig spy: cannot start lcm-spy (Debian package liblcm-java / liblcm-bin): " << std::strerror(errno)
            << "\n";
  return kExitUsage;
}

}  // namespace nimble::cli
