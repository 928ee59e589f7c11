#include "can_bridge/can_socket.h"

#include <linux/can/raw.h>
#include <linux/errqueue.h>
#include <linux/net_tstamp.h>
#include <net/if.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <thread>
#include <utility>

#include "can_bridge/frame_layout.h"

namespace nimble::can {

namespace {

/// "Network is down (ENETDOWN)".
std::string errno_text(int err) {
  std::string text = std::strerror(err);
  if (const char* name = strerrorname_np(err)) {
    text += " (";
    text += name;
    text += ")";
  }
  return text;
}

[[noreturn]] void fail(int fd, const std::string& interface, int err, const std::string& what) {
  if (fd >= 0) ::close(fd);
  throw CanError(interface, err, what);
}

void set_option(int fd, const std::string& interface, int level, int name, const void* value, socklen_t size,
                const char* what) {
  if (::setsockopt(fd, level, name, value, size) != 0) {
    const int err = errno;
    fail(fd, interface, err,
         std::string("cannot set ") + what + " on the CAN socket for '" + interface + "': " + errno_text(err));
  }
}

int64_t to_ns(const timespec& ts) { return static_cast<int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec; }

}  // namespace

CanError::CanError(const std::string& interface, int errno_value, const std::string& message)
    : std::runtime_error(message), interface_(interface), errno_value_(errno_value) {}

std::vector<can_filter> rig_filters() {
  std::vector<can_filter> filters;
  for (const FrameSpec& f : kAllFrames) {
    filters.push_back(can_filter{f.id, CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG});
  }
  return filters;
}

can_filter rig_block_filter() { return can_filter{0x100, 0x700 | CAN_EFF_FLAG | CAN_RTR_FLAG}; }

can_frame classical_view(const canfd_frame& frame) {
  can_frame f{};
  f.can_id = frame.can_id;
  if (frame.len <= CAN_MAX_DLEN) {
    f.len = frame.len;
    std::memcpy(f.data, frame.data, frame.len);
  }
  return f;
}

canfd_frame to_fd_frame(const can_frame& frame, uint8_t flags) {
  canfd_frame f{};
  f.can_id = frame.can_id;
  f.len = frame.len <= CAN_MAX_DLEN ? frame.len : CAN_MAX_DLEN;
  f.flags = flags;
  std::memcpy(f.data, frame.data, f.len);
  return f;
}

SendResult send_with_retry(const SendAttempt& attempt, const SendRetryPolicy& policy, CanSocketStats& stats,
                           const SleepFunction& sleep) {
  std::chrono::microseconds backoff = policy.first_backoff;
  for (int tries = 0;; ++tries) {
    const int err = attempt();
    if (err == 0) {
      ++stats.frames_sent;
      return SendResult::kSent;
    }
    stats.last_errno = err;
    if (err == ENOBUFS) {
      ++stats.send_enobufs;
    } else if (err == EAGAIN || err == EWOULDBLOCK) {
      ++stats.send_eagain;
    } else {
      ++stats.send_errors;
      return SendResult::kError;
    }
    if (tries >= policy.max_retries) {
      ++stats.send_dropped;
      return SendResult::kDropped;
    }
    ++stats.send_retries;
    if (sleep) sleep(backoff);
    backoff = std::min(backoff * 2, policy.max_backoff);
  }
}

CanSocket CanSocket::open(const std::string& interface, const CanSocketOptions& options) {
  if (interface.empty() || interface.size() >= IFNAMSIZ) {
    fail(-1, interface, EINVAL,
         "invalid CAN interface name '" + interface + "' (1.." + std::to_string(IFNAMSIZ - 1) + " characters)");
  }
  const int fd = ::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd < 0) {
    const int err = errno;
    std::string msg = "cannot open a CAN socket for '" + interface +
                      "': socket(PF_CAN, SOCK_RAW, CAN_RAW) failed: " + errno_text(err);
    if (err == EAFNOSUPPORT) {
      msg +=
          ". The running kernel has no CAN support (CONFIG_CAN not set or the can module not "
          "loadable). On a kernel with CAN: modprobe can can_raw vcan. Tests get real SocketCAN "
          "without it through tools/canvm/canvm (ctest runs the tests labelled 'can' that way).";
    } else if (err == EPROTONOSUPPORT) {
      msg += ". The kernel has CAN but no raw CAN sockets: modprobe can_raw.";
    }
    fail(-1, interface, err, msg);
  }

  const unsigned index = ::if_nametoindex(interface.c_str());
  if (index == 0) {
    const int err = errno;
    fail(fd, interface, err,
         "no network interface '" + interface + "': " + errno_text(err) + ". For a virtual bus: ip link add dev " +
             interface + " type vcan && ip link set " + interface + " up");
  }

