#include "launcher/netns.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <net/if.h>
#include <net/route.h>
#include <sched.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <linux/can.h>
#include <linux/can/raw.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "core/descriptors.h"

namespace nimble::launcher {
namespace {

bool write_file(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  return static_cast<bool>(out);
}

std::string errno_text() { return std::strerror(errno); }

}  // namespace

NamespaceResult configure_loopback_multicast() {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  if (fd < 0) return {false, "socket(): " + errno_text()};
  ifreq ifr{};
  std::strncpy(ifr.ifr_name, "lo", IFNAMSIZ - 1);
  if (::ioctl(fd, SIOCGIFFLAGS, &ifr) < 0) {
    const std::string e = errno_text();
    ::close(fd);
    return {false, "SIOCGIFFLAGS lo: " + e};
  }
  ifr.ifr_flags = static_cast<short>(ifr.ifr_flags | IFF_UP | IFF_MULTICAST);
  if (::ioctl(fd, SIOCSIFFLAGS, &ifr) < 0) {
    const std::string e = errno_text();
    ::close(fd);
    return {false, "bringing up lo with multicast: " + e};
  }
  rtentry route{};
  auto* dst = reinterpret_cast<sockaddr_in*>(&route.rt_dst);
  auto* mask = reinterpret_cast<sockaddr_in*>(&route.rt_genmask);
  dst->sin_family = AF_INET;
  mask->sin_family = AF_INET;
  inet_pton(AF_INET, "224.0.0.0", &dst->sin_addr);
  inet_pton(AF_INET, "240.0.0.0", &mask->sin_addr);
  char dev[] = "lo";
  route.rt_dev = dev;
  route.rt_flags = RTF_UP;
  if (::ioctl(fd, SIOCADDRT, &route) < 0 && errno != EEXIST) {
    const std::string e = errno_text();
    ::close(fd);
    return {false, "adding route 224.0.0.0/4 dev lo: " + e};
  }
  ::close(fd);
  return {true, "loopback up with multicast, route 224.0.0.0/4 dev lo"};
}

NamespaceResult enter_private_network_namespace() {
  std::string how;
  if (::unshare(CLONE_NEWNET) == 0) {
    how = "private network namespace";
  } else {
    const int first_errno = errno;
    const uid_t uid = ::getuid();
    const gid_t gid = ::getgid();
    if (::unshare(CLONE_NEWUSER | CLONE_NEWNET) != 0) {
      return {false, std::string("unshare(CLONE_NEWNET): ") + std::strerror(first_errno) +
                         "; unshare(CLONE_NEWUSER|CLONE_NEWNET): " + errno_text()};
    }
    write_file("/proc/self/setgroups", "deny");
    if (!write_file("/proc/self/uid_map", "0 " + std::to_string(uid) + " 1\n") ||
        !write_file("/proc/self/gid_map", "0 " + std::to_string(gid) + " 1\n")) {
      return {false, "user namespace: cannot write uid_map/gid_map"};
    }
    how = "private user and network namespace";
  }
  NamespaceResult lo = configure_loopback_multicast();
  if (!lo.ok) return lo;
  return {true, how + "; " + lo.detail};
}

bool lcm_url_works(const std::string& url) {
  lcm::LCM probe(url);
  return probe.good();
}

std::string multicast_fix_commands() {
  return "  sudo ip link set lo multicast on\n"
         "  sudo ip route add 224.0.0.0/4 dev lo\n"
         "(or let 'rig run' create a private network namespace: it needs root or unprivileged user namespaces)";
}

namespace {

/// Runs `argv` (no shell), returning its exit status and what it printed; in the network
/// namespace of `netns_fd` if it is not -1.
int run_quiet(const std::vector<std::string>& argv, std::string* output, int netns_fd = -1) {
  int pipe_fd[2];
  if (::pipe(pipe_fd) != 0) return -1;
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (netns_fd >= 0 && ::setns(netns_fd, CLONE_NEWNET) != 0) {
      std::fprintf(stderr, "setns(CLONE_NEWNET): %s\n", std::strerror(errno));
      ::_exit(126);
    }
    ::dup2(pipe_fd[1], 1);
    ::dup2(pipe_fd[1], 2);
    ::close(pipe_fd[0]);
    ::close(pipe_fd[1]);
    close_descriptors_from(STDERR_FILENO + 1);
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    ::execvp(args[0], args.data());
    std::fprintf(stderr, "cannot run %s: %s\n", args[0], std::strerror(errno));
    ::_exit(127);
  }
  ::close(pipe_fd[1]);
  char buf[512];
  ssize_t n;
  while ((n = ::read(pipe_fd[0], buf, sizeof buf)) > 0) output->append(buf, static_cast<std::size_t>(n));
  ::close(pipe_fd[0]);
  int status = 0;
  ::waitpid(pid, &status, 0);
  while (!output->empty() && output->back() == '\n') output->pop_back();
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

/// Sets IFF_UP on `name`; "" on success.
std::string bring_up(const std::string& name) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  if (fd < 0) return std::string("socket: ") + std::strerror(errno);
  ifreq ifr{};
  std::strncpy(ifr.ifr_name, name.c_str(), IFNAMSIZ - 1);
  std::string problem;
  if (::ioctl(fd, SIOCGIFFLAGS, &ifr) < 0) {
    problem = "SIOCGIFFLAGS " + name + ": " + std::strerror(errno);
  } else if (!(ifr.ifr_flags & IFF_UP)) {
    ifr.ifr_flags = static_cast<short>(ifr.ifr_flags | IFF_UP);
    if (::ioctl(fd, SIOCSIFFLAGS, &ifr) < 0) problem = "cannot bring " + name + " up: " + std::strerror(errno);
  }
  ::close(fd);
  return problem;
}

/// The MTU of `name`, or -1 (with `problem` set).
int interface_mtu(const std::string& name, std::string* problem) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  if (fd < 0) {
    *problem = std::string("socket: ") + std::strerror(errno);
    return -1;
  }
  ifreq ifr{};
  std::strncpy(ifr.ifr_name, name.c_str(), IFNAMSIZ - 1);
  int mtu = -1;
  if (::ioctl(fd, SIOCGIFMTU, &ifr) < 0) {
    *problem = "SIOCGIFMTU " + name + ": " + std::strerror(errno);
  } else {
    mtu = ifr.ifr_mtu;
  }
  ::close(fd);
  return mtu;
}

}  // namespace

