// MulticastTap (transport/multicast_tap.h): a udpm:// group read without LCM's receive thread.

#include "transport/multicast_tap.h"

#include <arpa/inet.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <ctime>

#include "transport/bus.h"
#include "transport/channel_filter.h"
#include "transport/clock.h"

namespace nimble::transport {

namespace {

constexpr uint32_t kLc02Magic = 0x4c433032;  // "LC02"
constexpr uint32_t kLc03Magic = 0x4c433033;  // "LC03"
constexpr std::size_t kShortHeader = 8;      // magic, sequence number
constexpr std::size_t kLongHeader = 20;      // magic, seqno, msg_size, offset, fragment_no, count
constexpr std::size_t kMaxDatagram = 65536;
constexpr unsigned kBatch = 32;
// LCM refuses more than 65,535 fragments of 65,423 bytes; the rig's messages are far smaller.
// A header announcing more than this is malformed here.
constexpr uint32_t kMaxMessageBytes = 64u << 20;
constexpr int kMaxChannel = 63;  // LCM_MAX_CHANNEL_NAME_LENGTH

uint32_t be32(const unsigned char* p) {
  uint32_t v;
  std::memcpy(&v, p, 4);
  return ntohl(v);
}
uint16_t be16(const unsigned char* p) {
  uint16_t v;
  std::memcpy(&v, p, 2);
  return ntohs(v);
}

/// The channel at `p` (at most `n` bytes, NUL-terminated within them and within LCM's limit),
/// or -1.
int channel_length(const unsigned char* p, std::size_t n) {
  const std::size_t limit = n < kMaxChannel + 1 ? n : kMaxChannel + 1;
  const void* nul = std::memchr(p, 0, limit);
  return nul == nullptr ? -1 : static_cast<int>(static_cast<const unsigned char*>(nul) - p);
}

int64_t realtime_ns() {
  timespec ts{};
  ::clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

std::string receive_socket_failure(const std::string& url, const std::string& call) {
  return "the receive socket on '" + url + "': " + call + ": " + std::strerror(errno) +
         ". For udpm:// the loopback needs multicast: run 'rig check' for the fix, or let 'rig run' create a "
         "private network namespace";
}

}  // namespace

MulticastTap::MulticastTap(Handler handler) : handler_(std::move(handler)) {}

MulticastTap::MulticastTap(const std::string& url, Handler handler) : handler_(std::move(handler)) {
  const std::string scheme = "udpm://";
  if (url.compare(0, scheme.size(), scheme) != 0) {
    throw TransportError("a multicast tap needs a udpm:// URL, not '" + url + "'");
  }
  const std::string rest = url.substr(scheme.size());
  const std::string host_port = rest.substr(0, rest.find('?'));
  const auto colon = host_port.find(':');
  const std::string host = host_port.substr(0, colon);
  const int port = udpm_port(url);
  int recv_buf = 0;
  if (const auto q = rest.find('?'); q != std::string::npos) {
    const std::string opts = "&" + rest.substr(q + 1);
    const std::string key = "&recv_buf_size=";
    if (const auto k = opts.find(key); k != std::string::npos) recv_buf = std::atoi(opts.c_str() + k + key.size());
  }
  in_addr group{};
  if (::inet_pton(AF_INET, host.empty() ? "239.255.76.67" : host.c_str(), &group) != 1 || port <= 0 || port > 65535) {
    throw TransportError("a multicast tap cannot read the group and port of '" + url + "'");
  }
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw TransportError(receive_socket_failure(url, "socket"));
  const int one = 1;
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr = group;
  addr.sin_port = htons(static_cast<uint16_t>(port));
  ip_mreq mreq{};
  mreq.imr_multiaddr = group;
  mreq.imr_interface.s_addr = htonl(INADDR_ANY);
  std::string failed;
  if (::setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one) != 0) {
    failed = "SO_REUSEADDR";
  } else if (recv_buf > 0 && ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUFFORCE, &recv_buf, sizeof recv_buf) != 0 &&
             ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &recv_buf, sizeof recv_buf) != 0) {
    // The socket's buffer is the only queue of what waits to be read: beyond net.core.rmem_max
    // where the process may (CAP_NET_ADMIN), else up to it, as LCM's receive socket.
    failed = "SO_RCVBUF";
  } else if (::setsockopt(fd_, SOL_SOCKET, SO_TIMESTAMPNS, &one, sizeof one) != 0) {
    failed = "SO_TIMESTAMPNS";
  } else if (::bind(fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
    failed = "bind";
  } else if (::setsockopt(fd_, IPPROTO_IP, IP_ADD_MEMBERSHIP, &mreq, sizeof mreq) != 0) {
    failed = "IP_ADD_MEMBERSHIP";
  }
  if (!failed.empty()) {
    const std::string what = receive_socket_failure(url, failed);
    ::close(fd_);
    fd_ = -1;
    throw TransportError(what);
  }
  buffers_.assign(kBatch, std::vector<unsigned char>(kMaxDatagram));
}

