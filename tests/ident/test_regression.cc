// Unit tests of the regression: closed forms on hand-sized examples, Monte
// Carlo checks of the standard deviations, errors.

#include <cmath>
#include <random>
#include <vector>

#include <catch2/catch.hpp>

#include "ident/regression.h"

using namespace nimble::ident;

namespace {

Eigen::VectorXd vec(std::initializer_list<double> xs) {
  Eigen::VectorXd v(static_cast<Eigen::Index>(xs.size()));
  Eigen::Index i = 0;
  for (double x : xs) v[i++] = x;
  return v;
}

Equation equation(const std::string& name, const std::string& dependent, std::vector<std::string> regressors,
                  double scale = 1.0) {
  Equation e;
  e.name = name;
  e.dependent = dependent;
  e.scale = scale;
  e.regressors = regressors;
  for (const auto& r : regressors) e.parameters.push_back(name + "_" + r);
  return e;
}

struct Spread {
  double mean = 0.0;
  double sd = 0.0;
};

Spread spread(const std::vector<double>& xs) {
  Spread s;
  for (double x : xs) s.mean += x;
  s.mean /= static_cast<double>(xs.size());
  for (double x : xs) s.sd += (x - s.mean) * (x - s.mean);
  s.sd = std::sqrt(s.sd / static_cast<double>(xs.size() - 1));
  return s;
}

double mean(const std::vector<double>& xs) { return spread(xs).mean; }

}  // namespace

TEST_CASE("OLS of a hand-sized straight-line fit equals the closed form", "[regression]") {
  SignalTable s;
  s["one"] = Eigen::VectorXd::Ones(5);
  s["x"] = vec({0, 1, 2, 3, 4});
  s["y"] = vec({1.1, 2.9, 5.2, 6.8, 9.1});
  const RegressionResult r = estimate_ols(s, {equation("E", "y", {"one", "x"})});
  // Closed form: b = Sxy / Sxx, a = ybar - b xbar, s^2 = RSS / (n - 2).
  const double n = 5, xbar = 2, ybar = (1.1 + 2.9 + 5.2 + 6.8 + 9.1) / 5, sxx = 10;
  const double sxy = -2 * (1.1 - ybar) - 1 * (2.9 - ybar) + 0 + 1 * (6.8 - ybar) + 2 * (9.1 - ybar);
  const double b = sxy / sxx, a = ybar - b * xbar;
  double rss = 0;
  for (int i = 0; i < 5; ++i) rss += std::pow(s["y"][i] - a - b * i, 2);
  const double s2 = rss / (n - 2);
  const EquationResult& e = r.equation("E");
  CHECK(e.theta[0] == Approx(a).epsilon(1e-12));
  CHECK(e.theta[1] == Approx(b).epsilon(1e-12));
  CHECK(e.residual_variance == Approx(s2).epsilon(1e-12));
  CHECK(e.sigma[1] == Approx(std::sqrt(s2 / sxx)).epsilon(1e-12));
  CHECK(e.sigma[0] == Approx(std::sqrt(s2 * (1 / n + xbar * xbar / sxx))).epsilon(1e-12));
  CHECK(e.covariance(0, 1) == Approx(-xbar * s2 / sxx).epsilon(1e-12));
  CHECK(e.correlation(0, 1) == Approx(-xbar * s2 / sxx / (e.sigma[0] * e.sigma[1])).epsilon(1e-12));
  CHECK(r.parameters().at("E_x").value == Approx(b).epsilon(1e-12));
  // The scale multiplies the dependent signal: 2 y gives twice the parameters.
  const RegressionResult r2 = estimate_ols(s, {equation("E", "y", {"one", "x"}, 2.0)});
  CHECK(r2.equation("E").theta[1] == Approx(2 * b).epsilon(1e-12));
}

TEST_CASE("WLS of one equation with given weights equals sum w x y / sum w x^2", "[regression]") {
  SignalTable s;
  s["x"] = vec({1, 2, 3, 4});
  s["y"] = vec({1.2, 1.8, 3.5, 3.7});
  const std::vector<double> w{4.0, 1.0, 0.25, 2.0};
  std::vector<Eigen::MatrixXd> weights;
  double sxy = 0, sxx = 0;
  for (int i = 0; i < 4; ++i) {
    weights.push_back(Eigen::MatrixXd::Constant(1, 1, w[static_cast<std::size_t>(i)]));
    sxy += w[static_cast<std::size_t>(i)] * s["x"][i] * s["y"][i];
    sxx += w[static_cast<std::size_t>(i)] * s["x"][i] * s["x"][i];
  }
  const RegressionResult r = estimate_gls(s, {equation("E", "y", {"x"})}, weights);
  const double theta = sxy / sxx;
  double chi2 = 0;
  for (int i = 0; i < 4; ++i) chi2 += w[static_cast<std::size_t>(i)] * std::pow(s["y"][i] - theta * s["x"][i], 2);
  CHECK(r.equation("E").theta[0] == Approx(theta).epsilon(1e-12));
  CHECK(r.scale_factor == Approx(chi2 / 3).epsilon(1e-12));
  CHECK(r.equation("E").sigma[0] == Approx(std::sqrt(chi2 / 3 / sxx)).epsilon(1e-12));
}

