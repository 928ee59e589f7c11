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

#include "cli/commands.h"
#include "launcher/launcher.h"

namespace nimble::cli {
namespace {

constexpr const char* kRunUsage =
    "usage: rig run <scenario.yaml> [--clock realtime|lockstep|inprocess] [--log FILE] [--json FILE]\n"
    "               [--set key.path=value]... [--seed N] [--no-progress] [--strict-timing]\n"
    "  Starts every process of the scenario, records all channels to an LCM log\n"
    "  (default rig_logs/<name>-<time>.lcmlog, replay with lcm-logplayer), and prints a\n"
    "  summary. realtime and lockstep run each process as its own OS process over LCM;\n"
    "  inprocess flies the same processes' code in this process, lockstep semantics, no\n"
    "  transport (same log, same truth as lockstep). Real time is judged from what each\n"
    "  process reports: more than summary.max_late_fraction of a channel late or\n"
    "  summary.max_overrun_fraction of a process's cycles overrun gives 'real-time degraded'.\n"
    "  --clock C          realtime (default of most scenarios), lockstep or inprocess\n"
    "  --log FILE         the LCM log (default rig_logs/<name>-<time>.lcmlog); the resolved\n"
    "                     scenario and each process's output are written next to it\n"
    "  --json FILE        the summary as JSON; '-' writes it to stdout (the text summary then\n"
    "                     goes to stderr)\n"
    "  --set key.path=v   override one scenario value, parsed as YAML: --set duration_s=3,\n"
    "                     --set processes=[plant,controller], --set 'faults=[{target: IMU,\n"
    "                     kind: off, start_s: 1}]' (quote values with spaces for the shell)\n"
    "  --seed N           the run's seed (a whole number >= 0)\n"
    "  --no-progress      no progress line on stderr (for logs and scripts)\n"
    "  --strict-timing    a real-time degraded run exits 4\n"
    "  Network: run.network_namespace auto (default) flies realtime and lockstep runs in a\n"
    "  private network namespace whose loopback carries multicast; 'rig spy --pid PID' joins\n"
    "  it. always: fail if one cannot be made; never: the host's network (rig check).\n"
    "  Exit code: 0 controlled, 1 not controlled, 2 bad input, 3 a process failed, hung\n"
    "  (HEARTBEAT_LOST) or the run stalled, 4 real-time degraded (only with --strict-timing),\n"
    "  5 completed in the controller's failsafe, 130 interrupted.\n";

constexpr const char* kSpyUsage =
    "usage: rig spy [--pid PID] [--url URL]\n"
    "  Starts lcm-spy with the rig's type jar on its classpath. --pid joins the network\n"
    "  namespace of a running 'rig run' (its pid is printed at start) to watch it live; the\n"
    "  user who started the run may (a run started without root lives in a user namespace\n"
    "  that is joined first). A run on the host's network prints its --url instead.\n"
    "  lcm-spy is a window: it needs a display (DISPLAY; over ssh: ssh -X; headless: xvfb-run).\n";

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

}  // namespace

int run_run_command(const std::vector<std::string>& args) {
  launcher::RunOptions o;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= args.size()) throw std::invalid_argument(a + " needs a value");
      return args[++i];
    };
    try {
      if (a == "--help" || a == "-h") {
        std::cout << kRunUsage;
        return 0;
      } else if (a == "--clock") {
        o.clock = value();
      } else if (a == "--log") {
        o.log_file = value();
      } else if (a == "--json") {
        o.json_file = value();
      } else if (a == "--set") {
        o.overrides.push_back(parse_override(value()));
      } else if (a == "--seed") {
        const std::string v = value();
        std::size_t used = 0;
        // std::stoull takes "-1" as 2^64 - 1: a seed must be written as a whole number >= 0.
        if (v.empty() || !std::isdigit(static_cast<unsigned char>(v[0]))) {
          throw std::invalid_argument("--seed needs a whole number >= 0, got '" + v + "'");
        }
        const unsigned long long seed = std::stoull(v, &used);
        if (used != v.size()) throw std::invalid_argument("--seed needs a whole number >= 0, got '" + v + "'");
        o.seed = seed;
      } else if (a == "--no-progress") {
        o.progress = false;
      } else if (a == "--strict-timing") {
        o.strict_timing = true;
      } else if (!a.empty() && a[0] == '-') {
        throw std::invalid_argument("unknown option '" + a + "'");
      } else if (o.scenario_file.empty()) {
        o.scenario_file = a;
      } else {
        throw std::invalid_argument("unexpected argument '" + a + "'");
      }
    } catch (const std::invalid_argument& e) {
      std::cerr << "rig run: " << e.what() << "\n" << kRunUsage;
      return kExitUsage;
    } catch (const std::out_of_range&) {
      std::cerr << "rig run: " << a << " value out of range\n";
      return kExitUsage;
    }
  }
  if (o.scenario_file.empty()) {
    std::cerr << "rig run: missing <scenario.yaml>\n" << kRunUsage;
    return kExitUsage;
  }
  return launcher::run_scenario(o);
}

int run_check_command(const std::vector<std::string>& args) {
  constexpr const char* kCheckUsage =
      "usage: rig check [--json FILE|-]\n"
      "  Can this host run the rig's LCM multicast, directly or in a private network namespace?\n"
      "  Prints what works and the commands that fix what does not. Exit code 0 if a run can\n"
      "  start, 1 if not. --json writes the findings as JSON ('-': stdout, the text to stderr).\n";
  std::string json;
  for (std::size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--help" || args[i] == "-h") {
      std::cout << kCheckUsage;
      return 0;
    } else if (args[i] == "--json" && i + 1 < args.size()) {
      json = args[++i];
    } else {
      std::cerr << "rig check: unexpected argument '" << args[i] << "'\n" << kCheckUsage;
      return kExitUsage;
    }
  }
  return launcher::check_host(json);
}

int run_spy_command(const std::vector<std::string>& args) {
  std::string url;
  std::string pid;
  for (std::size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--help" || args[i] == "-h") {
      std::cout << kSpyUsage;
      return 0;
    } else if (args[i] == "--url" && i + 1 < args.size()) {
      url = args[++i];
    } else if (args[i] == "--pid" && i + 1 < args.size()) {
      pid = args[++i];
    } else {
      std::cerr << "rig spy: unexpected argument '" << args[i] << "'\n" << kSpyUsage;
      return kExitUsage;
    }
  }
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
