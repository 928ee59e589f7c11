#define CATCH_CONFIG_MAIN
#include <catch2/catch.hpp>

#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <thread>
#include <vector>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <string>

#include "support/scratch.h"

namespace nimble::test {
namespace {

/// The scratch directories this process named, and whether a test case failed.
struct ScratchDirs {
  std::set<std::filesystem::path> dirs;
  bool failed = false;
};

ScratchDirs& scratch_dirs() {
  static ScratchDirs s;
  return s;
}

/// The processes whose parent is this one, with their command lines.
std::vector<std::pair<pid_t, std::string>> children() {
  std::vector<std::pair<pid_t, std::string>> found;
  const pid_t self = ::getpid();
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator("/proc", ec)) {
    const std::string name = e.path().filename().string();
    if (name.empty() || name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream stat(e.path() / "stat");
    std::string line;
    std::getline(stat, line);
    // "PID (COMM) STATE PPID ...": COMM may hold spaces and parentheses; the last ')' ends it.
    const std::size_t close = line.rfind(')');
    if (close == std::string::npos) continue;
    char state = 0;
    long ppid = 0;
    if (std::sscanf(line.c_str() + close + 1, " %c %ld", &state, &ppid) != 2 || ppid != self) continue;
    std::ifstream cmd(e.path() / "cmdline", std::ios::binary);
    std::string c((std::istreambuf_iterator<char>(cmd)), std::istreambuf_iterator<char>());
    for (char& ch : c) {
      if (ch == '\0') ch = ' ';
    }
    found.emplace_back(static_cast<pid_t>(std::stol(name)), state == 'Z' ? "(exited) " + c : c);
  }
  return found;
}

/// Every process a test case started, by hand or through the launcher, is gone when the case
/// ends: this process is the subreaper of all it starts (an orphan, such as a node started in the
/// background by a shell or a launcher's child whose launcher died, is handed to it instead of
/// init), and whatever still runs then is named, killed and reaped. So nothing a case started
/// outlives it holding the suite's files or the machine, whatever its outcome.
void reap_leftovers(const std::string& test_case) {
  for (int round = 0; round < 50; ++round) {
    while (::waitpid(-1, nullptr, WNOHANG) > 0) {
    }
    const auto left = children();
    if (left.empty()) return;
    for (const auto& [pid, command] : left) {
      if (command.rfind("(exited) ", 0) == 0) continue;
      std::fprintf(stderr, "test case '%s' left process %d running (%s): killed\n", test_case.c_str(),
                   static_cast<int>(pid), command.c_str());
      ::kill(pid, SIGKILL);
    }
    for (const auto& [pid, command] : left) ::waitpid(pid, nullptr, 0);
    // A killed process's own children are handed to this process next: another round.
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

/// Removes the scratch directories when the run ends without a failure; otherwise names them.
/// Reaps what each test case left running (reap_leftovers).
struct ScratchListener : Catch::TestEventListenerBase {
  using TestEventListenerBase::TestEventListenerBase;
  void testRunStarting(const Catch::TestRunInfo&) override { ::prctl(PR_SET_CHILD_SUBREAPER, 1); }
  void testCaseEnded(const Catch::TestCaseStats& stats) override {
    if (stats.totals.assertions.failed > 0 || stats.totals.testCases.failed > 0) scratch_dirs().failed = true;
    reap_leftovers(stats.testInfo.name);
  }
  void testRunEnded(const Catch::TestRunStats& stats) override {
    ScratchDirs& s = scratch_dirs();
    const char* keep = std::getenv("RIG_KEEP_TEST_FILES");
    const bool kept = s.failed || stats.totals.assertions.failed > 0 || (keep != nullptr && std::string(keep) == "1");
    for (const auto& dir : s.dirs) {
      std::error_code ec;
      if (!std::filesystem::exists(dir, ec)) continue;
      if (kept) {
        std::fprintf(stderr, "test files kept in %s\n", dir.c_str());
      } else {
        std::filesystem::remove_all(dir, ec);
      }
    }
  }
};

std::filesystem::path named(const std::string& tag) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("rig_" + tag + "_" + std::to_string(::getpid()));
  scratch_dirs().dirs.insert(dir);
  return dir;
}

}  // namespace

std::string scratch_path(const std::string& tag) { return named(tag).string(); }

std::string scratch_dir(const std::string& tag) {
  const std::filesystem::path dir = named(tag);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

std::string scratch_file(const std::string& tag, const std::string& name) {
  const std::filesystem::path dir = named(tag);
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

}  // namespace nimble::test

using ScratchListener = nimble::test::ScratchListener;
CATCH_REGISTER_LISTENER(ScratchListener)
