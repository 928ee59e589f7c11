#include "launcher/supervisor.h"

#include <fcntl.h>
#include <sched.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <thread>

#include "core/descriptors.h"
#include "transport/clock.h"

namespace nimble::launcher {

std::string pin_to(const std::vector<int>& cpus) {
  if (cpus.empty()) return "";
  const int online = static_cast<int>(::sysconf(_SC_NPROCESSORS_ONLN));
  cpu_set_t set;
  CPU_ZERO(&set);
  int used = 0;
  for (const int c : cpus) {
    if (c >= 0 && c < online && c < CPU_SETSIZE) {
      CPU_SET(c, &set);
      ++used;
    }
  }
  if (used == 0) return "none of the CPUs asked for exist on this machine (" + std::to_string(online) + " online)";
  if (::sched_setaffinity(0, sizeof set, &set) != 0) return std::string("sched_setaffinity: ") + std::strerror(errno);
  return used < static_cast<int>(cpus.size()) ? "some CPUs asked for do not exist; pinned to the others" : "";
}

std::string tail_of(const std::string& file, int lines) {
  std::ifstream in(file);
  std::vector<std::string> all;
  for (std::string line; std::getline(in, line);) all.push_back(line);
  std::string out;
  for (std::size_t i = all.size() > static_cast<std::size_t>(lines) ? all.size() - lines : 0; i < all.size(); ++i) {
    out += "    | " + all[i] + "\n";
  }
  return out;
}

std::string ChildProcess::describe() const {
  if (!exited) return "running";
  if (signal != 0) return "was killed by signal " + std::to_string(signal) + " (" + strsignal(signal) + ")";
  return "exited with code " + std::to_string(exit_code);
}

ProcessSupervisor::~ProcessSupervisor() {
  signal_all(SIGKILL);
  for (auto& c : children_) {
    if (!c.exited && c.pid > 0) ::waitpid(c.pid, nullptr, 0);
  }
}

const ChildProcess& ProcessSupervisor::start(const std::string& name, const std::string& exe,
                                             const std::vector<std::string>& args, const std::string& output_file,
                                             const std::vector<int>& cpus, int network_namespace_fd,
                                             const std::vector<std::string>& environment) {
  // Everything the child needs is prepared before fork: it only calls async-signal-safe
  // functions until exec.
  std::vector<char*> argv;
  argv.push_back(const_cast<char*>(exe.c_str()));
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  // The child's environment: this one's, with `environment`'s entries in place of those of the same name.
  std::vector<std::string> env_entries;
  for (char** e = environ; *e != nullptr; ++e) {
    const std::string entry = *e;
    const std::string name_eq = entry.substr(0, entry.find('=') + 1);
    const bool replaced = std::any_of(environment.begin(), environment.end(),
                                      [&name_eq](const std::string& x) { return x.rfind(name_eq, 0) == 0; });
    if (!replaced) env_entries.push_back(entry);
  }
  env_entries.insert(env_entries.end(), environment.begin(), environment.end());
  std::vector<char*> envp;
  for (auto& e : env_entries) envp.push_back(e.data());
  envp.push_back(nullptr);
  std::fflush(stdout);
  std::fflush(stderr);
  const pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error("cannot start " + name + ": fork failed: " + std::strerror(errno));
  if (pid == 0) {
    pin_to(cpus);
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);
    ::signal(SIGINT, SIG_IGN);
    if (!output_file.empty()) {
      const int fd = ::open(output_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
      if (fd >= 0) {
        ::dup2(fd, STDOUT_FILENO);
        ::dup2(fd, STDERR_FILENO);
        ::close(fd);
      }
    }
    if (network_namespace_fd >= 0 && ::setns(network_namespace_fd, CLONE_NEWNET) != 0) {
      std::fprintf(stderr, "cannot enter the network namespace of its host (setns): %s\n", std::strerror(errno));
      ::_exit(127);
    }
    // The process inherits its standard streams only: not the run's log, the launcher's LCM
    // sockets, a live view's listening socket or the pipes of other children.
    close_descriptors_from(STDERR_FILENO + 1);
    ::execve(exe.c_str(), argv.data(), envp.data());
    std::fprintf(stderr, "cannot execute %s: %s\n", exe.c_str(), std::strerror(errno));
    ::_exit(127);
  }
  ChildProcess c;
  c.name = name;
  c.pid = pid;
  c.output_file = output_file;
  children_.push_back(c);
  return children_.back();
}

const ChildProcess* ProcessSupervisor::reap() {
  const ChildProcess* first = nullptr;
  for (auto& c : children_) {
    if (c.exited || c.pid <= 0) continue;
    int status = 0;
    if (::waitpid(c.pid, &status, WNOHANG) == c.pid) {
      c.exited = true;
      if (WIFEXITED(status)) c.exit_code = WEXITSTATUS(status);
      if (WIFSIGNALED(status)) c.signal = WTERMSIG(status);
      if (first == nullptr) first = &c;
    }
  }
  return first;
}

bool ProcessSupervisor::all_exited() const {
  for (const auto& c : children_) {
    if (!c.exited) return false;
  }
  return true;
}

bool ProcessSupervisor::wait_all(double seconds, const Idle& idle) {
  const int64_t until = transport::monotonic_ns() + static_cast<int64_t>(seconds * 1e9);
  for (;;) {
    reap();
    if (all_exited()) return true;
    if (transport::monotonic_ns() >= until) return false;
    if (idle)
      idle();
    else
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

void ProcessSupervisor::signal_all(int sig) {
  reap();
  for (const auto& c : children_) {
    if (!c.exited && c.pid > 0) ::kill(c.pid, sig);
  }
}

void ProcessSupervisor::stop(double grace_s, const std::function<void()>& ask, const Idle& idle) {
  if (ask) ask();
  if (wait_all(grace_s, idle)) return;
  signal_all(SIGTERM);
  if (wait_all(1.0, idle)) return;
  signal_all(SIGKILL);
  wait_all(1.0, idle);
}

}  // namespace nimble::launcher
