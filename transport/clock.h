#pragma once
/// Time sources and timing statistics for rig processes.

#include <array>
#include <cstdint>
#include <vector>

namespace nimble::transport {

/// CLOCK_MONOTONIC now [ns].
int64_t monotonic_ns();

/// Largest time a message's microseconds convert to [ns], about 73 years: a time from the bus
/// (any int64) can be converted and added to a clock reading without overflowing.
constexpr int64_t kMaxMessageTimeNs = INT64_MAX / 4;

/// Latest simulated time a rig message can carry [us], about 11.6 days: no run is longer.
constexpr int64_t kMaxSimUtime = 1000000000000;
/// True if `utime` [us] can be the simulated time of a message of a run (0..kMaxSimUtime). A
/// node refuses other times before its cores see them: arithmetic on times stays far from
/// overflow, and no core catches up (frame by frame, step by step) over an absurd interval.
constexpr bool plausible_sim_utime(int64_t utime) { return utime >= 0 && utime <= kMaxSimUtime; }

/// A message's time [us] in ns, clamped to +-kMaxMessageTimeNs (a received utime is not trusted).
constexpr int64_t message_us_to_ns(int64_t us) {
  constexpr int64_t kMaxUs = kMaxMessageTimeNs / 1000;
  return us > kMaxUs ? kMaxMessageTimeNs : us < -kMaxUs ? -kMaxMessageTimeNs : us * 1000;
}
/// CLOCK_MONOTONIC now [us].
inline int64_t monotonic_us() { return monotonic_ns() / 1000; }
/// CLOCK_REALTIME now [us since the Unix epoch] (for heartbeats and faults).
int64_t wall_us();

/// Histogram of non-negative durations with 1 us bins up to 100 ms (and an overflow bin),
/// for exact-to-1-us percentiles over a whole run at O(1) cost per sample.
class LatencyHistogram {
 public:
  /// Adds one sample [ns]; negative values count as 0.
  void add_ns(int64_t ns);
  int64_t count() const { return count_; }
  /// Percentile in [0, 100] [us]; 0 when empty. The overflow bin reports max_us().
  double percentile_us(double pct) const;
  double max_us() const { return static_cast<double>(max_ns_) / 1000.0; }
  double mean_us() const;

 private:
  static constexpr int kBins = 100000;
  std::vector<uint32_t> bins_ = std::vector<uint32_t>(kBins + 1, 0);
  int64_t count_ = 0;
  int64_t max_ns_ = 0;
  double sum_ns_ = 0.0;
};

/// Sleeps until `deadline_ns` (CLOCK_MONOTONIC) with absolute-time semantics.
void sleep_until_ns(int64_t deadline_ns);

/// Asks the kernel for the finest timer slack (1 ns) for this thread, so that timed
/// waits wake up within microseconds of their deadline.
void use_fine_timer_slack();

}  // namespace nimble::transport
