#pragma once
/// DivergenceMonitor: decides from the innovation gate's decisions that the EKF has diverged.
///
/// A consistent filter rejects a measurement with the gate's probability q = 1 - gate_probability
/// (the NIS is chi-square distributed), independently from one measurement to the next. Over a
/// sliding window of n decisions the number of rejections is then Binomial(n, q); the monitor
/// declares divergence when it reaches the smallest k with P(Binomial(n, q) >= k) <= alpha. The
/// threshold follows from the gate and the false-alarm rate alone, not from any run.

#include <cstdint>
#include <deque>

namespace nimble {

class DivergenceMonitor {
 public:
  /// `window` decisions, gate rejection probability `q` in (0, 1), false-alarm probability per
  /// window `alpha` in (0, 1).
  /// @throws std::invalid_argument on values outside those ranges.
  DivergenceMonitor(int window, double q, double alpha);

  /// Adds one gating decision; true while the window holds at least threshold() rejections.
  bool add(bool rejected);

  int threshold() const { return threshold_; }
  int window() const { return window_; }
  int rejections_in_window() const { return rejected_; }

  /// P(Binomial(n, q) >= k).
  static double binomial_tail(int n, double q, int k);

 private:
  int window_;
  int threshold_;
  std::deque<bool> recent_;
  int rejected_ = 0;
};

}  // namespace nimble
