#pragma once
/// Discrete second-order Butterworth low-pass filter for the attitude commands
/// (15 Hz on roll and pitch, as the onboard stabilisation).
///
/// Bilinear (Tustin) transform of H(s) = wc^2 / (s^2 + sqrt(2) wc s + wc^2)
/// with the cut-off pre-warped, K = tan(pi fc / fs), so that the discrete
/// filter has exactly -3 dB at fc:
///   b0 = K^2 / n, b1 = 2 b0, b2 = b0, a1 = 2 (K^2 - 1) / n, a2 = (1 - sqrt(2) K + K^2) / n,
///   n = 1 + sqrt(2) K + K^2;  y[k] = b0 x[k] + b1 x[k-1] + b2 x[k-2] - a1 y[k-1] - a2 y[k-2].

namespace nimble {

/// Coefficients of the difference equation
/// y[k] = b0 x[k] + b1 x[k-1] + b2 x[k-2] - a1 y[k-1] - a2 y[k-2].
struct LowPassCoefficients {
  double b0, b1, b2, a1, a2;
};

/// Second-order Butterworth low-pass, direct form II transposed.
class SecondOrderLowPass {
 public:
  /// @throws std::invalid_argument unless 0 < cutoff_hz < sample_rate_hz / 2 (both finite).
  SecondOrderLowPass(double cutoff_hz, double sample_rate_hz);

  /// Filters one sample (any unit; the output has the unit of the input). Never throws;
  /// a non-finite input is replaced by the previous output.
  double step(double x);

  /// Sets the filter to steady state at `value` (output and internal state).
  void reset(double value = 0.0);

  /// Last output.
  double output() const { return y_; }
  /// Cut-off frequency [Hz].
  double cutoff_hz() const { return cutoff_hz_; }
  /// Sample rate [Hz].
  double sample_rate_hz() const { return sample_rate_hz_; }
  /// Gain |H(e^{j 2 pi f / fs})| of the discrete filter at `f_hz` [-].
  double gain_at(double f_hz) const;
  /// Coefficients of the difference equation (for linear analyses of the loops).
  LowPassCoefficients coefficients() const { return {b0_, b1_, b2_, a1_, a2_}; }

 private:
  double cutoff_hz_, sample_rate_hz_;
  double b0_, b1_, b2_, a1_, a2_;
  double s1_ = 0.0, s2_ = 0.0;  // transposed direct-form state
  double y_ = 0.0;
};

}  // namespace nimble