TEST_CASE("GLS across two equations equals the dense stacked formula", "[regression]") {
  SignalTable s;
  s["x"] = vec({1.0, -0.5, 2.0, 0.3, 1.7, -1.1});
  s["z"] = vec({0.2, 1.0, -0.7, 0.9, 0.1, 0.4});
  s["y1"] = vec({2.1, -0.9, 4.2, 0.5, 3.3, -2.4});
  s["y2"] = vec({0.9, 1.4, -0.3, 1.5, 1.0, 0.2});
  const std::vector<Equation> eqs{equation("A", "y1", {"x"}), equation("B", "y2", {"x", "z"}, 0.5)};
  std::vector<Eigen::MatrixXd> W;
  for (int i = 0; i < 6; ++i) {
    Eigen::Matrix2d S;
    S << 1.0 + 0.3 * i, 0.4, 0.4, 0.5 + 0.1 * i;  // per-sample residual covariance
    W.push_back(S.inverse());
  }
  const RegressionResult r = estimate_gls(s, eqs, W);
  // Dense: rows (sample i, equation e); X block-diagonal per sample.
  Eigen::MatrixXd X = Eigen::MatrixXd::Zero(12, 3), Wd = Eigen::MatrixXd::Zero(12, 12);
  Eigen::VectorXd y(12);
  for (int i = 0; i < 6; ++i) {
    X(2 * i, 0) = s["x"][i];
    X(2 * i + 1, 1) = s["x"][i];
    X(2 * i + 1, 2) = s["z"][i];
    y[2 * i] = s["y1"][i];
    y[2 * i + 1] = 0.5 * s["y2"][i];
    Wd.block(2 * i, 2 * i, 2, 2) = W[static_cast<std::size_t>(i)];
  }
  const Eigen::MatrixXd M = X.transpose() * Wd * X;
  const Eigen::VectorXd theta = M.inverse() * X.transpose() * Wd * y;
  const Eigen::VectorXd res = y - X * theta;
  const double s2 = res.dot(Wd * res) / (12 - 3);
  const Eigen::MatrixXd cov = s2 * M.inverse();
  CHECK(r.equation("A").theta[0] == Approx(theta[0]).epsilon(1e-10));
  CHECK(r.equation("B").theta[0] == Approx(theta[1]).epsilon(1e-10));
  CHECK(r.equation("B").theta[1] == Approx(theta[2]).epsilon(1e-10));
  CHECK(r.scale_factor == Approx(s2).epsilon(1e-10));
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) CHECK(r.covariance(i, j) == Approx(cov(i, j)).epsilon(1e-9).margin(1e-14));
  }
  CHECK(r.parameter_names == std::vector<std::string>{"A_x", "B_x", "B_z"});
}

TEST_CASE("WLS with one window over the whole record gives the OLS estimates (shared regressors)", "[regression]") {
  std::mt19937_64 rng(4);
  std::normal_distribution<double> nd;
  const Eigen::Index n = 500;
  SignalTable s;
  s["x"] = Eigen::VectorXd(n);
  s["u"] = Eigen::VectorXd(n);
  s["y1"] = Eigen::VectorXd(n);
  s["y2"] = Eigen::VectorXd(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    s["x"][i] = nd(rng);
    s["u"][i] = nd(rng);
    const double e = nd(rng);
    s["y1"][i] = 1.0 * s["x"][i] - 2.0 * s["u"][i] + e;
    s["y2"][i] = 0.5 * s["x"][i] + 3.0 * s["u"][i] + 0.8 * e + 0.3 * nd(rng);
  }
  const std::vector<Equation> eqs{equation("A", "y1", {"x", "u"}), equation("B", "y2", {"x", "u"})};
  const RegressionResult ols = estimate_ols(s, eqs);
  WlsOptions o;
  o.variance_window = 0;  // whole record
  o.regularisation = 0.0;
  const RegressionResult wls = estimate_wls(s, eqs, o);
  for (std::size_t e = 0; e < 2; ++e) {
    for (Eigen::Index j = 0; j < 2; ++j) {
      CHECK(wls.equations[e].theta[j] == Approx(ols.equations[e].theta[j]).epsilon(1e-9));
      CHECK(wls.equations[e].sigma[j] == Approx(ols.equations[e].sigma[j]).epsilon(0.01));
    }
  }
  CHECK(wls.scale_factor == Approx(1.0).epsilon(0.01));
}

