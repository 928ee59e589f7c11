/// `rig spy`: lcm-spy with the rig's types, on the host's network or in a running rig's namespace.

#include <fcntl.h>
#include <sched.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "cmdline/args.h"
#include "cli/commands.h"

namespace nimble::cli {
namespace {

/// The inode of a namespace link (/proc/<pid>/ns/<kind>), 0 if it cannot be read.
ino_t namespace_inode(const std::string& pid, const std::string& kind) {
  struct stat st {};
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

int run_spy_command(const std::vector<std::string>& args) {
  std::string url;
  std::string pid;
  cmdline::CommandLine cl("rig spy",
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
    return cmdline::kExitUsage;
  }
  if (!pid.empty()) {
    if (pid.find_first_not_of("0123456789") != std::string::npos || !std::filesystem::exists("/proc/" + pid)) {
      std::cerr << "rig spy: no process " << pid << " (is 'rig run' still running? it prints its pid at start)\n";
      return cmdline::kExitUsage;
    }
    if (namespace_inode(pid, "net") == namespace_inode("self", "net")) {
      std::cerr << "rig spy: pid " << pid
                << " runs on this host's network, not in a namespace of its own: "
                   "watch it with the URL it printed at start (rig spy --url '...')\n";
      return cmdline::kExitUsage;
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
      return cmdline::kExitUsage;
    }
    if (url.empty()) url = "udpm://239.255.76.67:7667?ttl=0";
  }
  const char* display = std::getenv("DISPLAY");
  const char* wayland = std::getenv("WAYLAND_DISPLAY");
  if ((display == nullptr || *display == '\0') && (wayland == nullptr || *wayland == '\0')) {
    std::cerr << "rig spy: no display (DISPLAY is not set): lcm-spy is a window. Run it on a desktop, over "
                 "ssh -X, or headless with xvfb-run rig spy ...\n";
    return cmdline::kExitUsage;
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
  return cmdline::kExitUsage;
}

}  // namespace nimble::cli
