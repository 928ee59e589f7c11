#pragma once
/// The rig's LCM transport: one Bus per process.
///
/// Bus wraps lcm::LCM with what a rig process needs and LCM 1.3.1 lacks:
///  - typed subscriptions with std::function handlers;
///  - malformed messages (wrong fingerprint, truncated) counted and reported, never thrown;
///  - per-channel receive statistics: count, drops (gaps in `seq`), queue capacity set on purpose;
///  - a clear error naming the URL when LCM cannot start (for example no multicast route);
///  - a second carrier for runs flown in one process: the same messages, encoded the same
///    way, through an InprocessHub instead of LCM.

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <regex>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "contract/channels.h"
#include "contract/decode.h"
#include "contract/faults.h"
#include "transport/clock.h"
#include "transport/fault_injector.h"
#include "transport/inprocess_hub.h"

namespace nimble::transport {

/// LCM could not be started on the given URL.
class TransportError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Receive statistics of one subscribed channel.
struct ChannelStats {
  int64_t received = 0;   ///< messages decoded and delivered
  int64_t malformed = 0;  ///< messages that failed to decode (dropped)
  int64_t drops = 0;      ///< messages missing according to gaps in the publisher's seq
  int64_t last_seq = -1;  ///< seq of the newest message, -1 before the first
  /// Real time, once Bus::set_deadlines() was called: messages handled more than the late
  /// threshold after their due time (channels stamped in simulated time only).
  int64_t late = 0;
  bool due_in_sim_time = false;  ///< the channel's utime is simulated time (the contract says)
  bool one_publisher = false;    ///< the channel has one publisher: its seq must continue
  /// The rig time [us] of a utime stamped on another clock (Bus::set_stamp_clock); empty: the
  /// utime is rig time.
  std::function<int64_t(int64_t)> rig_utime_of;
};

namespace detail {
template <typename T, typename = void>
struct has_latency_us : std::false_type {};
template <typename T>
struct has_latency_us<T, std::void_t<decltype(std::declval<T>().latency_us)>> : std::true_type {};
}  // namespace detail

/// Called for a message that failed to decode: channel and a description.
using MalformedHandler = std::function<void(const std::string& channel, const std::string& what)>;

/// Default receive queue per subscription [messages]; LCM's own default of 30 drops silently.
constexpr int kDefaultQueueCapacity = 1000;

class MulticastTap;

class Bus {
 public:
  /// Opens LCM on `url` (empty: LCM_DEFAULT_URL or LCM's default).
  /// @throws TransportError naming the URL if LCM does not start.
  explicit Bus(const std::string& url);
  /// Carries messages through `hub` (an in-process run); `hub` must outlive the Bus.
  explicit Bus(InprocessHub& hub);
  ~Bus();
  Bus(const Bus&) = delete;
  Bus& operator=(const Bus&) = delete;

  const std::string& url() const { return url_; }
  /// The hub of an in-process run, nullptr over LCM.
  InprocessHub* hub() const { return hub_; }

  /// Publishes `msg` on `channel`. Never throws; a failure is counted in publish_failures().
  /// On a channel the scenario faults, the message goes through the fault injector, which
  /// decides at `rig_utime` [us] when given (a message stamped on another clock: the IMU's),
  /// else at the message's utime.
  template <typename T>
  void publish(const std::string& channel, const T& msg, std::optional<int64_t> rig_utime = std::nullopt) {
    if (injector_ != nullptr && injector_->targets(channel)) {
      publish_faulted(channel, msg, rig_utime);
      return;
    }
    publish_now(channel, msg);
  }

  /// The messages of `channel` (subscribed or to be) carry a utime on another clock than the
  /// rig's: `rig_utime_of` gives the rig time of such a utime, at which the message is due
  /// (the late count of set_deadlines()).
  void set_stamp_clock(const std::string& channel, std::function<int64_t(int64_t)> rig_utime_of) {
    stats_[channel].rig_utime_of = std::move(rig_utime_of);
  }

  /// Publishes already encoded bytes (the fault injector, tools). Never throws.
  void publish_bytes(const std::string& channel, const void* data, int size);

  /// From now on, the messages of the channels `injector` targets go through it.
  void set_fault_injector(std::unique_ptr<FaultInjector> injector) { injector_ = std::move(injector); }
  const FaultInjector* fault_injector() const { return injector_.get(); }

