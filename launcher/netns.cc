#include "launcher/netns.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <net/if.h>
#include <net/route.h>
#include <sched.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>

#include <lcm/lcm-cpp.hpp>

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

}  // namespace nimble::launcher
