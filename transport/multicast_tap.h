#pragma once
/// MulticastTap: every message of a udpm:// run, received without LCM's receive thread.
///
/// LCM 1.3's udpm provider receives on a thread of its own: per datagram that thread wakes,
/// queues it and writes to a pipe, and the thread that handles messages wakes on the pipe. The
/// launcher receives every message of a run (its log and its monitor), about 6,000 per
/// simulated second and five times that per wall second in lockstep, and those two wake-ups
/// per message made it the busiest process of a lockstep run. Every wake-up is also paid by the
/// publisher, whose send wakes the receivers.
///
/// The tap is a socket bound and joined as LCM's receivers are (the group and port of the URL,
/// SO_REUSEADDR, the URL's recv_buf_size), read by the caller's thread in batches (recvmmsg).
/// It reads LCM's wire format: short messages (magic "LC02": sequence number, NUL-terminated
/// channel, payload) and fragmented ones ("LC03": sequence number, message size, fragment
/// offset, fragment number, fragment count; the channel in fragment 0), reassembled per sender.
/// A caller that need not answer at once (the launcher in real time) reads it every
/// millisecond without waiting on it, so that no publish wakes it; one that must (the
/// launcher's logger in lockstep) waits on fileno() and drains what came.
///
/// Receive times are the kernel's (SO_TIMESTAMPNS), on CLOCK_MONOTONIC in microseconds, as
/// Bus::subscribe_raw gives them.

#include <netinet/in.h>

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace nimble::transport {

class MulticastTap {
 public:
  /// One complete message: its channel, its payload, when its (last) datagram arrived [us,
  /// CLOCK_MONOTONIC].
  using Handler = std::function<void(const std::string& channel, const void* data, int size, int64_t recv_us)>;

  /// Binds and joins the group of `url` (udpm:// only; LCM's default group and port where the
  /// URL gives none).
  /// @throws TransportError naming the URL and the call that failed.
  MulticastTap(const std::string& url, Handler handler);
  /// A tap fed by take() only (tests): no socket.
  explicit MulticastTap(Handler handler);
  ~MulticastTap();
  MulticastTap(const MulticastTap&) = delete;
  MulticastTap& operator=(const MulticastTap&) = delete;

  /// Delivers every complete message the socket holds now, in order of arrival; returns how
  /// many. Never blocks.
  int drain();
  /// Waits up to `timeout_ns` for a datagram, then drain()s; returns how many messages.
  int wait_and_drain(int64_t timeout_ns);
  /// Receives for `timeout_ns`: waiting on the socket if `wait`, else without (what came, a
  /// sleep of at most 1 ms, what came then), so that no publish wakes the caller.
  int receive_for(int64_t timeout_ns, bool wait);
  /// Calls `send` (which publishes on LCM_SELF_TEST) every 100 ms until such a message comes
  /// back, for up to `timeout_ns`; true if one did: the group loops back to the tap.
  bool self_test(const std::function<void()>& send, int64_t timeout_ns);
  /// The socket, readable when a datagram waits.
  int fileno() const { return fd_; }

  /// One datagram as the socket gave it: `from` its sender (address and port, host order
  /// packed), `recv_us` its arrival. Delivers the message it completes, if any.
  void take(const unsigned char* datagram, std::size_t size, uint64_t from, int64_t recv_us);

  /// Datagrams that were not LCM's (too short, another magic, a malformed header) and
  /// fragmented messages abandoned incomplete.
  int64_t discarded() const { return discarded_; }
  /// The socket's receive buffer as the kernel reports it [bytes] (SO_RCVBUF: twice what was
  /// granted, its bookkeeping included); 0 without a socket.
  int receive_buffer_bytes() const;
  /// Messages delivered so far.
  int64_t delivered() const { return delivered_count_; }
  /// True once a message on LCM_SELF_TEST was seen: multicast reaches the tap.
  bool self_test_seen() const { return self_test_seen_; }

 private:
  /// A fragmented message being reassembled, one per sender (LCM sends a message's fragments
  /// together, under its transmit lock).
  struct Partial {
    uint32_t seqno = 0;
    std::string channel;
    std::vector<unsigned char> data;
    uint32_t fragments_expected = 0;
    uint32_t fragments_seen = 0;
    bool channel_known = false;
  };

  void take_fragment(const unsigned char* d, std::size_t n, uint64_t from, int64_t recv_us);
  void deliver(const std::string& channel, const void* data, int size, int64_t recv_us);

  Handler handler_;
  int fd_ = -1;
  std::map<uint64_t, Partial> partial_;
  int64_t discarded_ = 0;
  int64_t delivered_count_ = 0;
  bool self_test_seen_ = false;
  std::vector<std::vector<unsigned char>> buffers_;  // recvmmsg's, allocated once
};

}  // namespace nimble::transport
