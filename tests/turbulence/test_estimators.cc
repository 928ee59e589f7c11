// PSD and variance estimates and their stated uncertainties, checked on seeded records and by
// Monte Carlo over seeds.

#include <cmath>
#include <random>
#include <vector>

#include <catch2/catch.hpp>

#include "test_support.h"
#include "turbulence/ce500_analysis.h"
#include "turbulence/discretisation.h"
#include "turbulence/dryden.h"
#include "turbulence/lyapunov.h"
#include "turbulence/spectral_estimates.h"
#include "turbulence/uncertainty.h"

using namespace nimble::turbulence;

namespace {

Eigen::VectorXd white(std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::VectorXd x(static_cast<Eigen::Index>(n));
  for (Eigen::Index i = 0; i < x.size(); ++i) x[i] = normal(rng);
  return x;
}

double spread(const std::vector<double>& xs) {
  double mean = 0.0;
  for (const double x : xs) mean += x;
  mean /= static_cast<double>(xs.size());
  double s = 0.0;
  for (const double x : xs) s += (x - mean) * (x - mean);
  return std::sqrt(s / static_cast<double>(xs.size() - 1));
}

}  // namespace

TEST_CASE("Periodogram integral equals the 1/N sample variance and Welch the window-weighted mean square",
          "[turbulence][estimates]") {
  const Eigen::VectorXd x = white(3000, 3).array() + 5.0;  // a mean to remove; 3000 is not a power of two
  const double dt = 0.02;
  const SpectralEstimate p = periodogram(x, dt);
  CHECK(p.segment_length == 4096);
  CHECK(variance_from_estimate(p) == Approx(sample_variance(x) * 2999.0 / 3000.0).epsilon(1e-12));
  const SpectralEstimate w = welch(x, dt, 256);
  CHECK(w.segments == (3000 - 256) / 128 + 1);
  const Eigen::VectorXd q = welch_variance_weights(3000, 256);
  CHECK(q.sum() == Approx(1.0).epsilon(1e-12));
  const Eigen::VectorXd centred = x.array() - x.mean();
  CHECK(variance_from_estimate(w) == Approx(q.dot(centred.cwiseAbs2())).epsilon(1e-12));
  // Two-sided convention: white noise of variance 1 sampled at dt has S = dt at every frequency.
  CHECK(w.psd.segment(1, w.psd.size() - 2).mean() == Approx(dt).epsilon(0.05));
}

TEST_CASE("The sample-variance uncertainty formula holds by Monte Carlo over seeds", "[turbulence][estimates]") {
  const ShapingFilter f = time_based_second_order(1.0, 1.0);
  const Eigen::VectorXd W = Eigen::VectorXd::Ones(1);
  const Eigen::MatrixXd P = stationary_covariance(f.system, W);
  const double dt = 0.1;
  const std::size_t N = 2000;  // 200 s, about 200 correlation times
  const DiscreteModel d = discretise(f.system, W, dt);
  const Eigen::VectorXd R = sampled_autocovariance(d.Phi, P, f.system.C.row(0), N);
  const double sd_sample = quadratic_estimate_std(sample_variance_weights(N), R);
  const double sd_welch = quadratic_estimate_std(welch_variance_weights(N, 256), R);
  const double sd_psd = sample_variance_std_from_psd(f.psd, static_cast<double>(N) * dt);
  std::vector<double> s2, wv;
  const int seeds = 400;
  for (int seed = 0; seed < seeds; ++seed) {
    const Eigen::VectorXd x = (simulate_stationary(d, P, N, 1000 + seed) * f.system.C.transpose()).col(0);
    s2.push_back(sample_variance(x));
    wv.push_back(variance_from_estimate(welch(x, dt, 256)));
  }
  INFO("formula " << sd_sample << ", PSD approximation " << sd_psd << ", Monte Carlo " << spread(s2));
  // The spread estimated from 400 seeds has a relative standard error of about 1/sqrt(800) = 3.5 %.
  CHECK(spread(s2) == Approx(sd_sample).epsilon(0.12));
  CHECK(spread(wv) == Approx(sd_welch).epsilon(0.12));
  CHECK(sd_psd == Approx(sd_sample).epsilon(0.05));
  double mean = 0.0;
  for (const double v : s2) mean += v / seeds;
  CHECK(std::abs(mean - 1.0) < 4.0 * sd_sample / std::sqrt(static_cast<double>(seeds)));
  // A white sequence: the textbook 2 sigma^4 / (N - 1).
  const double sd_white = quadratic_estimate_std(sample_variance_weights(N), Eigen::VectorXd::Ones(1));
  CHECK(sd_white == Approx(std::sqrt(2.0 * N) / (N - 1.0)).epsilon(1e-9));
}

TEST_CASE("Welch bins have the stated degrees of freedom by Monte Carlo", "[turbulence][estimates]") {
  const std::size_t N = 4096, M = 256;
  const int seeds = 200;
  const double dt = 1.0;
  double sum_rel_var = 0.0;
  int count = 0;
  for (int seed = 0; seed < seeds; ++seed) {
    const SpectralEstimate e = welch(white(N, 500 + seed), dt, M);
    for (Eigen::Index k = 8; k < 120; ++k) {
      const double r = e.psd[k] / dt - 1.0;  // S = dt for unit-variance white samples
      sum_rel_var += r * r;
      ++count;
    }
  }
  const SpectralEstimate e = welch(white(N, 1), dt, M);
  const double predicted = 2.0 / e.dof;
  INFO("dof " << e.dof << ", segments " << e.segments);
  CHECK(e.dof == Approx(2.0 * e.segments / (1.0 + 2.0 / 36.0 * (1.0 - 1.0 / e.segments))).epsilon(1e-3));
  CHECK(sum_rel_var / count == Approx(predicted).epsilon(0.1));
}

TEST_CASE("Ce500 variances from a long seeded record agree with Lyapunov within each stated uncertainty",
          "[turbulence][estimates]") {
  Ce500Options o = ce500_default_options(nimble::turbulence::test::practical());
  o.duration_s = 3000.0;
  o.seed = 11;
  const Ce500Analysis a = analyse_ce500(nimble::turbulence::test::practical(), o);
  for (const SystemAnalysis* s : {&a.controlled, &a.reduced}) {
    for (std::size_t i = 0; i < s->variances.size(); ++i) {
      const OutputVariances& v = s->variances[i];
      INFO(s->key << " output " << i << ": lyapunov " << v.lyapunov.value);
      CHECK(std::abs(v.analytical_psd.value - v.lyapunov.value) < 1e-6 * v.lyapunov.value);
      for (const VarianceEstimate* e : {&v.periodogram, &v.welch, &v.sample}) {
        INFO("estimate " << e->value << " +- " << e->sigma);
        CHECK(e->sigma > 0.0);
        CHECK(e->sigma < 0.3 * v.lyapunov.value);
        CHECK(std::abs(e->value - v.lyapunov.value) < 4.0 * e->sigma);
      }
      // The continuous-time approximation of the sample variance's spread.
      CHECK(v.sample_sigma_from_psd == Approx(v.sample.sigma).epsilon(0.1));
    }
  }
}