std::string ensure_can_interface(const std::string& name, bool create_virtual, bool fd) {
  const std::string no_can_hint =
      "on a machine whose kernel has no CAN support, run the rig inside the CAN VM: "
      "tools/canvm/canvm run -- build/bin/rig run <scenario>";
  const int probe = ::socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (probe < 0) {
    const int e = errno;
    if (e == EAFNOSUPPORT)
      return "this kernel has no CAN support (AF_CAN: " + std::string(std::strerror(e)) + "); " + no_can_hint;
    return std::string("cannot open a CAN socket: ") + std::strerror(e);
  }
  ::close(probe);
  if (::if_nametoindex(name.c_str()) == 0) {
    if (!create_virtual) {
      return "CAN interface '" + name +
             "' does not exist in the run's network namespace (create it, set "
             "can_bridge.create_virtual: true, or run.network_namespace: never to use the host's interfaces)";
    }
    std::string out;
    const int code = run_quiet({"ip", "link", "add", "dev", name, "type", "vcan"}, &out);
    if (code != 0) {
      return "cannot create the virtual CAN interface '" + name + "' (ip link add dev " + name +
             " type vcan: " + (out.empty() ? "exit " + std::to_string(code) : out) +
             "); the kernel needs the vcan module (modprobe vcan); " + no_can_hint;
    }
    if (fd) {
      // A vcan takes MTU 16 (classical) or 72 (CAN FD), only while it is down (as it is now).
      out.clear();
      const int mtu_code = run_quiet({"ip", "link", "set", "dev", name, "mtu", std::to_string(CANFD_MTU)}, &out);
      if (mtu_code != 0) {
        return "cannot give the virtual CAN interface '" + name + "' the CAN FD MTU (ip link set dev " + name +
               " mtu " + std::to_string(CANFD_MTU) + ": " + (out.empty() ? "exit " + std::to_string(mtu_code) : out) +
               ")";
      }
    }
  }
  if (fd) {
    std::string problem;
    const int mtu = interface_mtu(name, &problem);
    if (mtu < 0) return problem;
    if (mtu != static_cast<int>(CANFD_MTU)) {
      return "CAN interface '" + name + "' has MTU " + std::to_string(mtu) +
             (mtu == static_cast<int>(CAN_MTU) ? " (classical CAN only)" : "") +
             " but can_bridge.fd is true, which needs CAN FD (MTU " + std::to_string(CANFD_MTU) + "): ip link set " +
             name + " down && ip link set " + name + " mtu " + std::to_string(CANFD_MTU) + " && ip link set " + name +
             " up (a real controller: ip link set " + name +
             " type can bitrate ... dbitrate ... fd on), "
             "or set can_bridge.fd: false";
    }
  }
  return bring_up(name);
}

