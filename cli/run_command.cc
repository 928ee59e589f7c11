/// `rig run`, `rig check`, `rig spy`: launching and watching the live rig.

#include <fcntl.h>
#include <sched.h>
#include <unistd.h>

#include <cctype>
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
    "  Exit code: 0 controlled, 1 not controlled, 2 bad input, 3 a process failed or the run\n"
    "  stalled, 4 real-time degraded (only with --strict-timing), 130 interrupted.\n";

constexpr const char* kSpyUsage =
    "usage: rig spy [--pid PID] [--url URL]\n"
    "  Starts lcm-spy with the rig's type jar on its classpath. --pid joins the network\n"
    "  namespace of a running 'rig run' (its pid is printed at start) to watch it live.\n";

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
  if (!o.clock || *o.clock != launcher::kClockInprocess) {
    std::cerr << "rig run: pid " << ::getpid() << " (watch live: rig spy --pid " << ::getpid() << ")\n";
  }
  return launcher::run_scenario(o);
}

int run_check_command(const std::vector<std::string>& args) {
  if (!args.empty()) {
    std::cerr << "usage: rig check\n";
    return kExitUsage;
  }
  return launcher::check_host();
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
    const std::string ns = "/proc/" + pid + "/ns/net";
    const int fd = ::open(ns.c_str(), O_RDONLY);
    if (fd < 0 || ::setns(fd, CLONE_NEWNET) != 0) {
      std::cerr << "rig spy: cannot join the network namespace of pid " << pid << " (" << ns
                << "): is 'rig run' still running, and are you root?\n";
      return kExitUsage;
    }
    ::close(fd);
    if (url.empty()) url = "udpm://239.255.76.67:7667?ttl=0";
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
