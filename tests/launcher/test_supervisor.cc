// Functional tests of ProcessSupervisor: real child processes started, reaped, named when they
// die, and stopped in order (ask, SIGTERM, SIGKILL).

#include <fcntl.h>
#include <signal.h>
#include <sys/socket.h>
#include <netinet/in.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <thread>
#include <fstream>
#include <sstream>
#include <string>

#include <catch2/catch.hpp>

#include "launcher/supervisor.h"
#include "tests/support/scratch.h"

using nimble::launcher::ChildProcess;
using nimble::launcher::ProcessSupervisor;

namespace {

std::string scratch(const std::string& name) { return nimble::test::scratch_file("supervisor", name); }

std::string slurp(const std::string& file) {
  std::ifstream in(file);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

TEST_CASE("supervisor: a child's exit code, its output file and its death are seen", "[launcher]") {
  ProcessSupervisor s;
  const std::string out = scratch("exit3.out");
  s.start("exits", "/bin/sh", {"-c", "echo said this; exit 3"}, out);
  REQUIRE(s.wait_all(10.0));
  const ChildProcess& c = s.children().front();
  CHECK(c.exited);
  CHECK(c.exit_code == 3);
  CHECK(c.describe() == "exited with code 3");
  CHECK(slurp(out) == "said this\n");
  CHECK(nimble::launcher::tail_of(out, 5) == "    | said this\n");
  CHECK(s.reap() == nullptr);  // reported once
}

TEST_CASE("supervisor: a missing executable is a child that exits 127 and says why", "[launcher]") {
  ProcessSupervisor s;
  const std::string out = scratch("missing.out");
  s.start("ghost", "/nonexistent/nimble_ghost", {}, out);
  REQUIRE(s.wait_all(10.0));
  CHECK(s.children().front().exit_code == 127);
  CHECK(slurp(out).find("cannot execute /nonexistent/nimble_ghost") != std::string::npos);
}

TEST_CASE("supervisor: stop asks first, then SIGTERM, then SIGKILL", "[launcher]") {
  ProcessSupervisor s;
  // One that leaves when asked (a flag file appears), one that needs SIGTERM,
  // one that ignores SIGTERM.
  const std::string flag = scratch("leave.flag");
  std::filesystem::remove(flag);
  s.start("polite", "/bin/sh", {"-c", "while [ ! -e " + flag + " ]; do sleep 0.01; done"});
  s.start("plain", "/bin/sleep", {"30"});
  s.start("stubborn", "/bin/sh", {"-c", "trap '' TERM; while true; do sleep 0.01; done"});
  bool asked = false;
  const auto t0 = std::chrono::steady_clock::now();
  s.stop(0.5, [&] {
    asked = true;
    std::ofstream(flag) << "go";
  });
  CHECK(asked);
  CHECK(std::chrono::steady_clock::now() - t0 < std::chrono::seconds(5));
  REQUIRE(s.all_exited());
  CHECK(s.children()[0].exit_code == 0);
  CHECK(s.children()[0].signal == 0);
  CHECK(s.children()[1].signal == SIGTERM);
  CHECK(s.children()[2].signal == SIGKILL);
  CHECK(s.children()[2].describe().find("was killed by signal 9") == 0);
}

TEST_CASE("supervisor: pinning to CPUs that do not exist is said, not fatal", "[launcher]") {
  CHECK(nimble::launcher::pin_to({}).empty());
  CHECK(nimble::launcher::pin_to({100000}).find("none of the CPUs") != std::string::npos);
}

TEST_CASE("supervisor: a child given a network namespace runs in it, a bad one is named", "[launcher]") {
  // A namespace held by a child of its own (unshare -n needs root, as rig run's second host does).
  ProcessSupervisor s;
  const ChildProcess& holder = s.start("holder", "/usr/bin/unshare", {"-n", "sleep", "30"}, scratch("holder.out"));
  const std::string self_ns = std::filesystem::read_symlink("/proc/self/ns/net").string();
  const std::string holder_path = "/proc/" + std::to_string(holder.pid) + "/ns/net";
  std::string holder_ns;
  for (int i = 0; i < 500 && (holder_ns.empty() || holder_ns == self_ns); ++i) {
    std::error_code ec;
    holder_ns = std::filesystem::read_symlink(holder_path, ec).string();
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  INFO(slurp(scratch("holder.out")));
  REQUIRE(holder_ns != self_ns);  // unshare -n works here (else this machine cannot run two hosts)
  const int fd = ::open(holder_path.c_str(), O_RDONLY | O_CLOEXEC);
  REQUIRE(fd >= 0);
  const std::string out = scratch("in_ns.out");
  s.start("in_ns", "/usr/bin/readlink", {"/proc/self/ns/net"}, out, {}, fd);
  const int not_a_namespace = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
  const std::string bad = scratch("bad_ns.out");
  s.start("bad_ns", "/usr/bin/readlink", {"/proc/self/ns/net"}, bad, {}, not_a_namespace);
  ::close(fd);
  ::close(not_a_namespace);
  for (int i = 0; i < 1000 && !(s.children()[1].exited && s.children()[2].exited); ++i) {
    s.reap();
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  CHECK(s.children()[1].exit_code == 0);
  CHECK(slurp(out) == holder_ns + "\n");
  CHECK(s.children()[2].exit_code == 127);
  CHECK(slurp(bad).find("cannot enter the network namespace of its host (setns)") != std::string::npos);
  s.stop(0.0);
}

TEST_CASE("supervisor: a child inherits only its standard streams, whatever the launcher holds open", "[launcher]") {
  // Descriptors as a library would leave them: no close-on-exec.
  const std::string held = scratch("held.lcmlog");
  const int file_fd = ::open(held.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  const int socket_fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  int pipe_fd[2] = {-1, -1};
  REQUIRE(file_fd >= 0);
  REQUIRE(socket_fd >= 0);
  REQUIRE(::pipe(pipe_fd) == 0);
  ProcessSupervisor s;
  const std::string out = scratch("fds.out");
  // ls lists its own descriptors: the standard streams and the directory it reads.
  s.start("lister", "/bin/ls", {"-l", "/proc/self/fd/"}, out);
  REQUIRE(s.wait_all(10.0));
  CHECK(s.children().front().exit_code == 0);
  const std::string listing = slurp(out);
  INFO(listing);
  std::istringstream lines(listing);
  std::string line;
  int standard = 0, own = 0, inherited = 0;
  while (std::getline(lines, line)) {
    const auto arrow = line.find(" -> ");
    if (arrow == std::string::npos) continue;
    const std::string target = line.substr(arrow + 4);
    std::istringstream words(line.substr(0, arrow));
    std::string word, fd;
    while (words >> word) fd = word;
    if (fd == "0" || fd == "1" || fd == "2")
      ++standard;
    else if (target.rfind("/proc/", 0) == 0 && target.size() > 3 && target.compare(target.size() - 3, 3, "/fd") == 0)
      ++own;
    else
      ++inherited;
  }
  CHECK(standard == 3);
  CHECK(own <= 1);
  CHECK(inherited == 0);
  CHECK(listing.find("held.lcmlog") == std::string::npos);
  CHECK(listing.find("socket:") == std::string::npos);
  CHECK(listing.find("pipe:") == std::string::npos);
  ::close(file_fd);
  ::close(socket_fd);
  ::close(pipe_fd[0]);
  ::close(pipe_fd[1]);
}