HostLink::~HostLink() {
  if (remote_fd_ >= 0) ::close(remote_fd_);
}

std::unique_ptr<HostLink> HostLink::create(const std::string& local_address, const std::string& remote_address,
                                           std::string* problem) {
  std::unique_ptr<HostLink> link(new HostLink());
  const int here = ::open("/proc/self/ns/net", O_RDONLY | O_CLOEXEC);
  if (here < 0) {
    *problem = "cannot open this process's network namespace (/proc/self/ns/net): " + errno_text();
    return nullptr;
  }
  // The new namespace: entered for a moment to hold it by a descriptor and bring up its lo.
  if (::unshare(CLONE_NEWNET) != 0) {
    *problem = "cannot create the second host's network namespace (unshare(CLONE_NEWNET)): " + errno_text();
    ::close(here);
    return nullptr;
  }
  link->remote_fd_ = ::open("/proc/self/ns/net", O_RDONLY | O_CLOEXEC);
  const int open_errno = errno;
  const NamespaceResult lo = configure_loopback_multicast();
  if (::setns(here, CLONE_NEWNET) != 0) {
    // This process is left in the wrong namespace: nothing it would do from here is right.
    std::fprintf(stderr, "rig run: cannot return to the launcher's network namespace: %s\n", std::strerror(errno));
    std::abort();
  }
  ::close(here);
  if (link->remote_fd_ < 0) {
    *problem = std::string("cannot open the second host's network namespace: ") + std::strerror(open_errno);
    return nullptr;
  }
  if (!lo.ok) {
    *problem = "second host's loopback: " + lo.detail;
    return nullptr;
  }
  char id[64] = {0};
  const std::string fd_path = "/proc/self/fd/" + std::to_string(link->remote_fd_);
  const ssize_t n = ::readlink(fd_path.c_str(), id, sizeof id - 1);
  link->remote_id_ = n > 0 ? std::string(id, static_cast<std::size_t>(n)) : "";

  // The veth pair, its second end moved into the new namespace (iproute2 takes a path to a
  // namespace where it would take a name), each end with its address, up, and the multicast
  // route on it in place of the one on lo.
  const std::string remote_ns = "/proc/" + std::to_string(::getpid()) + "/fd/" + std::to_string(link->remote_fd_);
  const std::string local_if = kLocalInterface, remote_if = kRemoteInterface;
  struct Step {
    std::vector<std::string> argv;
    bool in_remote;
  };
  const std::vector<Step> steps = {
      {{"ip", "link", "add", local_if, "type", "veth", "peer", "name", remote_if}, false},
      {{"ip", "link", "set", remote_if, "netns", remote_ns}, false},
      {{"ip", "addr", "add", local_address, "dev", local_if}, false},
      {{"ip", "link", "set", local_if, "multicast", "on", "up"}, false},
      {{"ip", "route", "replace", "224.0.0.0/4", "dev", local_if}, false},
      {{"ip", "addr", "add", remote_address, "dev", remote_if}, true},
      {{"ip", "link", "set", remote_if, "multicast", "on", "up"}, true},
      {{"ip", "route", "replace", "224.0.0.0/4", "dev", remote_if}, true},
  };
  for (const Step& step : steps) {
    std::string out;
    const int code = run_quiet(step.argv, &out, step.in_remote ? link->remote_fd_ : -1);
    if (code != 0) {
      std::string cmd;
      for (const auto& a : step.argv) cmd += (cmd.empty() ? "" : " ") + a;
      *problem = "cannot set up the link to the second host (" + cmd + (step.in_remote ? " in its namespace" : "") +
                 ": " + (out.empty() ? "exit " + std::to_string(code) : out) + ")";
      return nullptr;
    }
  }
  link->detail_ = "veth " + local_if + " " + local_address + " <-> " + remote_if + " " + remote_address +
                  ", route 224.0.0.0/4 on each end";
  return link;
}

}  // namespace nimble::launcher
