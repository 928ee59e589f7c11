#pragma once
/// LatchedInput: the messages a lockstep participant may use at a RIG_CLOCK tick.
///
/// In lockstep what a task sees at a tick must not depend on process timing. A message
/// another participant published at tick t (stamped t) may arrive before or after this
/// process runs its own tick t, so it counts as received only from the next tick on; a
/// message this process scheduled for time t itself goes out at the first tick at or after t.
/// The latch holds messages in arrival order with their stamp [us] and hands out those
/// released at a tick: the newest one (a state input), or each one in order (a stream to
/// apply). Real time: a message counts from its arrival; newest() gives the newest pushed.
/// Header-only, no LCM: the nodes push from their handlers, the tasks read at the tick.

#include <cstddef>
#include <cstdint>
#include <deque>
#include <limits>
#include <utility>

namespace nimble::transport {

template <typename T>
class LatchedInput {
 public:
  /// When a message stamped `stamp_utime` is released to a tick.
  enum class Release {
    kAfterStamp,  ///< at the first tick later than the stamp (an input published at a tick)
    kAtStamp,     ///< at the first tick at or after the stamp (an output due at its stamp)
  };

  /// `capacity`: most messages held; the oldest goes when a push exceeds it.
  explicit LatchedInput(Release release = Release::kAfterStamp,
                        std::size_t capacity = std::numeric_limits<std::size_t>::max())
      : release_(release), capacity_(capacity) {}

  /// Holds `msg`, stamped `stamp_utime` [us] (in simulated time), until a tick releases it.
  void push(int64_t stamp_utime, T msg) {
    held_.push_back(Entry{stamp_utime, std::move(msg)});
    if (held_.size() > capacity_) held_.pop_front();
  }

  /// True if the oldest held message is released at the tick at `tick_utime` [us].
  bool ready(int64_t tick_utime) const { return !held_.empty() && released(held_.front().stamp_utime, tick_utime); }
  /// The oldest held message and its stamp [us]; only when something is held.
  const T& front() const { return held_.front().msg; }
  int64_t front_stamp_utime() const { return held_.front().stamp_utime; }
  /// Drops the oldest held message.
  void pop() { held_.pop_front(); }

  /// Lockstep: the newest message released at the tick at `tick_utime` [us], or nullptr if
  /// none is. Older messages are dropped; the one returned stays held until a newer one is
  /// released. Real time (`lockstep` false): the newest message pushed, whatever its stamp.
  const T* newest(int64_t tick_utime, bool lockstep = true) {
    if (held_.empty()) return nullptr;
    if (!lockstep) {
      held_.erase(held_.begin(), held_.end() - 1);
      return &held_.back().msg;
    }
    std::size_t n = 0;  // messages released at this tick (the held ones are in arrival order)
    for (auto it = held_.rbegin(); it != held_.rend(); ++it) {
      if (released(it->stamp_utime, tick_utime)) {
        n = static_cast<std::size_t>(held_.rend() - it);
        break;
      }
    }
    if (n == 0) return nullptr;
    held_.erase(held_.begin(), held_.begin() + static_cast<std::ptrdiff_t>(n - 1));
    return &held_.front().msg;
  }

  /// Calls `fn(msg)` for each message released at the tick at `tick_utime` [us], oldest first,
  /// and drops them; stops at the first one not yet released.
  template <typename Fn>
  void drain(int64_t tick_utime, Fn&& fn) {
    while (ready(tick_utime)) {
      fn(held_.front().msg);
      held_.pop_front();
    }
  }

  std::size_t size() const { return held_.size(); }
  bool empty() const { return held_.empty(); }

 private:
  struct Entry {
    int64_t stamp_utime;
    T msg;
  };

  bool released(int64_t stamp_utime, int64_t tick_utime) const {
    return release_ == Release::kAfterStamp ? stamp_utime < tick_utime : stamp_utime <= tick_utime;
  }

  Release release_;
  std::size_t capacity_;
  std::deque<Entry> held_;
};

}  // namespace nimble::transport