  ifreq ifr{};
  std::memcpy(ifr.ifr_name, interface.c_str(), interface.size() + 1);
  if (::ioctl(fd, SIOCGIFFLAGS, &ifr) == 0 && !(ifr.ifr_flags & IFF_UP)) {
    fail(fd, interface, ENETDOWN, "CAN interface '" + interface + "' is down: ip link set " + interface + " up");
  }

  if (options.fd) {
    ifreq mtu_req{};
    std::memcpy(mtu_req.ifr_name, interface.c_str(), interface.size() + 1);
    if (::ioctl(fd, SIOCGIFMTU, &mtu_req) != 0) {
      const int err = errno;
      fail(fd, interface, err, "cannot read the MTU of CAN interface '" + interface + "': " + errno_text(err));
    }
    if (mtu_req.ifr_mtu != static_cast<int>(CANFD_MTU)) {
      fail(fd, interface, EINVAL,
           "CAN interface '" + interface + "' has MTU " + std::to_string(mtu_req.ifr_mtu) +
               (mtu_req.ifr_mtu == static_cast<int>(CAN_MTU) ? " (classical CAN only)" : "") + "; CAN FD needs MTU " +
               std::to_string(CANFD_MTU) + ": ip link set " + interface + " down && ip link set " + interface +
               " mtu " + std::to_string(CANFD_MTU) + " && ip link set " + interface +
               " up (a vcan accepts 16 or 72; a real controller also needs its data bitrate, "
               "e.g. ip link set " +
               interface + " type can bitrate 1000000 dbitrate 4000000 fd on)");
    }
    const int on = 1;
    set_option(fd, interface, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof on, "CAN_RAW_FD_FRAMES");
  }

  if (!options.receive_all) {
    set_option(fd, interface, SOL_CAN_RAW, CAN_RAW_FILTER, options.filters.empty() ? nullptr : options.filters.data(),
               static_cast<socklen_t>(options.filters.size() * sizeof(can_filter)), "CAN_RAW_FILTER");
  }
  const can_err_mask_t err_mask = options.error_frames ? options.error_mask : 0;
  set_option(fd, interface, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &err_mask, sizeof err_mask, "CAN_RAW_ERR_FILTER");
  const int own = options.receive_own ? 1 : 0;
  set_option(fd, interface, SOL_CAN_RAW, CAN_RAW_RECV_OWN_MSGS, &own, sizeof own, "CAN_RAW_RECV_OWN_MSGS");
  if (options.send_buffer_bytes > 0) {
    set_option(fd, interface, SOL_SOCKET, SO_SNDBUF, &options.send_buffer_bytes, sizeof options.send_buffer_bytes,
               "SO_SNDBUF");
  }
  if (options.receive_buffer_bytes > 0) {
    set_option(fd, interface, SOL_SOCKET, SO_RCVBUF, &options.receive_buffer_bytes, sizeof options.receive_buffer_bytes,
               "SO_RCVBUF");
  }
  if (options.timestamps) {
    const int flags = SOF_TIMESTAMPING_RX_SOFTWARE | SOF_TIMESTAMPING_SOFTWARE | SOF_TIMESTAMPING_RX_HARDWARE |
                      SOF_TIMESTAMPING_RAW_HARDWARE;
    set_option(fd, interface, SOL_SOCKET, SO_TIMESTAMPING, &flags, sizeof flags, "SO_TIMESTAMPING");
  }
  const int one = 1;
  set_option(fd, interface, SOL_SOCKET, SO_RXQ_OVFL, &one, sizeof one, "SO_RXQ_OVFL");

  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = static_cast<int>(index);
  if (::bind(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
    const int err = errno;
    std::string msg = "cannot bind the CAN socket to '" + interface + "': " + errno_text(err);
    if (err == ENODEV) msg += " ('" + interface + "' is not a CAN interface)";
    fail(fd, interface, err, msg);
  }
  CanSocket socket(fd, interface, options.retry);
  socket.timestamps_ = options.timestamps;
  socket.fd_enabled_ = options.fd;
  return socket;
}

CanSocket::CanSocket(int fd, std::string interface, SendRetryPolicy retry)
    : fd_(fd), interface_(std::move(interface)), retry_(retry) {}

CanSocket::CanSocket(CanSocket&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)),
      interface_(std::move(other.interface_)),
      retry_(other.retry_),
      stats_(other.stats_),
      timestamps_(other.timestamps_),
      fd_enabled_(other.fd_enabled_) {}

CanSocket& CanSocket::operator=(CanSocket&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = std::exchange(other.fd_, -1);
    interface_ = std::move(other.interface_);
    retry_ = other.retry_;
    stats_ = other.stats_;
    timestamps_ = other.timestamps_;
    fd_enabled_ = other.fd_enabled_;
  }
  return *this;
}