int MulticastTap::receive_buffer_bytes() const {
  int bytes = 0;
  socklen_t len = sizeof bytes;
  if (fd_ < 0 || ::getsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &bytes, &len) != 0) return 0;
  return bytes;
}

MulticastTap::~MulticastTap() {
  if (fd_ >= 0) ::close(fd_);
}

int MulticastTap::wait_and_drain(int64_t timeout_ns) {
  if (fd_ < 0) return 0;
  pollfd pfd{fd_, POLLIN, 0};
  const timespec ts{static_cast<time_t>(timeout_ns / 1000000000LL), static_cast<long>(timeout_ns % 1000000000LL)};
  if (::ppoll(&pfd, 1, &ts, nullptr) <= 0) return 0;
  return drain();
}

int MulticastTap::receive_for(int64_t timeout_ns, bool wait) {
  if (wait) return wait_and_drain(timeout_ns);
  int n = drain();
  const int64_t pause_ns = timeout_ns < 1000000 ? timeout_ns : 1000000;
  const timespec pause{0, static_cast<long>(pause_ns)};
  ::nanosleep(&pause, nullptr);
  return n + drain();
}

bool MulticastTap::self_test(const std::function<void()>& send, int64_t timeout_ns) {
  const int64_t give_up = monotonic_ns() + timeout_ns;
  while (!self_test_seen_ && monotonic_ns() < give_up) {
    send();
    wait_and_drain(100000000);
  }
  return self_test_seen_;
}

int MulticastTap::drain() {
  if (fd_ < 0) return 0;
  mmsghdr msgs[kBatch];
  iovec iov[kBatch];
  sockaddr_in from[kBatch];
  alignas(cmsghdr) unsigned char control[kBatch][CMSG_SPACE(sizeof(timespec))];
  int delivered = 0;
  for (;;) {
    std::memset(msgs, 0, sizeof msgs);
    for (unsigned i = 0; i < kBatch; ++i) {
      iov[i] = {buffers_[i].data(), buffers_[i].size()};
      msgs[i].msg_hdr.msg_iov = &iov[i];
      msgs[i].msg_hdr.msg_iovlen = 1;
      msgs[i].msg_hdr.msg_name = &from[i];
      msgs[i].msg_hdr.msg_namelen = sizeof from[i];
      msgs[i].msg_hdr.msg_control = control[i];
      msgs[i].msg_hdr.msg_controllen = sizeof control[i];
    }
    const int n = ::recvmmsg(fd_, msgs, kBatch, MSG_DONTWAIT, nullptr);
    if (n <= 0) break;  // nothing left (EAGAIN), or interrupted: the next call goes on
    // The kernel stamps arrival on CLOCK_REALTIME; one offset per batch brings it to
    // CLOCK_MONOTONIC, the clock of every other receive time in the rig.
    const int64_t to_monotonic = monotonic_ns() - realtime_ns();
    const int64_t now_us = monotonic_us();
    for (int i = 0; i < n; ++i) {
      int64_t recv_us = now_us;
      for (cmsghdr* c = CMSG_FIRSTHDR(&msgs[i].msg_hdr); c != nullptr; c = CMSG_NXTHDR(&msgs[i].msg_hdr, c)) {
        if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMPNS) {
          timespec ts{};
          std::memcpy(&ts, CMSG_DATA(c), sizeof ts);
          recv_us = (static_cast<int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec + to_monotonic) / 1000;
        }
      }
      const uint64_t sender = (static_cast<uint64_t>(ntohl(from[i].sin_addr.s_addr)) << 16) | ntohs(from[i].sin_port);
      const int64_t before = delivered_count_;
      take(buffers_[i].data(), msgs[i].msg_len, sender, recv_us);
      delivered += static_cast<int>(delivered_count_ - before);
    }
    if (n < static_cast<int>(kBatch)) break;
  }
  return delivered;
}

