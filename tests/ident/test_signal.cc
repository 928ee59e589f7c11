// Unit tests of resampling, the zero-phase Butterworth low-pass and the differentiator.

#include <cmath>
#include <vector>

#include <catch2/catch.hpp>

#include "ident/signal.h"

using namespace nimble::ident;

namespace {

Eigen::VectorXd sine(double f_hz, double rate_hz, Eigen::Index n, double phase_rad = 0.0) {
  Eigen::VectorXd x(n);
  for (Eigen::Index k = 0; k < n; ++k)
    x[k] = std::sin(2.0 * M_PI * f_hz * static_cast<double>(k) / rate_hz + phase_rad);
  return x;
}

/// Amplitude and phase of the f_hz component of x[a, b) by least squares on sin and cos.
std::pair<double, double> amplitude_phase(const Eigen::VectorXd& x, double f_hz, double rate_hz, Eigen::Index a,
                                          Eigen::Index b) {
  Eigen::MatrixXd X(b - a, 2);
  for (Eigen::Index k = a; k < b; ++k) {
    const double w = 2.0 * M_PI * f_hz * static_cast<double>(k) / rate_hz;
    X(k - a, 0) = std::sin(w);
    X(k - a, 1) = std::cos(w);
  }
  const Eigen::Vector2d c = X.colPivHouseholderQr().solve(x.segment(a, b - a));
  return {std::hypot(c[0], c[1]), std::atan2(c[1], c[0])};
}

/// A channel sampled at `rate_hz`: stamps t_k = k / rate_hz and values f(t_k), k = 0..last.
template <typename F>
Channel sampled(double rate_hz, int last, F f) {
  Channel c;
  for (int k = 0; k <= last; ++k) {
    c.t_s.push_back(k / rate_hz);
    c.values.push_back(f(c.t_s.back()));
  }
  return c;
}

}  // namespace

TEST_CASE("resampling interpolates linearly onto the common grid of all channels", "[signal]") {
  FlightData d;
  d.source = "multi-rate";
  // p at irregular stamps from 0.1 s, v at 200 Hz from 0 s; both linear in time.
  std::vector<double> tp{0.1, 0.13, 0.2, 0.45, 0.5, 1.0, 1.7};
  std::vector<double> tv;
  for (int k = 0; k <= 300; ++k) tv.push_back(k / 200.0);
  const auto lin = [](double t) { return 3.0 * t - 1.0; };
  std::vector<double> vp, vv;
  for (double t : tp) vp.push_back(lin(t));
  for (double t : tv) vv.push_back(2.0 * lin(t));
  d.channels["p"] = Channel{tp, vp};
  d.channels["v"] = Channel{tv, vv};
  const UniformData u = resample_uniform(d, 100.0, Interpolation::kLinear);
  CHECK(u.t_s[0] == Approx(0.1));             // latest first stamp
  CHECK(u.t_s[u.size() - 1] <= 1.5 + 1e-12);  // earliest last stamp
  CHECK(u.t_s[u.size() - 1] == Approx(1.5));
  CHECK(u.size() == 141);
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    CHECK(u.at("p")[k] == Approx(lin(u.t_s[k])).margin(1e-12));
    CHECK(u.at("v")[k] == Approx(2.0 * lin(u.t_s[k])).margin(1e-12));
  }
  CHECK_THROWS_AS(resample_uniform(d, 0.0), std::invalid_argument);
  CHECK_THROWS_AS(resample_uniform(d, -5.0), std::invalid_argument);
  // The cubic default is exact for straight lines too.
  const UniformData c = resample_uniform(d, 100.0);
  for (Eigen::Index k = 0; k < c.size(); ++k) CHECK(c.at("p")[k] == Approx(lin(c.t_s[k])).margin(1e-12));
}