TEST_CASE("OLS sigma matches the Monte Carlo spread of the estimates", "[regression][montecarlo]") {
  std::mt19937_64 rng(2024);
  std::normal_distribution<double> nd;
  const Eigen::Index n = 100;
  SignalTable s;
  s["one"] = Eigen::VectorXd::Ones(n);
  s["x"] = Eigen::VectorXd::LinSpaced(n, -1.0, 3.0);
  const std::vector<Equation> eqs{equation("E", "y", {"one", "x"})};
  std::vector<double> a, b, sa, sb, sbc;
  for (int run = 0; run < 300; ++run) {
    s["y"] = Eigen::VectorXd(n);
    for (Eigen::Index i = 0; i < n; ++i) s["y"][i] = 2.0 + 0.5 * s["x"][i] + 0.3 * nd(rng);
    const RegressionResult r = estimate_ols(s, eqs);
    a.push_back(r.equations[0].theta[0]);
    b.push_back(r.equations[0].theta[1]);
    sa.push_back(r.equations[0].sigma[0]);
    sb.push_back(r.equations[0].sigma[1]);
    sbc.push_back(r.equations[0].sigma_coloured[1]);
  }
  CHECK(spread(a).mean == Approx(2.0).margin(3 * spread(a).sd / std::sqrt(300.0)));
  CHECK(spread(b).mean == Approx(0.5).margin(3 * spread(b).sd / std::sqrt(300.0)));
  CHECK(mean(sa) == Approx(spread(a).sd).epsilon(0.15));
  CHECK(mean(sb) == Approx(spread(b).sd).epsilon(0.15));
  CHECK(mean(sbc) == Approx(spread(b).sd).epsilon(0.15));  // white residuals: both agree
}

TEST_CASE("WLS sigma matches the Monte Carlo spread with heteroscedastic, correlated noise",
          "[regression][montecarlo]") {
  std::mt19937_64 rng(77);
  std::normal_distribution<double> nd;
  const Eigen::Index n = 2000;
  SignalTable s;
  s["x"] = Eigen::VectorXd(n);
  s["u"] = Eigen::VectorXd(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    s["x"][i] = std::sin(0.01 * static_cast<double>(i)) + 0.5 * nd(rng);
    s["u"][i] = nd(rng);
  }
  const std::vector<Equation> eqs{equation("A", "y1", {"x", "u"}), equation("B", "y2", {"x", "u"})};
  WlsOptions o;
  o.variance_window = 200;
  std::vector<double> ols_b, wls_b, wls_sigma, wls_b2, wls_sigma2;
  for (int run = 0; run < 300; ++run) {
    s["y1"] = Eigen::VectorXd(n);
    s["y2"] = Eigen::VectorXd(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      const double level = i < n / 2 ? 0.1 : 1.0;  // quiet first half, noisy second
      const double e1 = level * nd(rng);
      const double e2 = 0.8 * e1 + 0.6 * level * nd(rng);
      s["y1"][i] = 1.5 * s["x"][i] - 0.5 * s["u"][i] + e1;
      s["y2"][i] = -0.7 * s["x"][i] + 2.0 * s["u"][i] + e2;
    }
    ols_b.push_back(estimate_ols(s, eqs).equations[0].theta[0]);
    const RegressionResult w = estimate_wls(s, eqs, o);
    wls_b.push_back(w.equations[0].theta[0]);
    wls_sigma.push_back(w.equations[0].sigma[0]);
    wls_b2.push_back(w.equations[1].theta[1]);
    wls_sigma2.push_back(w.equations[1].sigma[1]);
  }
  CHECK(spread(wls_b).mean == Approx(1.5).margin(3 * spread(wls_b).sd / std::sqrt(300.0)));
  CHECK(mean(wls_sigma) == Approx(spread(wls_b).sd).epsilon(0.15));
  CHECK(mean(wls_sigma2) == Approx(spread(wls_b2).sd).epsilon(0.15));
  // Weighting pays: the noisy half no longer dominates.
  CHECK(spread(wls_b).sd < 0.5 * spread(ols_b).sd);
}