void MulticastTap::take(const unsigned char* d, std::size_t n, uint64_t from, int64_t recv_us) {
  if (n < kShortHeader) {
    ++discarded_;
    return;
  }
  const uint32_t magic = be32(d);
  if (magic == kLc03Magic) {
    take_fragment(d, n, from, recv_us);
    return;
  }
  if (magic != kLc02Magic) {
    ++discarded_;
    return;
  }
  const int len = channel_length(d + kShortHeader, n - kShortHeader);
  if (len <= 0) {
    ++discarded_;
    return;
  }
  const std::string channel(reinterpret_cast<const char*>(d + kShortHeader), static_cast<std::size_t>(len));
  const std::size_t at = kShortHeader + static_cast<std::size_t>(len) + 1;
  deliver(channel, d + at, static_cast<int>(n - at), recv_us);
}

void MulticastTap::take_fragment(const unsigned char* d, std::size_t n, uint64_t from, int64_t recv_us) {
  if (n < kLongHeader) {
    ++discarded_;
    return;
  }
  const uint32_t seqno = be32(d + 4), size = be32(d + 8), offset = be32(d + 12);
  const uint32_t number = be16(d + 16), count = be16(d + 18);
  if (size > kMaxMessageBytes || count == 0 || number >= count) {
    ++discarded_;
    return;
  }
  auto it = partial_.find(from);
  if (it != partial_.end() &&
      (it->second.seqno != seqno || it->second.data.size() != size || it->second.fragments_expected != count)) {
    ++discarded_;  // the sender moved on: what it had sent of the last message is lost
    partial_.erase(it);
    it = partial_.end();
  }
  if (it == partial_.end()) {
    Partial p;
    p.seqno = seqno;
    p.data.resize(size);
    p.fragments_expected = count;
    it = partial_.emplace(from, std::move(p)).first;
  }
  Partial& p = it->second;
  const unsigned char* body = d + kLongHeader;
  std::size_t body_size = n - kLongHeader;
  if (number == 0) {
    const int len = channel_length(body, body_size);
    if (len <= 0) {
      ++discarded_;
      partial_.erase(it);
      return;
    }
    p.channel.assign(reinterpret_cast<const char*>(body), static_cast<std::size_t>(len));
    p.channel_known = true;
    body += len + 1;
    body_size -= static_cast<std::size_t>(len) + 1;
  }
  if (static_cast<uint64_t>(offset) + body_size > p.data.size()) {
    ++discarded_;
    partial_.erase(it);
    return;
  }
  std::memcpy(p.data.data() + offset, body, body_size);
  if (++p.fragments_seen < p.fragments_expected || !p.channel_known) return;
  const Partial done = std::move(p);
  partial_.erase(it);
  deliver(done.channel, done.data.data(), static_cast<int>(done.data.size()), recv_us);
}

void MulticastTap::deliver(const std::string& channel, const void* data, int size, int64_t recv_us) {
  ++delivered_count_;
  if (channel == "LCM_SELF_TEST") self_test_seen_ = true;
  handler_(channel, data, size, recv_us);
}

}  // namespace nimble::transport