TEST_CASE("cubic resampling: exact for quadratics on uneven stamps, keeps samples, upsamples 100 Hz data", "[signal]") {
  SECTION("quadratics on uneven stamps and samples on the grid") {
    FlightData d;
    d.source = "quadratic";
    std::vector<double> tp{0.0, 0.013, 0.02, 0.045, 0.05, 0.1, 0.17, 0.2, 0.31, 0.33, 0.4};
    const auto quad = [](double t) { return 5.0 * t * t - 2.0 * t + 0.3; };
    std::vector<double> vp;
    for (double t : tp) vp.push_back(quad(t));
    d.channels["p"] = Channel{tp, vp};
    // v: arbitrary values on a 200 Hz grid that the output grid hits exactly.
    std::vector<double> tv, vv;
    for (int k = 0; k <= 80; ++k) {
      tv.push_back(k / 200.0);
      vv.push_back(std::cos(7.3 * k) + 0.1 * k);
    }
    d.channels["v"] = Channel{tv, vv};
    const UniformData cubic = resample_uniform(d, 200.0, Interpolation::kCubic);
    const UniformData linear = resample_uniform(d, 200.0, Interpolation::kLinear);
    REQUIRE(cubic.size() == 81);
    double linear_worst = 0.0;
    for (Eigen::Index k = 0; k < cubic.size(); ++k) {
      const double t = cubic.t_s[k];
      CHECK(cubic.at("p")[k] == Approx(quad(t)).margin(1e-12));
      linear_worst = std::max(linear_worst, std::fabs(linear.at("p")[k] - quad(t)));
      CHECK(cubic.at("v")[k] == Approx(vv[static_cast<std::size_t>(k)]).margin(1e-12));
      CHECK(linear.at("v")[k] == Approx(vv[static_cast<std::size_t>(k)]).margin(1e-12));
    }
    CHECK(linear_worst > 1e-3);  // the straight lines cut the parabola's corners
  }
  SECTION("a 5 Hz sine sampled at 100 Hz: linear attenuates it by sinc^2, cubic by (w h)^4 / 80") {
    FlightData d;
    d.source = "100 Hz";
    d.channels["delta_f"] = sampled(100.0, 1000, [](double t) { return std::sin(2.0 * M_PI * 5.0 * t + 0.3); });
    const double wh = 2.0 * M_PI * 5.0 / 100.0;
    const double sinc2 = std::pow(std::sin(wh / 2.0) / (wh / 2.0), 2);  // 0.99180
    for (Interpolation how : {Interpolation::kLinear, Interpolation::kCubic}) {
      INFO(to_string(how));
      const UniformData u = resample_uniform(d, 512.0, how);
      // In-phase gain: projection on the true sine over the middle 8 s.
      double num = 0.0, den = 0.0;
      for (Eigen::Index k = 512; k < 9 * 512; ++k) {
        const double truth = std::sin(2.0 * M_PI * 5.0 * u.t_s[k] + 0.3);
        num += u.at("delta_f")[k] * truth;
        den += truth * truth;
      }
      const double gain = num / den;
      if (how == Interpolation::kLinear) {
        CHECK(gain == Approx(sinc2).margin(3e-4));
      } else {
        CHECK(std::fabs(1.0 - gain) < 3e-4);
        CHECK(std::fabs(1.0 - gain) == Approx(std::pow(wh, 4) / 80.0).epsilon(0.25));
      }
    }
  }
  SECTION("a step overshoots by at most 7.4 % next to it, except a set-point") {
    FlightData d;
    d.source = "step";
    std::vector<double> t, y;
    for (int k = 0; k <= 20; ++k) {
      t.push_back(k / 100.0);
      y.push_back(k < 10 ? 0.0 : 1.0);
    }
    d.channels["delta_t"] = Channel{t, y};
    d.channels["phi_sp"] = Channel{t, y};
    const UniformData u = resample_uniform(d, 12800.0);
    CHECK(u.at("delta_t").minCoeff() == Approx(-2.0 / 27.0).margin(1e-4));
    CHECK(u.at("delta_t").maxCoeff() == Approx(1.0 + 2.0 / 27.0).margin(1e-4));
    for (Eigen::Index k = 0; k < u.size(); ++k) {
      if (u.t_s[k] < 0.08 - 1e-9 || u.t_s[k] > 0.11 + 1e-9)
        CHECK(u.at("delta_t")[k] == Approx(y[u.t_s[k] < 0.1 ? 0 : 20]));
    }
    // The set-point, a step by nature, is interpolated linearly: no overshoot.
    CHECK(is_set_point("phi_sp"));
    CHECK_FALSE(is_set_point("delta_t"));
    CHECK(u.at("phi_sp").minCoeff() == 0.0);
    CHECK(u.at("phi_sp").maxCoeff() == 1.0);
    CHECK(u.at("phi_sp")[1216] == Approx(0.5));  // t = 0.095 s, half-way up the step
  }
  CHECK(interpolation_from_string("cubic") == Interpolation::kCubic);
  CHECK(interpolation_from_string("linear") == Interpolation::kLinear);
  CHECK_THROWS_WITH(interpolation_from_string("spline"), Catch::Contains("'spline'"));
}