TEST_CASE("coloured residuals: the Newey-West sigma matches the spread, the white one is too small",
          "[regression][montecarlo]") {
  std::mt19937_64 rng(99);
  std::normal_distribution<double> nd;
  const Eigen::Index n = 3000;
  SignalTable s;
  s["x"] = Eigen::VectorXd(n);
  double ar = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) {
    ar = 0.9 * ar + nd(rng);  // slowly varying regressor
    s["x"][i] = ar;
  }
  const std::vector<Equation> eqs{equation("E", "y", {"x"})};
  CovarianceOptions cov;
  cov.correlation_lags = 80;
  std::vector<double> b, sw, sc;
  for (int run = 0; run < 300; ++run) {
    s["y"] = Eigen::VectorXd(n);
    double e = 0.0;
    for (Eigen::Index i = 0; i < n; ++i) {
      e = 0.9 * e + nd(rng);  // AR(1) residual
      s["y"][i] = 0.7 * s["x"][i] + e;
    }
    const RegressionResult r = estimate_ols(s, eqs, cov);
    b.push_back(r.equations[0].theta[0]);
    sw.push_back(r.equations[0].sigma[0]);
    sc.push_back(r.equations[0].sigma_coloured[0]);
  }
  CHECK(mean(sc) == Approx(spread(b).sd).epsilon(0.2));
  CHECK(mean(sw) < 0.5 * spread(b).sd);
}

TEST_CASE("strongly correlated parameters are flagged", "[regression]") {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> nd;
  const Eigen::Index n = 400;
  SignalTable s;
  s["x"] = Eigen::VectorXd(n);
  s["x_twin"] = Eigen::VectorXd(n);
  s["u"] = Eigen::VectorXd(n);
  s["y"] = Eigen::VectorXd(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    s["x"][i] = nd(rng);
    s["x_twin"][i] = s["x"][i] + 0.1 * nd(rng);
    s["u"][i] = nd(rng);
    s["y"][i] = s["x"][i] + s["u"][i] + 0.1 * nd(rng);
  }
  const RegressionResult r = estimate_ols(s, {equation("E", "y", {"x", "u", "x_twin"})});
  const auto pairs = correlated_pairs(r, 0.9);
  REQUIRE(pairs.size() == 1);
  CHECK(pairs[0].a == "E_x");
  CHECK(pairs[0].b == "E_x_twin");
  CHECK(pairs[0].rho < -0.9);
  CHECK(correlated_pairs(estimate_ols(s, {equation("E", "y", {"x", "u"})}), 0.9).empty());
}

TEST_CASE("regression errors name the equation and the signal", "[regression]") {
  SignalTable s;
  s["x"] = vec({1, 2, 3, 4, 5});
  s["x2"] = vec({2, 4, 6, 8, 10});
  s["zero"] = Eigen::VectorXd::Zero(5);
  s["y"] = vec({1, 2, 2, 4, 5});
  s["short"] = vec({1, 2});
  CHECK_THROWS_WITH(estimate_ols(s, {equation("L", "y", {"x", "v_abs_v"})}),
                    Catch::Contains("equation L") && Catch::Contains("v_abs_v"));
  CHECK_THROWS_WITH(estimate_ols(s, {equation("L", "y", {"x", "x2"})}),
                    Catch::Contains("equation L") && Catch::Contains("linear combination"));
  CHECK_THROWS_WITH(estimate_ols(s, {equation("Y", "y", {"x", "zero"})}),
                    Catch::Contains("'zero'") && Catch::Contains("does not excite"));
  CHECK_THROWS_WITH(estimate_ols(s, {equation("L", "y", {"x", "short"})}), Catch::Contains("'short'"));
  Equation dup = equation("L", "y", {"x"});
  CHECK_THROWS_WITH(estimate_ols(s, {dup, dup}), Catch::Contains("L_x") && Catch::Contains("twice"));
  SignalTable tiny;
  tiny["x"] = vec({1, 2});
  tiny["u"] = vec({0, 1});
  tiny["y"] = vec({1, 2});
  CHECK_THROWS_WITH(estimate_ols(tiny, {equation("L", "y", {"x", "u"})}), Catch::Contains("2 samples for 2"));
  CHECK_THROWS_AS(estimate_ols(s, {}), std::invalid_argument);
  CHECK_THROWS_AS(method_from_string("mle"), std::invalid_argument);
  CHECK(method_from_string("wls") == Method::kWls);
}
