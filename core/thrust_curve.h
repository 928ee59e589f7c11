#pragma once
/// The Nimble's thrust against flapping frequency, thesis Eq 4.18: the one definition the
/// plant (its trim and its thrust) and the controller (its hover frequency) share.

#include <cmath>

namespace nimble {

/// Thrust of the flapping wing pairs: T = pairs * (slope * f_hz - offset) [N].
struct ThrustCurve {
  double slope_n_per_hz = 0.0114;  ///< thesis Eq 4.18
  double offset_n = 0.0449;        ///< thesis Eq 4.18
  double pairs = 2.0;              ///< two wing pairs

  /// Thrust [N] at flapping frequency `f_radps` [rad/s].
  double thrust_n(double f_radps) const {
    const double f_hz = f_radps / (2.0 * M_PI);
    return pairs * (slope_n_per_hz * f_hz - offset_n);
  }
  /// Flapping frequency [rad/s] at which the thrust is `thrust_n` [N].
  double frequency_radps(double thrust_n) const {
    const double f_hz = (thrust_n / pairs + offset_n) / slope_n_per_hz;
    return 2.0 * M_PI * f_hz;
  }
};

}  // namespace nimble
