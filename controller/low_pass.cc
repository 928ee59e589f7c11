#include "controller/low_pass.h"

#include <cmath>
#include <complex>
#include <stdexcept>
#include <string>

#include "core/constants.h"

namespace nimble {

SecondOrderLowPass::SecondOrderLowPass(double cutoff_hz, double sample_rate_hz)
    : cutoff_hz_(cutoff_hz), sample_rate_hz_(sample_rate_hz) {
  if (!(std::isfinite(sample_rate_hz) && sample_rate_hz > 0.0)) {
    throw std::invalid_argument("low-pass: sample rate must be > 0 Hz, got " + std::to_string(sample_rate_hz));
  }
  if (!(std::isfinite(cutoff_hz) && cutoff_hz > 0.0 && cutoff_hz < 0.5 * sample_rate_hz)) {
    throw std::invalid_argument("low-pass: cut-off must be in (0, " + std::to_string(0.5 * sample_rate_hz) +
                                ") Hz (below Nyquist), got " + std::to_string(cutoff_hz));
  }
  const double k = std::tan(kPi * cutoff_hz / sample_rate_hz);
  const double q_inv = std::sqrt(2.0);
  const double n = 1.0 + q_inv * k + k * k;
  b0_ = k * k / n;
  b1_ = 2.0 * b0_;
  b2_ = b0_;
  a1_ = 2.0 * (k * k - 1.0) / n;
  a2_ = (1.0 - q_inv * k + k * k) / n;
}

double SecondOrderLowPass::step(double x) {
  if (!std::isfinite(x)) x = y_;
  const double y = b0_ * x + s1_;
  s1_ = b1_ * x - a1_ * y + s2_;
  s2_ = b2_ * x - a2_ * y;
  y_ = y;
  return y;
}

void SecondOrderLowPass::reset(double value) {
  if (!std::isfinite(value)) value = 0.0;
  // Steady state of the transposed form for constant input and output `value`.
  y_ = value;
  s2_ = b2_ * value - a2_ * value;
  s1_ = b1_ * value - a1_ * value + s2_;
}

double SecondOrderLowPass::gain_at(double f_hz) const {
  const std::complex<double> z = std::polar(1.0, 2.0 * kPi * f_hz / sample_rate_hz_);
  const std::complex<double> zi = 1.0 / z;
  const std::complex<double> num = b0_ + b1_ * zi + b2_ * zi * zi;
  const std::complex<double> den = 1.0 + a1_ * zi + a2_ * zi * zi;
  return std::abs(num / den);
}

}  // namespace nimble
