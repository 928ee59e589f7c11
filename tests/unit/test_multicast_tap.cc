// MulticastTap (transport/multicast_tap.h): LCM's wire format read without LCM, from datagrams
// made here and from LCM itself over a real udpm group in a private network namespace.

#include <arpa/inet.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <lcm/lcm-cpp.hpp>

#include "launcher/netns.h"
#include "transport/bus.h"
#include "transport/channel_filter.h"
#include "transport/clock.h"
#include "transport/multicast_tap.h"

using nimble::transport::MulticastTap;

namespace {

struct Got {
  std::string channel;
  std::vector<unsigned char> data;
  int64_t recv_us = 0;
};

MulticastTap::Handler into(std::vector<Got>& got) {
  return [&got](const std::string& channel, const void* data, int size, int64_t recv_us) {
    const auto* p = static_cast<const unsigned char*>(data);
    got.push_back({channel, std::vector<unsigned char>(p, p + size), recv_us});
  };
}

void put32(std::vector<unsigned char>& d, uint32_t v) {
  v = htonl(v);
  const auto* p = reinterpret_cast<const unsigned char*>(&v);
  d.insert(d.end(), p, p + 4);
}
void put16(std::vector<unsigned char>& d, uint16_t v) {
  v = htons(v);
  const auto* p = reinterpret_cast<const unsigned char*>(&v);
  d.insert(d.end(), p, p + 2);
}

/// `payload` on `channel` as LCM fragments it ("LC03"), `size` payload bytes per fragment (the
/// channel and its NUL in fragment 0 count against it, as LCM counts them).
std::vector<std::vector<unsigned char>> fragments(const std::string& channel, const std::vector<unsigned char>& payload,
                                                  uint32_t seqno, std::size_t size) {
  const std::size_t first = size - channel.size() - 1;
  const std::size_t rest = payload.size() - first;
  const uint16_t count = static_cast<uint16_t>(1 + (rest + size - 1) / size);
  std::vector<std::vector<unsigned char>> out;
  std::size_t offset = 0;
  for (uint16_t k = 0; k < count; ++k) {
    std::vector<unsigned char> d;
    put32(d, 0x4c433033);
    put32(d, seqno);
    put32(d, static_cast<uint32_t>(payload.size()));
    put32(d, static_cast<uint32_t>(offset));
    put16(d, k);
    put16(d, count);
    std::size_t n = size;
    if (k == 0) {
      d.insert(d.end(), channel.begin(), channel.end());
      d.push_back(0);
      n = first;
    }
    n = std::min(n, payload.size() - offset);
    d.insert(d.end(), payload.begin() + static_cast<long>(offset), payload.begin() + static_cast<long>(offset + n));
    offset += n;
    out.push_back(d);
  }
  return out;
}

std::vector<unsigned char> counting(std::size_t n) {
  std::vector<unsigned char> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = static_cast<unsigned char>(i * 7 + i / 251);
  return v;
}

}  // namespace

TEST_CASE("multicast tap: short messages as LCM sends them, anything else counted and dropped", "[transport]") {
  std::vector<Got> got;
  MulticastTap tap(into(got));
  const std::vector<unsigned char> payload = counting(40);
  const auto d = nimble::transport::lcm_short_datagram("SAMPLE", payload, 9);
  tap.take(d.data(), d.size(), 1, 1234);
  REQUIRE(got.size() == 1);
  CHECK(got[0].channel == "SAMPLE");
  CHECK(got[0].data == payload);
  CHECK(got[0].recv_us == 1234);
  // An empty payload is a message.
  const auto empty = nimble::transport::lcm_short_datagram("E", {}, 10);
  tap.take(empty.data(), empty.size(), 1, 0);
  REQUIRE(got.size() == 2);
  CHECK(got[1].data.empty());
  CHECK(tap.discarded() == 0);

  // Too short, another magic, no NUL after the channel, an empty channel, a channel over LCM's 63.
  std::vector<unsigned char> bad_magic = d;
  bad_magic[3] = '9';
  std::vector<unsigned char> no_nul = {'L', 'C', '0', '2', 0, 0, 0, 1, 'A', 'B'};
  const auto empty_channel = nimble::transport::lcm_short_datagram("", payload);
  const auto long_channel = nimble::transport::lcm_short_datagram(std::string(64, 'X'), payload);
  for (const auto& b :
       {std::vector<unsigned char>(d.begin(), d.begin() + 7), bad_magic, no_nul, empty_channel, long_channel}) {
    tap.take(b.data(), b.size(), 1, 0);
  }
  CHECK(got.size() == 2);
  CHECK(tap.discarded() == 5);
  CHECK(tap.delivered() == 2);
}

