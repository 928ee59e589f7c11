// Unit tests of the FFT, the periodogram and Welch PSD scaling (Parseval) and the autocorrelation.

#include <cmath>
#include <complex>
#include <random>
#include <vector>

#include <catch2/catch.hpp>

#include "ident/spectrum.h"

using namespace nimble::ident;

namespace {

Eigen::VectorXd white(Eigen::Index n, double sd, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> nd(0.0, sd);
  Eigen::VectorXd x(n);
  for (auto& v : x) v = nd(rng);
  return x;
}

double variance(const Eigen::VectorXd& x) { return (x.array() - x.mean()).square().mean(); }

}  // namespace

TEST_CASE("radix-2 FFT equals the direct DFT", "[spectrum]") {
  const Eigen::VectorXd x = white(64, 1.0, 3);
  std::vector<std::complex<double>> buf(x.data(), x.data() + x.size());
  fft_radix2(buf);
  for (int k = 0; k < 64; ++k) {
    std::complex<double> direct = 0.0;
    for (int n = 0; n < 64; ++n) direct += x[n] * std::polar(1.0, -2.0 * M_PI * k * n / 64.0);
    CHECK(std::abs(buf[static_cast<std::size_t>(k)] - direct) < 1e-12);
  }
  std::vector<std::complex<double>> odd(48);
  CHECK_THROWS_AS(fft_radix2(odd), std::invalid_argument);
}

TEST_CASE("periodogram: one-sided units^2/Hz, integral equals the variance exactly", "[spectrum]") {
  const double rate = 512.0;
  const Eigen::VectorXd x = white(1000, 0.7, 5).array() + 3.0;  // not a power of two, non-zero mean
  const Psd p = periodogram(x, rate);
  CHECK(p.integral() == Approx(variance(x)).epsilon(1e-10));
  CHECK(p.f_hz[p.f_hz.size() - 1] == Approx(rate / 2));
  CHECK(p.psd[0] == Approx(0.0).margin(1e-20));  // mean removed

  // A sine of amplitude A: power A^2/2, concentrated at its frequency.
  Eigen::VectorXd s(2048);
  for (Eigen::Index k = 0; k < s.size(); ++k) s[k] = 1.5 * std::sin(2.0 * M_PI * 32.0 * static_cast<double>(k) / rate);
  const Psd ps = periodogram(s, rate);
  Eigen::Index peak = 0;
  ps.psd.maxCoeff(&peak);
  CHECK(ps.f_hz[peak] == Approx(32.0));
  CHECK(ps.integral() == Approx(1.5 * 1.5 / 2).epsilon(1e-9));
  CHECK(ps.integral_up_to(30.0) < 1e-20);
}

TEST_CASE("Welch: Hann, 50 % overlap, white-noise level 2 var / rate, integral the variance", "[spectrum]") {
  const double rate = 512.0, sd = 2.0;
  const Eigen::VectorXd x = white(64 * 1024, sd, 11);
  const Psd p = welch(x, rate, 1024);
  CHECK(p.df_hz == Approx(0.5));
  CHECK(p.segments == 127);  // (65536 - 1024) / 512 + 1
  CHECK(p.integral() == Approx(sd * sd).epsilon(0.02));
  const double level = p.psd.segment(10, p.psd.size() - 20).mean();
  CHECK(level == Approx(2.0 * sd * sd / rate).epsilon(0.02));

  Eigen::VectorXd s(8192);
  for (Eigen::Index k = 0; k < s.size(); ++k) s[k] = 0.8 * std::sin(2.0 * M_PI * 20.25 * static_cast<double>(k) / rate);
  const Psd ps = welch(s, rate, 1000);  // rounded down to 512 samples
  CHECK(ps.df_hz == Approx(1.0));
  CHECK(ps.integral() == Approx(0.8 * 0.8 / 2).epsilon(0.01));
  CHECK_THROWS_AS(welch(s, rate, 4), std::invalid_argument);
}

TEST_CASE("Welch over ranges uses only those samples", "[spectrum]") {
  const double rate = 512.0;
  Eigen::VectorXd x = white(8192, 0.1, 2);
  x.segment(4096, 4096) = white(4096, 1.0, 3);  // loud second half
  const Psd quiet = welch(x, rate, 512, {{0, 4096}});
  const Psd loud = welch(x, rate, 512, {{4096, 8192}});
  const Psd both = welch(x, rate, 512, {{100, 2100}, {5000, 7000}});
  CHECK(quiet.integral() == Approx(0.01).epsilon(0.1));
  CHECK(loud.integral() == Approx(1.0).epsilon(0.1));
  CHECK(both.integral() == Approx(0.505).epsilon(0.15));
  CHECK_THROWS_AS(welch(x, rate, 512, {{0, 4}}), std::invalid_argument);
}

TEST_CASE("autocorrelation: 1 at lag 0, a^k for an AR(1) process", "[spectrum]") {
  const Eigen::VectorXd e = white(200000, 1.0, 9);
  Eigen::VectorXd x(e.size());
  x[0] = e[0];
  for (Eigen::Index k = 1; k < x.size(); ++k) x[k] = 0.8 * x[k - 1] + e[k];
  const Eigen::VectorXd rho = autocorrelation(x, 5);
  REQUIRE(rho.size() == 6);
  CHECK(rho[0] == 1.0);
  for (int k = 1; k <= 5; ++k) CHECK(rho[k] == Approx(std::pow(0.8, k)).margin(0.01));
  const Eigen::VectorXd rw = autocorrelation(e, 3);
  for (int k = 1; k <= 3; ++k) CHECK(std::fabs(rw[k]) < 0.01);
}
