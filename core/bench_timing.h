#pragma once
/// Timing helpers of the benchmarks (header-only): thread CPU time, elapsed wall time, and
/// the median, minimum and maximum over repetitions.

#include <time.h>

#include <algorithm>
#include <chrono>
#include <vector>

namespace nimble {

/// CPU time of this thread [ms]: unlike wall time, not inflated by other processes.
inline double thread_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return 1e3 * static_cast<double>(ts.tv_sec) + 1e-6 * static_cast<double>(ts.tv_nsec);
}

/// Wall time from t0 to t1 [ms].
inline double elapsed_ms(std::chrono::steady_clock::time_point t0, std::chrono::steady_clock::time_point t1) {
  return std::chrono::duration<double, std::milli>(t1 - t0).count();
}

/// Median of the repetitions (the upper one of an even count). `xs` must not be empty.
inline double median(std::vector<double> xs) {
  std::sort(xs.begin(), xs.end());
  return xs[xs.size() / 2];
}

/// Median, minimum and maximum of the repetitions.
struct TimingSpread {
  double median = 0.0;
  double min = 0.0;
  double max = 0.0;
};

/// The spread of `xs`, which must not be empty.
inline TimingSpread timing_spread(const std::vector<double>& xs) {
  return {median(xs), *std::min_element(xs.begin(), xs.end()), *std::max_element(xs.begin(), xs.end())};
}

}  // namespace nimble