TEST_CASE("multicast tap: fragmented messages reassembled per sender, a broken one dropped and counted",
          "[transport]") {
  std::vector<Got> got;
  MulticastTap tap(into(got));
  const std::vector<unsigned char> big = counting(10000), other = counting(7000);
  const auto a = fragments("BIG", big, 5, 3000);
  const auto b = fragments("OTHER", other, 77, 3000);
  REQUIRE(a.size() == 4);
  REQUIRE(b.size() == 3);
  // Two senders' fragments interleaved: each message whole, at its last fragment's time.
  tap.take(a[0].data(), a[0].size(), 1, 10);
  tap.take(b[0].data(), b[0].size(), 2, 11);
  tap.take(a[1].data(), a[1].size(), 1, 12);
  tap.take(b[1].data(), b[1].size(), 2, 13);
  tap.take(b[2].data(), b[2].size(), 2, 14);
  REQUIRE(got.size() == 1);
  CHECK(got[0].channel == "OTHER");
  CHECK(got[0].data == other);
  CHECK(got[0].recv_us == 14);
  tap.take(a[2].data(), a[2].size(), 1, 15);
  tap.take(a[3].data(), a[3].size(), 1, 16);
  REQUIRE(got.size() == 2);
  CHECK(got[1].channel == "BIG");
  CHECK(got[1].data == big);
  CHECK(tap.discarded() == 0);

  // A sender that moves on to its next message abandons the one it had not finished.
  const auto c = fragments("BIG", big, 6, 3000);
  const auto e = fragments("BIG", big, 7, 3000);
  tap.take(c[0].data(), c[0].size(), 1, 0);
  tap.take(c[1].data(), c[1].size(), 1, 0);
  for (const auto& f : e) tap.take(f.data(), f.size(), 1, 0);
  REQUIRE(got.size() == 3);
  CHECK(got[2].data == big);
  CHECK(tap.discarded() == 1);

  // A fragment that would write past the message, a fragment number past the count, a message
  // size over the limit: each dropped, nothing delivered.
  auto past = fragments("BIG", big, 8, 3000);
  past[1][12] = 0x7f;  // offset far beyond 10,000
  tap.take(past[0].data(), past[0].size(), 3, 0);
  tap.take(past[1].data(), past[1].size(), 3, 0);
  auto number = fragments("BIG", big, 9, 3000);
  number[2][17] = 9;  // fragment 9 of 4
  tap.take(number[2].data(), number[2].size(), 4, 0);
  auto huge = fragments("BIG", big, 10, 3000);
  huge[0][8] = 0x7f;  // 2 GB announced
  tap.take(huge[0].data(), huge[0].size(), 5, 0);
  CHECK(got.size() == 3);
  CHECK(tap.discarded() == 4);
}

TEST_CASE("multicast tap: LCM's own messages over a udpm group, short and fragmented, with kernel receive times",
          "[transport]") {
  // A private network namespace with a multicast loopback, in a child (the test process keeps
  // its own); the child reports what it checked through its exit status and a pipe.
  int fds[2];
  REQUIRE(::pipe(fds) == 0);
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::close(fds[0]);
    auto report = [&](const std::string& what, int code) {
      (void)!::write(fds[1], what.data(), what.size());
      ::_exit(code);
    };
    const nimble::launcher::NamespaceResult ns = nimble::launcher::enter_private_network_namespace();
    if (!ns.ok) report("no private network namespace: " + ns.detail, 2);
    const std::string url = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304";
    std::vector<Got> got;
    try {
      MulticastTap tap(url, into(got));
      lcm::LCM lcm(url);
      if (!lcm.good()) report("LCM does not start on " + url, 3);
      // The URL's buffer, whatever net.core.rmem_max says (the test runs as root).
      if (tap.receive_buffer_bytes() < 4194304) {
        report("a receive buffer of " + std::to_string(tap.receive_buffer_bytes()) + " bytes", 12);
      }
      const std::string probe = "probe";
      if (!tap.self_test([&] { lcm.publish("LCM_SELF_TEST", probe.data(), static_cast<unsigned>(probe.size())); },
                         5000000000LL)) {
        report("the self test did not come back", 4);
      }
      got.clear();
      const std::vector<unsigned char> small = counting(100), large = counting(150000);  // LCM: 3 fragments
      const int64_t before_us = nimble::transport::monotonic_us();
      lcm.publish("SMALL", small.data(), static_cast<unsigned>(small.size()));
      lcm.publish("LARGE", large.data(), static_cast<unsigned>(large.size()));
      lcm.publish("SMALL", small.data(), static_cast<unsigned>(small.size()));
      for (int i = 0; i < 50 && got.size() < 3; ++i) tap.receive_for(20000000, i % 2 == 0);
      const int64_t after_us = nimble::transport::monotonic_us();
      if (got.size() != 3) report("received " + std::to_string(got.size()) + " of 3 messages", 5);
      if (got[0].channel != "SMALL" || got[0].data != small) report("the first message differs", 6);
      if (got[1].channel != "LARGE" || got[1].data != large) report("the fragmented message differs", 7);
      if (got[2].channel != "SMALL" || got[2].data != small) report("the third message differs", 8);
      for (const Got& g : got) {
        if (g.recv_us < before_us - 1000 || g.recv_us > after_us + 1000) {
          report("a receive time " + std::to_string(g.recv_us) + " us outside [" + std::to_string(before_us) + ", " +
                     std::to_string(after_us) + "]",
                 9);
        }
      }
      if (tap.discarded() != 0) report("discarded " + std::to_string(tap.discarded()), 10);
    } catch (const std::exception& e) {
      report(e.what(), 11);
    }
    report("ok", 0);
  }
  ::close(fds[1]);
  std::string what;
  char buf[512];
  for (ssize_t n; (n = ::read(fds[0], buf, sizeof buf)) > 0;) what.append(buf, static_cast<std::size_t>(n));
  ::close(fds[0]);
  int status = 0;
  REQUIRE(::waitpid(pid, &status, 0) == pid);
  INFO(what);
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
  CHECK(what == "ok");
}