TEST_CASE("Butterworth sections reproduce the analytic magnitude of the bilinear design", "[signal]") {
  for (int order : {1, 2, 5, 10}) {
    for (double fc : {9.0, 12.0, 60.0}) {
      const auto sos = butterworth_lowpass(order, fc, 512.0);
      CHECK(sos.size() == static_cast<std::size_t>((order + 1) / 2));
      CHECK(std::abs(frequency_response(sos, 0.0, 512.0)) == Approx(1.0).epsilon(1e-12));
      // -3 dB at the cut-off: pre-warping puts it exactly there.
      CHECK(std::norm(frequency_response(sos, fc, 512.0)) == Approx(0.5).epsilon(1e-9));
      for (double f : {0.5, 3.0, 8.0, 11.0, 20.0, 100.0, 250.0}) {
        INFO("order " << order << " fc " << fc << " f " << f);
        const double analytic = butterworth_magnitude_squared(order, fc, 512.0, f);
        CHECK(std::norm(frequency_response(sos, f, 512.0)) == Approx(analytic).epsilon(1e-8).margin(1e-15));
      }
    }
  }
  CHECK_THROWS_AS(butterworth_lowpass(0, 9.0, 512.0), std::invalid_argument);
  CHECK_THROWS_AS(butterworth_lowpass(10, 256.0, 512.0), std::invalid_argument);
  CHECK_THROWS_AS(butterworth_lowpass(10, 0.0, 512.0), std::invalid_argument);
}

TEST_CASE("filtfilt attenuates sines by |H|^2 of the Butterworth and does not shift them", "[signal]") {
  const double rate = 512.0, fc = 9.0;
  const int order = 10;
  const auto sos = butterworth_lowpass(order, fc, rate);
  const Eigen::Index n = 8 * 512;
  for (double f : {2.0, 6.0, 9.0, 11.0, 13.0}) {
    INFO("f = " << f << " Hz");
    const double phase = 0.7;  // a delayed sine
    const Eigen::VectorXd x = sine(f, rate, n, phase);
    const Eigen::VectorXd y = filtfilt(sos, x, default_padding(fc, rate));
    const auto [amp, ph] = amplitude_phase(y, f, rate, n / 4, 3 * n / 4);
    const double expected = butterworth_magnitude_squared(order, fc, rate, f);  // forward-backward: |H|^2
    CHECK(amp == Approx(expected).margin(2e-4));
    if (expected > 1e-2) CHECK(std::remainder(ph - phase, 2.0 * M_PI) == Approx(0.0).margin(1e-4));
  }
  // The causal filter, by contrast, delays: the check above can fail.
  const Eigen::VectorXd x = sine(4.0, rate, n, 0.7);
  const auto [amp, ph] = amplitude_phase(sosfilt(sos, x, true), 4.0, rate, n / 4, 3 * n / 4);
  CHECK(std::fabs(std::remainder(ph - 0.7, 2.0 * M_PI)) > 0.3);
  CHECK(amp == Approx(std::sqrt(butterworth_magnitude_squared(order, fc, rate, 4.0))).margin(1e-3));
}