 private:
  template <typename T>
  void publish_faulted(const std::string& channel, const T& original, std::optional<int64_t> rig_utime) {
    T msg = original;
    FaultableMessage m;
    m.utime = &msg.utime;
    m.rig_utime = rig_utime;
    m.seq = &msg.seq;
    m.values = contract::value_fields(msg);
    m.encode = [&msg] {
      std::vector<uint8_t> bytes(static_cast<std::size_t>(msg.getEncodedSize()));
      msg.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
      return bytes;
    };
    m.restore = [&msg](const std::vector<uint8_t>& bytes) {
      msg.decode(bytes.data(), 0, static_cast<int>(bytes.size()));
    };
    injector_->publish(*this, channel, m);
  }

  template <typename T>
  void publish_now(const std::string& channel, const T& msg) {
    if (hub_ != nullptr) {
      const int size = msg.getEncodedSize();
      if (scratch_.size() < static_cast<std::size_t>(size)) scratch_.resize(static_cast<std::size_t>(size));
      if (msg.encode(scratch_.data(), 0, size) != size) {
        ++publish_failures_;
        return;
      }
      hub_->publish(channel, scratch_.data(), size, /*own_encoding=*/true);
      return;
    }
    if (lcm_->publish(channel, &msg) != 0) ++publish_failures_;
  }

 public:
  /// Subscribes `handler` to `channel` (an exact name). The handler gets the decoded
  /// message. Types whose first fields are `utime, seq` get drop counting from gaps in seq.
  /// A message that does not decode exactly, or (on a channel with one publisher) whose seq
  /// does not continue the sequence, is malformed: counted, reported, never delivered.
  template <typename T>
  void subscribe(const std::string& channel, std::function<void(const T&)> handler,
                 int queue_capacity = kDefaultQueueCapacity) {
    auto sub = std::make_unique<Subscription>();
    sub->channel = channel;
    sub->stats = &stats_[channel];
    sub->bus = this;
    sub->stats->due_in_sim_time = contract::due_in_sim_time(channel);
    sub->stats->one_publisher = contract::single_publisher(channel);
    sub->decode_and_call = [this, handler](const void* data, int size, ChannelStats& stats,
                                           std::string& error) -> bool {
      T msg{};  // value-initialised: decode() fills it, the compiler cannot see that
      // Bytes the rig's own encoder wrote in this process encode back by construction; any
      // other bytes (over LCM, or published raw) are checked in full.
      const bool own = hub_ != nullptr && hub_->delivering_own_encoding();
      if (!contract::decode_as(data, size, msg, own, &error)) return false;
      if (!track_seq(msg.seq, stats)) {
        error = "seq " + std::to_string(msg.seq) + " does not continue the publisher's " +
                std::to_string(stats.last_seq) + " (a stray publisher, or bytes that happened to decode)";
        return false;
      }
      if (late_threshold_ns_ > 0 && stats.due_in_sim_time) {
        // Due at its simulated time; a motion-capture pose (stamped at mid-exposure) once
        // its latency has passed.
        int64_t due_ns = message_us_to_ns(stats.rig_utime_of ? stats.rig_utime_of(msg.utime) : msg.utime);
        if constexpr (detail::has_latency_us<T>::value) due_ns += message_us_to_ns(msg.latency_us);
        count_late(due_ns, stats);
      }
      handler(msg);
      return true;
    };
    attach(std::move(sub), queue_capacity);
  }

  /// Subscribes to every channel matching `regex` without decoding (for loggers).
  /// The handler gets channel, data, size and the receive time [us, CLOCK_MONOTONIC].
  void subscribe_raw(const std::string& regex,
                     std::function<void(const std::string&, const void*, int, int64_t)> handler,
                     int queue_capacity = 10000);

  /// Real time: from now on, a message of a channel stamped in simulated time counts as late
  /// (ChannelStats::late) when it is handled more than `threshold_ns` after it was due:
  /// at t0 + utime, a motion-capture pose at t0 + utime + latency_us. Rig processes call it
  /// at the start of a real-time run. 0 turns it off.
  void set_deadlines(int64_t t0_monotonic_ns, int64_t threshold_ns) {
    t0_ns_ = t0_monotonic_ns;
    late_threshold_ns_ = threshold_ns;
  }

