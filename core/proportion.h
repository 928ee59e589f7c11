#pragma once
/// A proportion of counts with its Wilson score interval: naming rates, false-alarm rates and
/// controlled rates measured over many flights or records.

namespace nimble {

/// count of n, with its interval.
struct Proportion {
  int count = 0, n = 0;
  double p = 0.0, lo = 0.0, hi = 1.0;
};

/// count of n with its Wilson score interval at z (1.96: 95 %); n <= 0 gives p 0 in [0, 1].
Proportion wilson(int count, int n, double z = 1.959963984540054);

}  // namespace nimble
