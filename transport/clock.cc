#include "transport/clock.h"

#include <sys/prctl.h>
#include <time.h>

#include <algorithm>
#include <cmath>
#include <cerrno>

namespace nimble::transport {

int64_t monotonic_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

int64_t wall_us() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000LL + ts.tv_nsec / 1000;
}

void LatencyHistogram::add_ns(int64_t ns) {
  ns = std::max<int64_t>(ns, 0);
  const int64_t bin = std::min<int64_t>(ns / 1000, kBins);
  ++bins_[static_cast<std::size_t>(bin)];
  ++count_;
  max_ns_ = std::max(max_ns_, ns);
  sum_ns_ += static_cast<double>(ns);
}

double LatencyHistogram::percentile_us(double pct) const {
  if (count_ == 0) return 0.0;
  const auto rank = static_cast<int64_t>(std::ceil(pct / 100.0 * static_cast<double>(count_)));
  int64_t seen = 0;
  for (int i = 0; i <= kBins; ++i) {
    seen += bins_[static_cast<std::size_t>(i)];
    if (seen >= std::max<int64_t>(rank, 1)) return i == kBins ? max_us() : static_cast<double>(i);
  }
  return max_us();
}

double LatencyHistogram::mean_us() const { return count_ == 0 ? 0.0 : sum_ns_ / static_cast<double>(count_) / 1000.0; }

void sleep_until_ns(int64_t deadline_ns) {
  timespec ts{};
  ts.tv_sec = deadline_ns / 1000000000LL;
  ts.tv_nsec = deadline_ns % 1000000000LL;
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

void use_fine_timer_slack() { prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL); }

}  // namespace nimble::transport