TEST_CASE("filtfilt keeps slow signals at the edges (odd reflection, steady start)", "[signal]") {
  const auto sos = butterworth_lowpass(10, 9.0, 512.0);
  const Eigen::Index n = 2048;
  Eigen::VectorXd ramp(n), constant = Eigen::VectorXd::Constant(n, 3.5);
  for (Eigen::Index k = 0; k < n; ++k) ramp[k] = 2.0 + 0.5 * static_cast<double>(k) / 512.0;
  const Eigen::VectorXd yc = filtfilt(sos, constant, default_padding(9.0, 512.0));
  CHECK((yc - constant).cwiseAbs().maxCoeff() < 1e-12);
  const Eigen::VectorXd yr = filtfilt(sos, ramp, default_padding(9.0, 512.0));
  CHECK((yr - ramp).cwiseAbs().maxCoeff() < 5e-5);  // the ramp rises by 2 over the record
  // Without padding the ends are visibly off: the padding is what keeps them.
  const Eigen::VectorXd y0 = filtfilt(sos, ramp, 0);
  CHECK((y0 - ramp).cwiseAbs().maxCoeff() > 1e-3);
  CHECK_THROWS_AS(filtfilt(sos, Eigen::VectorXd::Zero(1), 10), std::invalid_argument);
}

TEST_CASE("the differentiator recovers the derivative of a sine and is exact for quartics", "[signal]") {
  const double rate = 512.0, f = 3.0, w = 2.0 * M_PI * f;
  const Eigen::Index n = 1024;
  const Eigen::VectorXd x = sine(f, rate, n, 0.3);
  const Eigen::VectorXd d = differentiate(x, rate);
  double interior = 0.0, edge = 0.0;
  for (Eigen::Index k = 0; k < n; ++k) {
    const double exact = w * std::cos(w * static_cast<double>(k) / rate + 0.3);
    const double err = std::fabs(d[k] - exact) / w;
    (k >= 2 && k + 2 < n ? interior : edge) = std::max(k >= 2 && k + 2 < n ? interior : edge, err);
  }
  CHECK(interior < 1e-6);  // fourth order: (w dt)^4 / 30 = 6e-8
  CHECK(edge < 2e-3);      // second-order stencils at the ends
  Eigen::VectorXd q(50);
  for (Eigen::Index k = 0; k < q.size(); ++k) {
    const double t = static_cast<double>(k) / rate;
    q[k] = 1.0 + 2.0 * t - 3.0 * t * t + 4.0 * t * t * t - 5.0 * t * t * t * t;
  }
  const Eigen::VectorXd dq = differentiate(q, rate);
  for (Eigen::Index k = 2; k + 2 < q.size(); ++k) {
    const double t = static_cast<double>(k) / rate;
    CHECK(dq[k] == Approx(2.0 - 6.0 * t + 12.0 * t * t - 20.0 * t * t * t).epsilon(1e-9));
  }
  CHECK_THROWS_AS(differentiate(Eigen::VectorXd::Zero(1), rate), std::invalid_argument);
}

TEST_CASE("process() resamples then filters every channel", "[signal]") {
  FlightData d;
  d.source = "two tones";
  d.channels["p"] =
      sampled(1000.0, 3999, [](double t) { return std::sin(2.0 * M_PI * 2.0 * t) + std::sin(2.0 * M_PI * 40.0 * t); });
  ProcessingOptions o;  // 512 Hz, order 10, 9 Hz
  const UniformData u = process(d, o);
  CHECK(u.rate_hz == 512.0);
  // The 40 Hz tone is gone, the 2 Hz tone passes unchanged (|H(2 Hz)|^2 = 1 - 1e-13).
  double worst = 0.0;
  for (Eigen::Index k = 500; k < 1500; ++k) {
    worst = std::max(worst, std::fabs(u.at("p")[k] - std::sin(2.0 * M_PI * 2.0 * u.t_s[k])));
  }
  CHECK(worst < 2e-3);
  o.cutoff_hz = 300.0;
  CHECK_THROWS_AS(process(d, o), std::invalid_argument);
}
