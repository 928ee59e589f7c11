#pragma once
/// Timing helpers of the benchmarks (header-only): thread CPU time, elapsed wall time, and
/// the median, minimum and maximum over repetitions.

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace nimble {

/// The command line of a benchmark that takes one optional argument, its repetitions:
/// `--help` prints `usage` on stdout and the benchmark exits 0; anything but a whole number >= 1
/// prints it on stderr and exits 2. Returns the repetitions, or -(exit code + 1) to exit.
inline int bench_repetitions(int argc, char** argv, const char* usage, int fallback) {
  if (argc < 2) return fallback;
  const std::string a = argv[1];
  if (a == "--help" || a == "-h") {
    std::fputs(usage, stdout);
    return -1;
  }
  char* end = nullptr;
  const long n = std::strtol(a.c_str(), &end, 10);
  if (argc > 2 || end == a.c_str() || *end != '\0' || n < 1 || n > 1000000) {
    std::fprintf(stderr, "%s: '%s' is not a number of repetitions\n%s", argv[0], a.c_str(), usage);
    return -3;
  }
  return static_cast<int>(n);
}

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
