// The kernel-side channel filter on real UDP sockets over the loopback: LCM datagrams on the
// listed channels pass, others are dropped in the kernel, and anything that is not an LCM
// short message passes untouched.

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <set>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "contract/channels.h"
#include "transport/channel_filter.h"

using namespace nimble::transport;
namespace ch = nimble::contract::channels;

namespace {

/// A UDP socket bound to an ephemeral port on 127.0.0.1, closed at the end.
struct Socket {
  int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in addr{};
  Socket() {
    addr.sin_family = AF_INET;
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    REQUIRE(::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0);
    socklen_t len = sizeof addr;
    REQUIRE(::getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len) == 0);
  }
  ~Socket() { ::close(fd); }
  int port() const { return ntohs(addr.sin_port); }
};

/// Sends each datagram to `to`, then returns what `to` received, in order.
std::vector<std::vector<unsigned char>> deliver(Socket& to, const std::vector<std::vector<unsigned char>>& datagrams) {
  Socket from;
  for (const auto& d : datagrams) {
    REQUIRE(::sendto(from.fd, d.data(), d.size(), 0, reinterpret_cast<const sockaddr*>(&to.addr), sizeof to.addr) ==
            static_cast<ssize_t>(d.size()));
  }
  std::vector<std::vector<unsigned char>> got;
  pollfd p{to.fd, POLLIN, 0};
  while (::poll(&p, 1, 100) > 0) {
    std::vector<unsigned char> buf(70000);
    const ssize_t n = ::recv(to.fd, buf.data(), buf.size(), 0);
    REQUIRE(n >= 0);
    buf.resize(static_cast<std::size_t>(n));
    got.push_back(buf);
  }
  return got;
}

std::vector<unsigned char> bytes(const std::string& s) { return std::vector<unsigned char>(s.begin(), s.end()); }

}  // namespace

TEST_CASE("channel filter: only the listed channels' LCM messages reach the socket", "[transport]") {
  Socket rx;
  REQUIRE(attach_channel_filter(rx.fd, {ch::kImu, ch::kActuatorCommand, ch::kRunControl}).empty());
  const std::vector<unsigned char> payload(40, 0x5a);
  const auto imu = lcm_short_datagram(ch::kImu, payload);
  const auto cmd = lcm_short_datagram(ch::kActuatorCommand, payload, 7);
  const auto run = lcm_short_datagram(ch::kRunControl, bytes("x"));  // short payload, long name
  const auto self_test = lcm_short_datagram("LCM_SELF_TEST", bytes("lcm self test"));
  const auto not_lcm = bytes("not an LCM datagram at all");
  const std::vector<std::vector<unsigned char>> sent = {
      lcm_short_datagram(ch::kTruth, payload),
      imu,
      lcm_short_datagram(ch::kImu + "X", payload),         // a longer name sharing the prefix
      lcm_short_datagram(ch::kImu.substr(0, 2), payload),  // a shorter one
      lcm_short_datagram(ch::kActuatorCommandCan, payload),
      cmd,
      lcm_short_datagram(ch::kActuatorFeedback, payload),  // same first words as the command
      run,
      self_test,
      not_lcm,
  };
  const auto got = deliver(rx, sent);
  REQUIRE(got.size() == 5);
  CHECK(got[0] == imu);
  CHECK(got[1] == cmd);
  CHECK(got[2] == run);
  CHECK(got[3] == self_test);
  CHECK(got[4] == not_lcm);
}

TEST_CASE("channel filter: names of every length up to the word boundary and beyond", "[transport]") {
  // 1..9 characters: every split between whole words and trailing bytes.
  const std::string alphabet = "ABCDEFGHI";
  for (std::size_t n = 1; n <= alphabet.size(); ++n) {
    const std::string name = alphabet.substr(0, n);
    INFO(name);
    Socket rx;
    REQUIRE(attach_channel_filter(rx.fd, {name}).empty());
    const std::vector<unsigned char> payload(16, 1);
    const auto got = deliver(rx, {lcm_short_datagram(name + "Z", payload), lcm_short_datagram(name, payload),
                                  lcm_short_datagram(name.substr(0, n - 1) + "Z", payload)});
    REQUIRE(got.size() == 1);
    CHECK(got[0] == lcm_short_datagram(name, payload));
  }
}

TEST_CASE("channel filter: a detached filter lets every datagram through again", "[transport]") {
  // What a process needs once it subscribes by pattern after its exact channels (a Python
  // participant: python/py_participant.cc): the filter of the exact channels must go.
  Socket rx;
  REQUIRE(attach_channel_filter(rx.fd, {"A"}).empty());
  const std::vector<unsigned char> payload(8, 0);
  REQUIRE(deliver(rx, {lcm_short_datagram("A", payload), lcm_short_datagram("B", payload)}).size() == 1);
  REQUIRE(detach_channel_filter(rx.fd).empty());
  const auto got = deliver(rx, {lcm_short_datagram("A", payload), lcm_short_datagram("B", payload)});
  REQUIRE(got.size() == 2);
  CHECK(got[1] == lcm_short_datagram("B", payload));
  CHECK(detach_channel_filter(-1).find("SO_DETACH_FILTER") == 0);
}

TEST_CASE("channel filter: a new filter replaces the old one, and the bound sockets are found by port", "[transport]") {
  Socket rx;
  REQUIRE(attach_channel_filter(rx.fd, {"A"}).empty());
  REQUIRE(attach_channel_filter(rx.fd, {"B"}).empty());
  const std::vector<unsigned char> payload(8, 0);
  const auto got = deliver(rx, {lcm_short_datagram("A", payload), lcm_short_datagram("B", payload)});
  REQUIRE(got.size() == 1);
  CHECK(got[0] == lcm_short_datagram("B", payload));
  CHECK(udp_sockets_bound_to(rx.port()) == std::set<int>{rx.fd});
  CHECK(udpm_port("udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608") == 7667);
  CHECK(udpm_port("udpm://239.255.76.67:21234") == 21234);
  CHECK(udpm_port("udpm://239.255.76.67") == 7667);
  CHECK(udpm_port("memq://") == -1);
}