  /// Over udpm://: keep only the subscribed channels on this process's receive socket, in
  /// the kernel (transport/channel_filter.h), from the next subscription on. A subscription
  /// by pattern (subscribe_raw) turns the filter off. No effect in process or on other providers.
  void enable_channel_filter(bool on) {
    filter_enabled_ = on;
    refresh_channel_filter();
  }
  /// "" while the filter works as asked, else why it does not (it is then simply off).
  const std::string& channel_filter_problem() const { return filter_problem_; }
  /// True if the kernel filter is in place on the receive socket.
  bool channel_filter_active() const { return filter_active_; }

  /// Called for every malformed message in addition to counting it.
  void on_malformed(MalformedHandler handler) { on_malformed_ = std::move(handler); }

  /// File descriptor that becomes readable when messages wait (for poll/ppoll); -1 in process.
  int fileno() const;
  /// Handles one message, blocking until one arrives. Returns 0 on success, -1 on error.
  /// In process: delivers everything waiting (never blocks).
  int handle();
  /// Handles one message or returns after `timeout_ms`: > 0 handled, 0 timeout, < 0 error.
  /// In process: delivers everything waiting (never waits).
  int handle_timeout(int timeout_ms);
  /// Handles every message already waiting without blocking; returns how many.
  int drain();

  /// Receive statistics by channel (exact subscriptions only).
  const std::map<std::string, ChannelStats>& stats() const { return stats_; }
  int64_t publish_failures() const { return publish_failures_; }
  int64_t malformed_total() const;

  /// The underlying LCM instance (for tools that need its full API); only over LCM.
  lcm::LCM& lcm() { return *lcm_; }

 private:
  struct Subscription {
    std::string channel;
    ChannelStats* stats = nullptr;
    Bus* bus = nullptr;
    std::function<bool(const void*, int, ChannelStats&, std::string&)> decode_and_call;
    std::function<void(const std::string&, const void*, int, int64_t)> raw;
    std::unique_ptr<std::regex> pattern;  ///< over the tap: a subscribe_raw's pattern, whole-name match
    void on_receive(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
    /// `recv_us`: when it arrived [us, CLOCK_MONOTONIC], or -1: now.
    void deliver(const std::string& channel, const void* data, int size, int64_t recv_us = -1);
  };

  /// Counts gaps in `seq` as drops. On a channel with one publisher, a seq that does not
  /// continue the sequence (contract::seq_continues) is refused: false, nothing counted.
  static bool track_seq(int64_t seq, ChannelStats& stats);
  void count_late(int64_t due_ns, ChannelStats& stats) const;
  void attach(std::unique_ptr<Subscription> sub, int queue_capacity);
  void refresh_channel_filter();
  /// Over udpm: the tap this Bus receives on, made (and its group checked with LCM's self-test
  /// message) at the first subscription or fileno().
  /// @throws TransportError if multicast does not reach it.
  MulticastTap& tap();
  /// Over the tap: one message to every subscription it matches, in subscription order.
  void dispatch(const std::string& channel, const void* data, int size, int64_t recv_us);

  std::string url_;
  std::unique_ptr<lcm::LCM> lcm_;
  /// Over udpm the Bus receives on a MulticastTap (transport/multicast_tap.h), read by the
  /// process's own thread, instead of LCM's receive thread: one wake-up per message, not two.
  std::unique_ptr<MulticastTap> tap_;
  InprocessHub* hub_ = nullptr;
  std::vector<unsigned char> scratch_;  // in process: the encoded message
  std::unique_ptr<FaultInjector> injector_;
  std::map<std::string, ChannelStats> stats_;
  std::vector<std::unique_ptr<Subscription>> subs_;
  MalformedHandler on_malformed_;
  int64_t publish_failures_ = 0;
  int64_t t0_ns_ = 0;
  int64_t late_threshold_ns_ = 0;
  // Kernel channel filter (udpm only).
  bool filter_enabled_ = false;
  bool filter_active_ = false;
  bool subscribed_by_pattern_ = false;
  std::string receive_url_;         ///< url_, or LCM's when url_ is empty
  int port_ = -1;                   ///< receive_url_'s udpm port, -1 for other providers
  std::set<std::string> channels_;  ///< exact subscriptions
  std::string filter_problem_;
};

}  // namespace nimble::transport
