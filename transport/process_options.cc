// The command line and the real-time scheduling policy of a rig process (transport/process_options.h).

#include "transport/process_options.h"

#include <sched.h>
#include <sys/mman.h>

#include <cerrno>
#include <cstring>
#include <utility>

#include "cmdline/args.h"

namespace nimble::transport {

std::string apply_realtime_priority(int priority) {
  if (priority <= 0) return "";
  sched_param sp{};
  sp.sched_priority = priority;
  if (::sched_setscheduler(0, SCHED_FIFO, &sp) != 0) {
    return std::string("cannot run under SCHED_FIFO priority ") + std::to_string(priority) + ": " +
           std::strerror(errno) + " (needs root or CAP_SYS_NICE); running with the default scheduler";
  }
  if (::mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
    return std::string("SCHED_FIFO set, but mlockall failed: ") + std::strerror(errno);
  }
  return "";
}

namespace {

std::string& realtime_problem_storage() {
  static std::string why;
  return why;
}

}  // namespace

void set_realtime_problem(const std::string& why) { realtime_problem_storage() = why; }
const std::string& realtime_problem() { return realtime_problem_storage(); }

std::optional<int> parse_node_options(int argc, char** argv, const std::string& program,
                                      const std::string& default_name, NodeOptions& options) {
  NodeOptions o;
  o.name = default_name;
  cmdline::CommandLine cl(program,
                          "The rig's " + default_name +
                              " process. 'rig run' starts it with the resolved scenario it writes next to\n"
                              "the log and the run's LCM URL; it announces HEARTBEAT READY, waits for RUN_CONTROL\n"
                              "start and runs until stopped.");
  cl->footer(
      "Exit code: 0 stopped cleanly, 2 bad command line or configuration, 3 a lockstep participant\n"
      "did not acknowledge in time, 4 another fatal fault.");
  cl->add_option("--scenario", o.scenario_file, "the resolved scenario YAML (rig run writes it next to the log)")
      ->type_name("FILE")
      ->required();
  cl->add_option("--name", o.name, "the process name on HEARTBEAT, FAULT and STEP_ACK")
      ->type_name("NAME")
      ->capture_default_str();
  cl->add_option("--lcm-url", o.lcm_url,
                 "the run's LCM URL (default: LCM's, that is LCM_DEFAULT_URL or udpm://239.255.76.67:7667)")
      ->type_name("URL");
  if (const auto done = cl.parse(argc, argv)) return *done == 0 ? kExitOk : kExitConfig;
  options = std::move(o);
  return std::nullopt;
}

}  // namespace nimble::transport
