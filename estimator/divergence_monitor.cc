#include "estimator/divergence_monitor.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace nimble {

double DivergenceMonitor::binomial_tail(int n, double q, int k) {
  if (k <= 0) return 1.0;
  if (k > n) return 0.0;
  // Sum of the pmf from k to n, in logs (lgamma) for large n.
  double tail = 0.0;
  for (int i = k; i <= n; ++i) {
    const double log_pmf = std::lgamma(n + 1.0) - std::lgamma(i + 1.0) - std::lgamma(n - i + 1.0) + i * std::log(q) +
                           (n - i) * std::log1p(-q);
    tail += std::exp(log_pmf);
  }
  return tail;
}

DivergenceMonitor::DivergenceMonitor(int window, double q, double alpha) : window_(window) {
  if (window < 1) throw std::invalid_argument("divergence window must be at least 1, got " + std::to_string(window));
  if (!(q > 0.0 && q < 1.0)) throw std::invalid_argument("gate rejection probability must be in (0, 1)");
  if (!(alpha > 0.0 && alpha < 1.0)) throw std::invalid_argument("false-alarm probability must be in (0, 1)");
  threshold_ = window + 1;  // never, if even a full window of rejections is not rare enough
  for (int k = 1; k <= window; ++k) {
    if (binomial_tail(window, q, k) <= alpha) {
      threshold_ = k;
      break;
    }
  }
}

bool DivergenceMonitor::add(bool rejected) {
  recent_.push_back(rejected);
  rejected_ += rejected ? 1 : 0;
  if (static_cast<int>(recent_.size()) > window_) {
    rejected_ -= recent_.front() ? 1 : 0;
    recent_.pop_front();
  }
  return rejected_ >= threshold_;
}

}  // namespace nimble
