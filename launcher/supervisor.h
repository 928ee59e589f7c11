#pragma once
/// ProcessSupervisor: starts child processes, notices when they die, and stops them in order.
/// Used by the launcher for the rig's processes and by the benches and system tests that start
/// processes of their own (bench/bench_can_bridge.cc).
///
/// A child dies with its supervisor (PR_SET_PDEATHSIG), ignores SIGINT (the supervisor handles
/// Ctrl-C and stops everything in order), may be pinned to CPUs, and writes its output to a
/// file of its own. stop() asks politely (a callback, e.g. RUN_CONTROL stop), then SIGTERM,
/// then SIGKILL.

#include <sys/types.h>

#include <functional>
#include <string>
#include <vector>

namespace nimble::launcher {

/// Pins the calling process to those of `cpus` that exist; returns a note when some (or all)
/// do not, or the error; empty when pinned as asked (or `cpus` is empty).
std::string pin_to(const std::vector<int>& cpus);

/// The last `lines` lines of a text file, each indented as "    | line".
std::string tail_of(const std::string& file, int lines);

struct ChildProcess {
  std::string name;
  pid_t pid = -1;
  std::string output_file;  ///< stdout and stderr (empty: the supervisor's own)
  bool exited = false;
  int exit_code = -1;
  int signal = 0;  ///< the signal that killed it, 0 if none

  /// "exited with code 3", "was killed by signal 9 (Killed)" or "running".
  std::string describe() const;
};

class ProcessSupervisor {
 public:
  /// Called while waiting, about every 10 ms (e.g. to handle messages); may be empty.
  using Idle = std::function<void()>;

  ProcessSupervisor() = default;
  ProcessSupervisor(const ProcessSupervisor&) = delete;
  ProcessSupervisor& operator=(const ProcessSupervisor&) = delete;
  /// Kills (SIGKILL) and reaps whatever still runs.
  ~ProcessSupervisor();

  /// Starts `exe` with `args` as child `name`. If the executable cannot be started the child
  /// exits with code 127 and says why in its output. With `network_namespace_fd` (a descriptor
  /// of a network namespace, e.g. HostLink's) the child enters that namespace before exec
  /// (setns); if it cannot, it exits with code 127 and says why. `environment`: "NAME=value"
  /// entries that replace or add to the supervisor's own environment in the child's.
  /// @throws std::runtime_error if fork fails.
  const ChildProcess& start(const std::string& name, const std::string& exe, const std::vector<std::string>& args,
                            const std::string& output_file = "", const std::vector<int>& cpus = {},
                            int network_namespace_fd = -1, const std::vector<std::string>& environment = {});

  /// Reaps the children that have exited; returns the first one newly found dead, or nullptr.
  const ChildProcess* reap();
  bool all_exited() const;
  /// Waits up to `seconds` for every child to exit; true if they all did.
  bool wait_all(double seconds, const Idle& idle = {});
  /// Stops every child: `ask` (may be empty), up to `grace_s` for them to exit, then SIGTERM
  /// and 1 s, then SIGKILL and 1 s.
  void stop(double grace_s, const std::function<void()>& ask = {}, const Idle& idle = {});
  /// Sends `sig` to every child still running.
  void signal_all(int sig);

  const std::vector<ChildProcess>& children() const { return children_; }

 private:
  std::vector<ChildProcess> children_;
};

}  // namespace nimble::launcher
