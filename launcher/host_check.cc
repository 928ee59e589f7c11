// `rig check` (check_host) and writable_problem (launcher/launcher.h): what the launcher asks of
// the host before a run.

#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>

#include "core/json_line.h"
#include "core/output_file.h"
#include "launcher/launcher.h"
#include "launcher/netns.h"

namespace nimble::launcher {

std::string writable_problem(const std::string& file) {
  const bool existed = std::filesystem::exists(file);
  errno = 0;
  {
    std::ofstream out(file, std::ios::app);
    if (!out) return std::string("cannot be written (") + (errno ? std::strerror(errno) : "open failed") + ")";
  }
  if (!existed) std::filesystem::remove(file);
  return "";
}

int check_host(const std::string& json_target) {
  // With --json -, stdout carries the JSON and the text goes to stderr.
  std::ostream& out = json_target == "-" ? std::cerr : std::cout;
  const std::string url = "udpm://239.255.76.67:7667?ttl=0";
  out << "LCM multicast on this host's loopback (" << url << "): ";
  const bool host_ok = lcm_url_works(url);
  bool ns_ok = false;
  if (host_ok) {
    out << "works\n";
  } else {
    out << "does NOT work (no multicast route or loopback multicast off)\n";
    // Probe a private namespace in a child, so this process stays where it is.
    const pid_t pid = ::fork();
    if (pid == 0) {
      const NamespaceResult r = enter_private_network_namespace();
      ::_exit(r.ok && lcm_url_works(url) ? 0 : 1);
    }
    int status = 0;
    ::waitpid(pid, &status, 0);
    ns_ok = WIFEXITED(status) && WEXITSTATUS(status) == 0;
    out << "private network namespace with multicast loopback: " << (ns_ok ? "works" : "does NOT work") << "\n";
    if (ns_ok) {
      out << "'rig run' will run each rig in its own private namespace. To run LCM tools on the host\n"
             "itself (lcm-spy on a host-level URL), fix the host's loopback with:\n"
          << multicast_fix_commands() << "\n";
    } else {
      out << "Neither works. Fix the host's loopback with:\n" << multicast_fix_commands() << "\n";
    }
  }
  const bool ok = host_ok || ns_ok;
  if (!json_target.empty()) {
    OrderedJson j;
    j["url"] = url;
    j["host_multicast"] = host_ok;
    j["private_namespace"] = host_ok ? "not needed" : (ns_ok ? "works" : "does not work");
    j["runs_can_start"] = ok;
    if (!host_ok) j["fix"] = multicast_fix_commands();
    const std::string doc = json_line(j);
    if (json_target == "-") {
      std::cout << doc << "\n";
    } else {
      try {
        write_file(json_target, doc + "\n");
      } catch (const OutputError& e) {
        std::cerr << "rig check: " << e.what() << "\n";
        return kRunBadInput;
      }
    }
  }
  return ok ? 0 : 1;
}

}  // namespace nimble::launcher
