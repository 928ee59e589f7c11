#include "transport/bus.h"

#include <cstdlib>
#include <limits>

#include <poll.h>
#include <sys/socket.h>

#include "contract/channels.h"
#include "transport/channel_filter.h"
#include "transport/clock.h"
#include "transport/multicast_tap.h"

namespace nimble::transport {

Bus::Bus(const std::string& url) : url_(url) {
  // LCM's URL when none is given: LCM_DEFAULT_URL, else its default group (udpm).
  const char* env = std::getenv("LCM_DEFAULT_URL");
  receive_url_ = !url.empty() ? url : (env != nullptr && *env != 0 ? env : "udpm://239.255.76.67:7667");
  port_ = udpm_port(receive_url_);
  lcm_ = std::make_unique<lcm::LCM>(url);
  if (!lcm_->good()) {
    throw TransportError("LCM could not start on '" + (url.empty() ? std::string("(default URL)") : url) +
                         "'. For udpm:// the loopback needs multicast: run 'rig check' for the fix, "
                         "or let 'rig run' create a private network namespace");
  }
}

Bus::Bus(InprocessHub& hub) : url_("inprocess"), hub_(&hub) {}

Bus::~Bus() = default;

void Bus::publish_bytes(const std::string& channel, const void* data, int size) {
  if (hub_ != nullptr) {
    hub_->publish(channel, data, size);
    return;
  }
  if (lcm_->publish(channel, data, static_cast<unsigned int>(size)) != 0) ++publish_failures_;
}

bool Bus::track_seq(int64_t seq, ChannelStats& stats) {
  if (stats.one_publisher && !contract::seq_continues(stats.last_seq, seq)) return false;
  if (stats.last_seq >= 0 && seq > stats.last_seq && seq - stats.last_seq > 1) {
    // Saturating: on a channel with several publishers a stray seq can be anything (found by
    // fuzz_node_plant: the sum overflowed).
    const int64_t gap = seq - stats.last_seq - 1;
    stats.drops = gap > std::numeric_limits<int64_t>::max() - stats.drops ? std::numeric_limits<int64_t>::max()
                                                                          : stats.drops + gap;
  }
  stats.last_seq = seq;
  return true;
}

void Bus::count_late(int64_t due_ns, ChannelStats& stats) const {
  if (monotonic_ns() - (t0_ns_ + due_ns) > late_threshold_ns_) ++stats.late;
}

void Bus::Subscription::on_receive(const lcm::ReceiveBuffer* rbuf, const std::string& ch) {
  deliver(ch, rbuf->data, static_cast<int>(rbuf->data_size));
}

void Bus::Subscription::deliver(const std::string& ch, const void* data, int size, int64_t recv_us) {
  if (raw) {
    raw(ch, data, size, recv_us >= 0 ? recv_us : monotonic_us());
    return;
  }
  std::string error;
  if (decode_and_call(data, size, *stats, error)) {
    ++stats->received;
  } else {
    ++stats->malformed;
    if (bus->on_malformed_) bus->on_malformed_(ch, error);
  }
}

void Bus::attach(std::unique_ptr<Subscription> sub, int queue_capacity) {
  if (hub_ != nullptr) {
    Subscription* s = sub.get();
    hub_->subscribe(s->channel, [s](const std::string& ch, const void* data, int size) { s->deliver(ch, data, size); });
    subs_.push_back(std::move(sub));
    return;
  }
  if (port_ > 0) {
    tap();  // the socket's buffer (the URL's recv_buf_size) is the queue
    if (sub->raw) sub->pattern = std::make_unique<std::regex>(sub->channel, std::regex::optimize);
  } else {
    lcm::Subscription* handle = lcm_->subscribe(sub->channel, &Subscription::on_receive, sub.get());
    if (handle != nullptr) handle->setQueueCapacity(queue_capacity);
  }
  if (sub->raw) {
    subscribed_by_pattern_ = true;
  } else {
    channels_.insert(sub->channel);
  }
  subs_.push_back(std::move(sub));
  refresh_channel_filter();
}

void Bus::refresh_channel_filter() {
  if (hub_ != nullptr || port_ <= 0 || channels_.empty()) return;
  const int fd = tap().fileno();  // made at the first subscription
  if (!filter_enabled_ || subscribed_by_pattern_) {
    if (filter_active_) {
      filter_problem_ = detach_channel_filter(fd);
      if (!filter_problem_.empty()) return;  // still active: wait_for_start() announces it
    }
    filter_active_ = false;
    return;
  }
  filter_problem_ = attach_channel_filter(fd, channels_);
  filter_active_ = filter_problem_.empty();
}

void Bus::subscribe_raw(const std::string& regex,
                        std::function<void(const std::string&, const void*, int, int64_t)> handler,
                        int queue_capacity) {
  auto sub = std::make_unique<Subscription>();
  sub->channel = regex;
  sub->bus = this;
  sub->raw = std::move(handler);
  attach(std::move(sub), queue_capacity);
}

MulticastTap& Bus::tap() {
  if (!tap_) {
    auto t =
        std::make_unique<MulticastTap>(receive_url_, [this](const std::string& ch, const void* data, int size,
                                                            int64_t recv_us) { dispatch(ch, data, size, recv_us); });
    // LCM's own check, as its receive thread makes it: its self-test message comes back.
    const std::string probe = "nimble bus self test";
    if (!t->self_test([&] { lcm_->publish("LCM_SELF_TEST", probe.data(), static_cast<unsigned>(probe.size())); },
                      10000000000LL)) {
      throw TransportError("nothing comes back on '" + receive_url_ +
                           "' within 10 s: multicast does not loop back. Run 'rig check' for the fix, or let "
                           "'rig run' create a private network namespace");
    }
    tap_ = std::move(t);
  }
  return *tap_;
}

void Bus::dispatch(const std::string& channel, const void* data, int size, int64_t recv_us) {
  // By index: a handler may subscribe, and subs_ grow under it.
  for (std::size_t i = 0, n = subs_.size(); i < n; ++i) {
    Subscription& s = *subs_[i];
    if (s.pattern ? std::regex_match(channel, *s.pattern) : s.channel == channel)
      s.deliver(channel, data, size, recv_us);
  }
}

int Bus::fileno() const {
  if (hub_ != nullptr) return -1;
  if (port_ > 0) return const_cast<Bus*>(this)->tap().fileno();
  return lcm_->getFileno();
}

int Bus::handle() {
  if (hub_ != nullptr) {
    hub_->drain();
    return 0;
  }
  if (port_ > 0) {
    // Waits for a datagram and handles what came (possibly nothing: bytes that are not LCM's).
    pollfd pfd{tap().fileno(), POLLIN, 0};
    if (::poll(&pfd, 1, -1) < 0) return -1;
    tap().drain();
    return 0;
  }
  return lcm_->handle();
}

int Bus::handle_timeout(int timeout_ms) {
  if (hub_ != nullptr) return hub_->drain() > 0 ? 1 : 0;
  if (port_ > 0) return tap().wait_and_drain(static_cast<int64_t>(timeout_ms) * 1000000LL) > 0 ? 1 : 0;
  return lcm_->handleTimeout(timeout_ms);
}

int Bus::drain() {
  if (hub_ != nullptr) return static_cast<int>(hub_->drain());
  if (port_ > 0) return tap().drain();
  int n = 0;
  pollfd pfd{fileno(), POLLIN, 0};
  while (::poll(&pfd, 1, 0) > 0 && (pfd.revents & POLLIN)) {
    if (lcm_->handle() != 0) break;
    ++n;
  }
  return n;
}

int64_t Bus::malformed_total() const {
  int64_t n = 0;
  for (const auto& [name, s] : stats_) n += s.malformed;
  return n;
}

}  // namespace nimble::transport
