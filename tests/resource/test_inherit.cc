// Nothing exposed to a child: the processes `rig run` starts hold only their standard streams and
// what they opened themselves, not the launcher's log, its LCM sockets or a live view's listening
// socket. Read from /proc while a real-time run with a live view flies.

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <catch2/catch.hpp>
#include "tests/support/scratch.h"

namespace fs = std::filesystem;

namespace {

/// fd number -> what it points to, of process `pid`.
std::map<int, std::string> descriptors(pid_t pid) {
  std::map<int, std::string> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator("/proc/" + std::to_string(pid) + "/fd", ec)) {
    std::error_code ec2;
    const fs::path target = fs::read_symlink(e.path(), ec2);
    if (!ec2) out[std::stoi(e.path().filename().string())] = target.string();
  }
  return out;
}

/// The children of `pid` (from /proc/PID/task/*/children).
std::vector<pid_t> children_of(pid_t pid) {
  std::vector<pid_t> out;
  std::error_code ec;
  for (const auto& t : fs::directory_iterator("/proc/" + std::to_string(pid) + "/task", ec)) {
    std::ifstream in(t.path() / "children");
    pid_t c;
    while (in >> c) out.push_back(c);
  }
  return out;
}

std::string comm_of(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/comm");
  std::string s;
  std::getline(in, s);
  return s;
}

}  // namespace

TEST_CASE("the processes of a run inherit nothing of the launcher's: log, LCM sockets, live view socket",
          "[resource]") {
  const fs::path dir = nimble::test::scratch_dir("inherit");
  const std::string log = (dir / "run.lcmlog").string();
  const pid_t rig = ::fork();
  REQUIRE(rig >= 0);
  if (rig == 0) {
    std::freopen((dir / "rig.out").c_str(), "w", stdout);
    std::freopen((dir / "rig.err").c_str(), "w", stderr);
    if (::chdir(RIG_SOURCE_DIR) != 0) ::_exit(126);
    ::execl(RIG_BIN, RIG_BIN, "run", "rig_configs/hover.yaml", "--clock", "realtime", "--set", "duration_s=3", "--log",
            log.c_str(), "--foxglove", "127.0.0.1:0", "--no-progress", static_cast<char*>(nullptr));
    ::_exit(127);
  }
  // Wait for the four processes of the run.
  std::map<std::string, pid_t> processes;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (processes.size() < 4 && std::chrono::steady_clock::now() < deadline) {
    for (const pid_t c : children_of(rig)) {
      const std::string name = comm_of(c);
      if (name.rfind("nimble_", 0) == 0) processes[name] = c;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  REQUIRE(processes.size() == 4);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // each process opened its own
  const std::map<int, std::string> launcher = descriptors(rig);
  std::set<std::string> launcher_objects;  // sockets and pipes by inode, files by path
  bool launcher_has_log = false, launcher_has_sockets = false;
  for (const auto& [fd, target] : launcher) {
    if (fd <= 2) continue;
    launcher_objects.insert(target);
    launcher_has_log |= target == log;
    launcher_has_sockets |= target.rfind("socket:", 0) == 0;
  }
  // The launcher holds what a child must not get.
  CHECK(launcher_has_log);
  CHECK(launcher_has_sockets);
  for (const auto& [name, pid] : processes) {
    const std::map<int, std::string> fds = descriptors(pid);
    std::ostringstream listing;
    for (const auto& [fd, target] : fds) listing << fd << " -> " << target << "\n";
    INFO(name << " (pid " << pid << "):\n" << listing.str());
    WARN(name << " (pid " << pid << "):\n" << listing.str());
    REQUIRE(fds.count(1) == 1);
    // Its output file (comm is cut at 15 characters: the name's start is enough).
    CHECK_THAT(fds.at(1),
               Catch::StartsWith(log + "." + name.substr(std::string("nimble_").size())) && Catch::EndsWith(".out"));
    for (const auto& [fd, target] : fds) {
      if (fd <= 2 || target.rfind("anon_inode:", 0) == 0) continue;  // epoll, timers: not told apart by name
      // Its own: its LCM sockets, epoll and timer descriptors; none the launcher holds.
      CHECK(launcher_objects.count(target) == 0);
      CHECK(target != log);
    }
  }
  int status = 0;
  ::waitpid(rig, &status, 0);
  CHECK(WIFEXITED(status));
  fs::remove_all(dir);
}