CanSocket::~CanSocket() {
  if (fd_ >= 0) ::close(fd_);
}

SendResult CanSocket::send(const can_frame& frame) {
  const int fd = fd_;
  const SendAttempt attempt = [fd, &frame]() -> int {
    const ssize_t n = ::send(fd, &frame, sizeof frame, MSG_DONTWAIT);
    if (n == static_cast<ssize_t>(sizeof frame)) return 0;
    return n < 0 ? errno : EIO;
  };
  return send_with_retry(attempt, retry_, stats_, [](std::chrono::microseconds t) { std::this_thread::sleep_for(t); });
}

SendResult CanSocket::send(const canfd_frame& frame) {
  const int fd = fd_;
  const SendAttempt attempt = [fd, &frame]() -> int {
    const ssize_t n = ::send(fd, &frame, sizeof frame, MSG_DONTWAIT);
    if (n == static_cast<ssize_t>(sizeof frame)) return 0;
    return n < 0 ? errno : EIO;
  };
  const SendResult r =
      send_with_retry(attempt, retry_, stats_, [](std::chrono::microseconds t) { std::this_thread::sleep_for(t); });
  if (r == SendResult::kSent) ++stats_.fd_frames_sent;
  return r;
}

ReceiveResult CanSocket::receive(ReceivedFrame* out, int timeout_ms) {
  pollfd pfd{fd_, POLLIN, 0};
  const int ready = ::poll(&pfd, 1, timeout_ms);
  if (ready == 0 || (ready < 0 && errno == EINTR)) return ReceiveResult::kTimeout;
  if (ready < 0) {
    stats_.last_errno = errno;
    ++stats_.receive_errors;
    return ReceiveResult::kError;
  }

  ReceivedFrame rx;
  canfd_frame buffer{};
  iovec iov{&buffer, sizeof buffer};
  alignas(cmsghdr) char control[CMSG_SPACE(sizeof(scm_timestamping)) + CMSG_SPACE(sizeof(uint32_t)) + 64];
  msghdr msg{};
  msg.msg_iov = &iov;
  msg.msg_iovlen = 1;
  msg.msg_control = control;
  msg.msg_controllen = sizeof control;
  const ssize_t n = ::recvmsg(fd_, &msg, MSG_DONTWAIT);
  if (n < 0) {
    if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) return ReceiveResult::kTimeout;
    stats_.last_errno = errno;
    ++stats_.receive_errors;
    return ReceiveResult::kError;
  }
  if ((n != static_cast<ssize_t>(CAN_MTU) && n != static_cast<ssize_t>(CANFD_MTU)) || (msg.msg_flags & MSG_TRUNC)) {
    stats_.last_errno = EMSGSIZE;
    ++stats_.receive_errors;
    return ReceiveResult::kError;
  }
  if (n == static_cast<ssize_t>(CANFD_MTU)) {
    if (buffer.len > CANFD_MAX_DLEN) buffer.len = CANFD_MAX_DLEN;
    rx.is_fd = true;
    rx.fd_frame = buffer;
    rx.fd_flags = buffer.flags;
    rx.frame = classical_view(buffer);
  } else {
    std::memcpy(&rx.frame, &buffer, sizeof rx.frame);
  }
  for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
    if (c->cmsg_level != SOL_SOCKET) continue;
    if (c->cmsg_type == SCM_TIMESTAMPING && c->cmsg_len >= CMSG_LEN(sizeof(scm_timestamping))) {
      scm_timestamping ts;
      std::memcpy(&ts, CMSG_DATA(c), sizeof ts);
      if (ts.ts[0].tv_sec != 0 || ts.ts[0].tv_nsec != 0) {
        rx.has_kernel_time = true;
        rx.kernel_time_ns = to_ns(ts.ts[0]);
      }
      rx.hardware_time_ns = to_ns(ts.ts[2]);
    } else if (c->cmsg_type == SO_RXQ_OVFL && c->cmsg_len >= CMSG_LEN(sizeof(uint32_t))) {
      uint32_t dropped = 0;
      std::memcpy(&dropped, CMSG_DATA(c), sizeof dropped);
      stats_.receive_dropped = dropped;  // cumulative count kept by the kernel for this socket
    }
  }
  if (timestamps_ && !rx.has_kernel_time) ++stats_.missing_timestamps;
  rx.is_error_frame = is_error_frame(rx.frame);
  if (rx.is_error_frame) {
    rx.error = decode_error_frame(rx.frame);
    ++stats_.error_frames;
  } else {
    ++stats_.frames_received;
    if (rx.is_fd) ++stats_.fd_frames_received;
  }
  if (out != nullptr) *out = std::move(rx);
  return ReceiveResult::kFrame;
}

}  // namespace nimble::can
