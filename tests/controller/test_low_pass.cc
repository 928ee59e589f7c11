// Unit tests of the second-order Butterworth command low-pass.

#include <cmath>
#include <stdexcept>

#include <catch2/catch.hpp>

#include "controller/low_pass.h"
#include "core/constants.h"

using namespace nimble;

namespace {

constexpr double kFs = 512.0;

/// Steady-state amplitude of the filter's response to a unit sine at f_hz, by simulation.
double simulated_gain(double f_hz, double fc_hz = 15.0) {
  SecondOrderLowPass lp(fc_hz, kFs);
  double peak = 0.0;
  const int n = static_cast<int>(4.0 * kFs);
  for (int k = 0; k < n; ++k) {
    const double y = lp.step(std::sin(2.0 * kPi * f_hz * k / kFs));
    if (k > n / 2) peak = std::max(peak, std::fabs(y));
  }
  return peak;
}

}  // namespace

TEST_CASE("low-pass has DC gain 1", "[lowpass]") {
  SecondOrderLowPass lp(15.0, kFs);
  double y = 0.0;
  for (int k = 0; k < 512; ++k) y = lp.step(2.5);
  CHECK(y == Approx(2.5).epsilon(1e-9));
  CHECK(lp.gain_at(0.0) == Approx(1.0).epsilon(1e-12));
}

TEST_CASE("low-pass is -3 dB at 15 Hz and second order above", "[lowpass]") {
  CHECK(simulated_gain(15.0) == Approx(1.0 / std::sqrt(2.0)).epsilon(0.01));
  SecondOrderLowPass lp(15.0, kFs);
  CHECK(lp.gain_at(15.0) == Approx(1.0 / std::sqrt(2.0)).epsilon(1e-9));
  // Butterworth: flat in the pass band, -40 dB/decade above the cut-off.
  CHECK(simulated_gain(3.0) == Approx(1.0).epsilon(0.01));
  const double g60 = simulated_gain(60.0);
  CHECK(g60 < 0.08);
  CHECK(g60 > 0.03);
}

TEST_CASE("low-pass reset sets a steady state, bad cut-offs throw", "[lowpass]") {
  SecondOrderLowPass lp(15.0, kFs);
  lp.reset(0.3);
  CHECK(lp.step(0.3) == Approx(0.3).epsilon(1e-12));
  CHECK(lp.step(0.3) == Approx(0.3).epsilon(1e-12));
  CHECK_THROWS_AS(SecondOrderLowPass(256.0, kFs), std::invalid_argument);
  CHECK_THROWS_AS(SecondOrderLowPass(0.0, kFs), std::invalid_argument);
  CHECK_THROWS_AS(SecondOrderLowPass(15.0, -1.0), std::invalid_argument);
}
