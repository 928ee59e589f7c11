// Unit tests of the second-order reference generator with rate and acceleration limits.

#include <cmath>
#include <limits>
#include <stdexcept>

#include <catch2/catch.hpp>

#include "controller/reference_generator.h"
#include "core/constants.h"

using namespace nimble;

namespace {

constexpr double kDt = 1.0 / 512.0;
constexpr double kDeg = kPi / 180.0;

/// Unit-step response of omega^2 / (s^2 + 2 zeta omega s + omega^2), zeta < 1.
double continuous_step(double t, double omega, double zeta) {
  const double wd = omega * std::sqrt(1.0 - zeta * zeta);
  return 1.0 -
         std::exp(-zeta * omega * t) * (std::cos(wd * t) + zeta / std::sqrt(1.0 - zeta * zeta) * std::sin(wd * t));
}

}  // namespace

TEST_CASE("default parameters are the onboard int_euler values", "[reference]") {
  const ReferenceGeneratorConfig c;
  CHECK(c.omega_radps == Approx(800.0 * kDeg));
  CHECK(c.zeta == 0.85);
  CHECK(c.rate_max_radps == Approx(400.0 * kDeg));
  CHECK(c.accel_max_radps2 == Approx(8000.0 * kDeg));
  CHECK(c.setpoint_max_rad == Approx(60.0 * kDeg));
}

TEST_CASE("rate and acceleration limits hold on a large step and are reached", "[reference]") {
  const ReferenceGeneratorConfig c;
  ReferenceGenerator ref(c, kDt);
  ref.reset(-60.0 * kDeg);  // full-scale 120 deg step
  double max_rate = 0.0, max_accel = 0.0;
  for (int k = 0; k < 3 * 512; ++k) {
    const ReferenceState& s = ref.step(60.0 * kDeg);
    REQUIRE(std::fabs(s.rate_radps) <= c.rate_max_radps + 1e-12);
    REQUIRE(std::fabs(s.accel_radps2) <= c.accel_max_radps2 + 1e-9);
    max_rate = std::max(max_rate, std::fabs(s.rate_radps));
    max_accel = std::max(max_accel, std::fabs(s.accel_radps2));
  }
  // A 120 deg step asks omega^2 * 2.09 = 408 rad/s^2 and, unlimited, a peak rate of
  // about 14 rad/s: both limits must have been active.
  CHECK(max_rate == Approx(c.rate_max_radps));
  CHECK(max_accel == Approx(c.accel_max_radps2));
  CHECK(ref.state().angle_rad == Approx(60.0 * kDeg).margin(1e-6));
}

TEST_CASE("large negative step: limits hold, settles at the set-point", "[reference]") {
  const ReferenceGeneratorConfig c;
  ReferenceGenerator ref(c, kDt);
  ref.reset(40.0 * kDeg);
  double min_angle = 1e9;
  for (int k = 0; k < 3 * 512; ++k) {
    const ReferenceState& s = ref.step(-40.0 * kDeg);
    REQUIRE(std::fabs(s.rate_radps) <= c.rate_max_radps + 1e-12);
    REQUIRE(std::fabs(s.accel_radps2) <= c.accel_max_radps2 + 1e-9);
    min_angle = std::min(min_angle, s.angle_rad);
  }
  CHECK(ref.state().angle_rad == Approx(-40.0 * kDeg).margin(1e-6));
  // Overshoot of an 80 deg step stays below 2 % of the step even with the limits active.
  CHECK(min_angle > -40.0 * kDeg - 0.02 * 80.0 * kDeg);
}

TEST_CASE("small step follows the second-order response with zeta = 0.85", "[reference]") {
  const ReferenceGeneratorConfig c;
  ReferenceGenerator ref(c, kDt);
  const double step = 0.05;  // small: far from the rate and acceleration limits
  double peak = 0.0, worst_dev = 0.0;
  for (int k = 1; k <= 2 * 512; ++k) {
    const double y = ref.step(step).angle_rad;
    peak = std::max(peak, y);
    worst_dev = std::max(worst_dev, std::fabs(y / step - continuous_step(k * kDt, c.omega_radps, c.zeta)));
  }
  const double allowed_overshoot = std::exp(-kPi * c.zeta / std::sqrt(1.0 - c.zeta * c.zeta));  // 0.63 %
  CHECK(peak > step);  // underdamped: some overshoot
  CHECK((peak - step) / step <= 1.5 * allowed_overshoot);
  CHECK(worst_dev < 0.03);  // within 3 % of the step of the continuous response
  CHECK(ref.state().angle_rad == Approx(step).margin(1e-6));
  CHECK(ref.state().rate_radps == Approx(0.0).margin(1e-5));
}

TEST_CASE("set-point beyond 60 deg is clamped and counted, non-finite keeps the last", "[reference]") {
  ReferenceGenerator ref(ReferenceGeneratorConfig{}, kDt);
  for (int k = 0; k < 3 * 512; ++k) ref.step(80.0 * kDeg);
  CHECK(ref.state().angle_rad == Approx(60.0 * kDeg).margin(1e-6));
  CHECK(ref.setpoint_clamp_count() == 3 * 512);
  ref.step(std::numeric_limits<double>::quiet_NaN());
  CHECK(ref.setpoint_clamp_count() == 3 * 512 + 1);
  CHECK(std::isfinite(ref.state().angle_rad));
  CHECK(ref.state().angle_rad == Approx(60.0 * kDeg).margin(1e-6));
}

TEST_CASE("reference generator rejects bad parameters", "[reference]") {
  CHECK_THROWS_AS(ReferenceGenerator(ReferenceGeneratorConfig{}, 0.0), std::invalid_argument);
  ReferenceGeneratorConfig c;
  c.rate_max_radps = -1.0;
  CHECK_THROWS_WITH(ReferenceGenerator(c, kDt), Catch::Contains("rate_max_radps"));
}
