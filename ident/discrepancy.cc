#include "ident/discrepancy.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>
#include <stdexcept>

#include <boost/math/distributions/fisher_f.hpp>

#include "core/chi_square.h"
#include "ident/metrics.h"
#include "ident/spectrum.h"

namespace nimble::ident {
namespace {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;
using Folds = std::vector<std::pair<Index, Index>>;

// ---------------------------------------------------------------------------------------
// The candidate library.

// The library is the registry's effects (core/effects.h); the regressor columns of each are
// computed in candidate_columns().

/// A regressor column is excited when its standard deviation reaches this fraction of its
/// root mean square plus an absolute floor: a column that is (nearly) constant cannot be
/// told from the other regressors (except the intercept of sensor_bias, which is constant
/// by design). The floors are 10 resolution steps of the rig's actuator interface for the
/// inputs (the servos: kServoExcitationFloorRad, as rig identify uses) and 1e-9 otherwise.
double excitation_floor(const std::string& channel) {
  if (channel == "delta_d" || channel == "delta_w") return kServoExcitationFloorRad;
  if (channel == "delta_t") return 0.1;
  if (channel == "delta_f") return 0.1;
  return 1e-9;
}

// ---------------------------------------------------------------------------------------
// Least squares from per-fold sufficient statistics.

struct Eq {
  std::string name;    // "L", "Y" or "F" (the flap actuator, when the data has its command)
  std::string output;  // "p_dot", "v_dot_star", "delta_f_dot"
  std::string unit;
  double scale = 1.0;
  VectorXd y;          // scale * dependent
  std::vector<std::string> names;
  std::vector<VectorXd> cols;
};

/// A set of columns added to equation `eq`.
struct Addition {
  std::size_t eq = 0;
  std::vector<std::string> names;
  std::vector<VectorXd> cols;
};

MatrixXd design(const std::vector<VectorXd>& cols) {
  MatrixXd X(cols.front().size(), static_cast<Index>(cols.size()));
  for (std::size_t j = 0; j < cols.size(); ++j) X.col(static_cast<Index>(j)) = cols[j];
  return X;
}

struct FoldStats {
  std::vector<MatrixXd> G;  // C_k' C_k
  std::vector<VectorXd> b;  // C_k' y_k
  std::vector<double> s;    // y_k' y_k
  MatrixXd Gt;
  VectorXd bt;
  double st = 0.0;
};

FoldStats fold_stats(const MatrixXd& C, const VectorXd& y, const Folds& folds) {
  FoldStats f;
  f.Gt = MatrixXd::Zero(C.cols(), C.cols());
  f.bt = VectorXd::Zero(C.cols());
  for (const auto& [a, e] : folds) {
    const auto Ck = C.middleRows(a, e - a);
    const auto yk = y.segment(a, e - a);
    MatrixXd G = MatrixXd::Zero(C.cols(), C.cols());
    G.selfadjointView<Eigen::Lower>().rankUpdate(Ck.transpose());
    G = G.selfadjointView<Eigen::Lower>();
    f.G.push_back(G);
    f.b.push_back(Ck.transpose() * yk);
    f.s.push_back(yk.squaredNorm());
    f.Gt += f.G.back();
    f.bt += f.b.back();
    f.st += f.s.back();
  }
  return f;
}

/// Solves G theta = b with column scaling; false if G is (numerically) singular.
bool solve(const MatrixXd& G, const VectorXd& b, VectorXd& theta) {
  const VectorXd d = G.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
  const MatrixXd Gs = d.asDiagonal() * G * d.asDiagonal();
  Eigen::LDLT<MatrixXd> ldlt(Gs);
  if (ldlt.info() != Eigen::Success) return false;
  const VectorXd D = ldlt.vectorD();
  if (D.minCoeff() <= 1e-10 * D.maxCoeff()) return false;
  theta = d.asDiagonal() * ldlt.solve(d.asDiagonal() * b);
  return theta.allFinite();
}

/// RSS of the fit on all folds.
double full_rss(const FoldStats& f) {
  VectorXd theta;
  if (!solve(f.Gt, f.bt, theta)) return std::numeric_limits<double>::quiet_NaN();
  return f.st - theta.dot(f.bt);
}

/// Covariance of the OLS estimate allowing coloured residuals: batch means of the scores
/// x_i e_i over blocks of `block` samples, Cov = G^-1 S G^-1 n / (n - q).
MatrixXd coloured_covariance(const MatrixXd& C, const VectorXd& e, Index block) {
  const Index n = C.rows(), q = C.cols();
  MatrixXd S = MatrixXd::Zero(q, q);
  for (Index a = 0; a < n; a += block) {
    const Index len = std::min(block, n - a);
    const VectorXd g = C.middleRows(a, len).transpose() * e.segment(a, len);
    S += g * g.transpose();
  }
  const MatrixXd G = C.transpose() * C;
  const VectorXd d = G.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
  const MatrixXd Ginv = d.asDiagonal() * (d.asDiagonal() * G * d.asDiagonal()).ldlt().solve(
                                             MatrixXd::Identity(q, q)) * d.asDiagonal();
  return Ginv * S * Ginv * (static_cast<double>(n) / static_cast<double>(std::max<Index>(1, n - q)));
}

/// How the coloured covariance batches a series: blocks of at least `min_block` samples and
/// longer than the residual's correlation (twice the lag at which its autocorrelation first
/// falls below 0.1), and at most n / 30, so that there are at least 30 blocks.
struct BatchRule {
  Index min_block = 1;

  /// Block length for the series e.
  Index block(const VectorXd& e) const {
    const Index n = e.size();
    const Index cap = std::max<Index>(1, n / 30);
    const VectorXd d = e.array() - e.mean();
    const double c0 = d.squaredNorm();
    Index lag = 1;
    if (c0 > 0.0) {
      for (; lag < cap; ++lag) {
        if (std::fabs(d.head(n - lag).dot(d.tail(n - lag)) / c0) < 0.1) break;
      }
    }
    return std::clamp<Index>(std::max<Index>(2 * lag, min_block), 1, cap);
  }
};

/// Number of blocks of length `block` in n samples.
double block_count(Index n, Index block) { return static_cast<double>((n + block - 1) / block); }

/// Tail probability of a Wald statistic W of k parameters whose covariance is a batch-means
/// estimate from B blocks: the estimate has nu = B - 1 degrees of freedom, so W is
/// Hotelling's T^2 and W (nu - k + 1) / (k nu) ~ F(k, nu - k + 1). A chi-square reference
/// would ignore the estimate's own scatter, which matters far in the tail where the
/// partial-F rule sits. (Counting the blocks by the tested regressor's energy in them, Kish's
/// effective number, was measured too: it cut the power, lateral inflow 17 -> 15 of 24
/// generator records, forward-speed coupling on the rig's coupled doublet and a 6 ms delay on
/// the identification train no longer named, with 0 false names on 32-seed nulls either way
/// under process noise x5, measurement noise x4, other gains and 6-20 s records: the other
/// entry criteria carry the false-alarm control.)
double wald_tail(double wald, Index k, double blocks) {
  if (std::isnan(wald)) return 1.0;
  if (std::isinf(wald)) return 0.0;
  const double K = static_cast<double>(k), nu = blocks - 1.0;
  if (nu - K + 1.0 < 1.0) return 1.0;  // too few blocks to test k parameters
  const double F = std::max(0.0, wald) * (nu - K + 1.0) / (K * nu);
  return boost::math::cdf(boost::math::complement(boost::math::fisher_f(K, nu - K + 1.0), F));
}

/// The part of x above f_hz: x minus its zero-phase Butterworth low-pass (order 4, applied
/// forward and backward), so that the two parts add up to x exactly.
VectorXd high_pass(const VectorXd& x, double f_hz, double rate_hz) {
  const auto sos = butterworth_lowpass(4, f_hz, rate_hz);
  return x - filtfilt(sos, x, default_padding(f_hz, rate_hz));
}

// ---------------------------------------------------------------------------------------
// Building the equations and candidate columns.

Folds make_folds(Index n, std::size_t k) {
  Folds folds;
  for (std::size_t i = 0; i < k; ++i) {
    const Index a = static_cast<Index>(static_cast<double>(n) * static_cast<double>(i) / static_cast<double>(k));
    const Index b = static_cast<Index>(static_cast<double>(n) * static_cast<double>(i + 1) / static_cast<double>(k));
    folds.push_back({a, b});
  }
  return folds;
}

VectorXd delayed(const VectorXd& x, Index k) {
  VectorXd out(x.size());
  for (Index i = 0; i < x.size(); ++i) out[i] = x[std::max<Index>(0, i - k)];
  return out;
}

/// The command as the actuator receives it: delta_f_cmd late by the command path's known
/// latency (DiscrepancyOptions::command_latency_s, rounded to samples), as signal
/// "delta_f_cmd_applied". The actuator equation and its delay candidate use it, so that a
/// named actuator_delay is the delay beyond that latency.
void add_applied_command(UniformData& d, double latency_s) {
  if (!d.has("delta_f_cmd")) return;
  d.signals["delta_f_cmd_applied"] = delayed(d.at("delta_f_cmd"), std::lround(latency_s * d.rate_hz));
}

bool excited(const VectorXd& x, const std::string& channel) {
  const double mean = x.mean();
  const double sd = std::sqrt((x.array() - mean).square().mean());
  return sd >= excitation_floor(channel) && sd >= 1e-6 * std::sqrt(x.squaredNorm() / static_cast<double>(x.size()));
}

/// The flap actuator's equation (thesis Eq 33, delta_f_dot = -pole delta_f + gain
/// delta_f_cmd) joins the model as a third equation "F" when the data carries the flight
/// board's command delta_f_cmd and it moves: a delay before the actuator (the plant's
/// actuator_delay, a late link) shows there, where the L and Y equations, which see the
/// actuator's output, cannot see it. Always equation 2.
constexpr std::size_t kActuatorEq = 2;

bool has_actuator_equation(const UniformData& d) {
  return d.has("delta_f_cmd_applied") && d.has("delta_f") && excited(d.at("delta_f_cmd_applied"), "delta_f");
}

/// The columns of candidate `spec` on the prepared data (delay in samples for actuator_delay).
std::vector<Addition> candidate_columns(const CandidateSpec& spec, const UniformData& d, const Trim& trim,
                                        double g, Index delay_samples) {
  const Index n = d.size();
  VectorXd col;
  std::vector<Addition> out;
  auto add = [&](std::size_t eq, const std::string& name, VectorXd c) {
    for (auto& a : out) {
      if (a.eq == eq) {
        a.names.push_back(name);
        a.cols.push_back(std::move(c));
        return;
      }
    }
    out.push_back({eq, {name}, {std::move(c)}});
  };
  const std::size_t L = 0, Y = 1;
  const auto& p = d.at("p");
  const auto& v = d.at("v");
  if (spec.name == "kinematic_coupling") {
    add(Y, "Y_pw", p.cwiseProduct((d.at("w").array() - trim.w0_mps).matrix()));
  } else if (spec.name == "gravity_nonlinearity") {
    const auto& phi = d.at("phi");
    add(Y, "Y_gphi", (g * std::cos(trim.theta0_rad) * (phi.array().sin() - phi.array())).matrix());
  } else if (spec.name == "lateral_inflow") {
    const VectorXd vv = v.cwiseProduct(v.cwiseAbs());
    add(L, "L_vv", vv);
    add(Y, "Y_vv", vv);
  } else if (spec.name == "forward_speed_coupling") {
    const VectorXd du = d.at("u").array() - trim.u0_mps;
    add(L, "L_up", du.cwiseProduct(p));
    add(L, "L_uv", du.cwiseProduct(v));
    add(Y, "Y_up", du.cwiseProduct(p));
    add(Y, "Y_uv", du.cwiseProduct(v));
  } else if (spec.name == "actuator_delay") {
    const auto& df = d.at("delta_f");
    const VectorXd c = delayed(df, delay_samples) - df;
    add(L, "L_df_delayed", c);
    add(Y, "Y_df_delayed", c);
    if (has_actuator_equation(d)) {
      const auto& cmd = d.at("delta_f_cmd_applied");
      add(kActuatorEq, "F_cmd_delayed", delayed(cmd, delay_samples) - cmd);
    }
  } else if (spec.name == "sensor_bias") {
    add(L, "L_0", VectorXd::Ones(n));
    add(Y, "Y_0", VectorXd::Ones(n));
  } else if (spec.name == "dihedral_coupling") {
    add(L, "L_dd", d.at("delta_d"));
    add(Y, "Y_dd", d.at("delta_d"));
  } else if (spec.name == "yaw_coupling") {
    add(L, "Lr", d.at("r"));
    add(Y, "Yr", d.at("r"));
  } else {
    throw std::logic_error("no columns for candidate " + spec.name);
  }
  return out;
}

/// The columns of `eq` with `adds` (for this equation) appended.
MatrixXd augmented_design(const Eq& eq, const std::vector<Addition>& adds) {
  std::vector<VectorXd> cols = eq.cols;
  for (const auto& a : adds) {
    for (const auto& c : a.cols) cols.push_back(c);
  }
  return design(cols);
}

// ---------------------------------------------------------------------------------------
// The state of the stepwise search: the baseline equations plus what has entered.

struct Model {
  std::vector<Eq> eqs;
  std::vector<std::vector<Addition>> added;  // per equation, the additions that entered
  std::vector<std::string> effect_names;

  MatrixXd X(std::size_t e) const { return augmented_design(eqs[e], added[e]); }
  std::vector<std::string> names(std::size_t e) const {
    std::vector<std::string> out = eqs[e].names;
    for (const auto& a : added[e]) out.insert(out.end(), a.names.begin(), a.names.end());
    return out;
  }
};

/// Per-fold stats of every equation of the current model.
std::vector<FoldStats> model_stats(const Model& m, const Folds& folds) {
  std::vector<FoldStats> out;
  for (std::size_t e = 0; e < m.eqs.size(); ++e) out.push_back(fold_stats(m.X(e), m.eqs[e].y, folds));
  return out;
}

/// The fit of one equation with addition `a` appended (`with`: the fold stats of that
/// design): all its parameters and their coloured covariance, the addition's Wald statistic
/// and chi-square tail, and the equation's PSE before (`rss_before`) and after.
struct AdditionFit {
  VectorXd theta;
  MatrixXd cov;
  Index off = 0, k = 0;  ///< the addition's parameters: theta.segment(off, k)
  double wald = 0.0, p = 1.0;
  double pse_before = 0.0, pse_after = 0.0;
};

/// Fits `a` (see AdditionFit); false if the design is singular.
bool fit_addition(const Model& m, const Addition& a, const FoldStats& with, double rss_before, const BatchRule& batch,
                  AdditionFit& f) {
  std::vector<Addition> all = m.added[a.eq];
  all.push_back(a);
  const MatrixXd C = augmented_design(m.eqs[a.eq], all);
  if (!solve(with.Gt, with.bt, f.theta)) return false;
  const VectorXd resid = m.eqs[a.eq].y - C * f.theta;
  const Index block = batch.block(resid);
  f.cov = coloured_covariance(C, resid, block);
  f.k = static_cast<Index>(a.cols.size());
  f.off = C.cols() - f.k;
  const VectorXd th = f.theta.tail(f.k);
  f.wald = th.dot(f.cov.block(f.off, f.off, f.k, f.k).ldlt().solve(th));
  f.p = wald_tail(f.wald, f.k, block_count(C.rows(), block));
  // PSE = RSS / N + sigma_max^2 P / N, sigma_max^2 the variance of the dependent (SIDPAC).
  const double N = static_cast<double>(C.rows());
  const VectorXd& y = m.eqs[a.eq].y;
  const double s2max = (y.array() - y.mean()).square().mean();
  f.pse_before = rss_before / N + s2max * static_cast<double>(f.off) / N;
  f.pse_after = full_rss(with) / N + s2max * static_cast<double>(C.cols()) / N;
  return true;
}

/// Records the fit of `a` in the trial: partial F, parameters, sigma, PSE of its equation.
void record(const Model& m, const Addition& a, const AdditionFit& f, CandidateTrial& t) {
  const std::string& eqname = m.eqs[a.eq].name;
  t.partial_f[eqname] = f.wald / static_cast<double>(f.k);
  for (Index j = 0; j < f.k; ++j) {
    t.parameters[a.names[static_cast<std::size_t>(j)]] = f.theta[f.off + j];
    t.sigma[a.names[static_cast<std::size_t>(j)]] = std::sqrt(std::max(0.0, f.cov(f.off + j, f.off + j)));
  }
  t.pse_before[eqname] = f.pse_before;
  t.pse_after[eqname] = f.pse_after;
}

/// RSS of the fit on every fold but k (on those folds).
double training_rss(const FoldStats& f, std::size_t k) {
  VectorXd th;
  if (!solve(f.Gt - f.G[k], f.bt - f.b[k], th)) return std::numeric_limits<double>::infinity();
  return (f.st - f.s[k]) - th.dot(f.bt - f.b[k]);
}

/// Relative drop of the held-out squared error and its standard error (a Diebold-Mariano
/// comparison of two predictors). Per sample, d_i = sum over equations of
/// (before_i^2 - after_i^2) / sum_j before_j^2; drop = sum_i d_i. Its standard error comes
/// from batch means of d over blocks longer than d's correlation time (block_length), so it
/// holds for coloured residuals; an effect that lives in a few manoeuvres is judged on all the
/// samples, not on the scatter of a few folds.
void heldout_drop(const std::vector<VectorXd>& before, const std::vector<VectorXd>& after, const BatchRule& batch,
                  double& drop, double& se) {
  const Index n = before.front().size();
  VectorXd d = VectorXd::Zero(n);
  for (std::size_t e = 0; e < before.size(); ++e) {
    const double total = before[e].squaredNorm();
    if (!(total > 0.0)) continue;
    d += ((before[e].array().square() - after[e].array().square()) / total).matrix();
  }
  drop = d.sum();
  const double mean = drop / static_cast<double>(n);
  const Index block = batch.block(d);
  double var = 0.0;
  for (Index a = 0; a < n; a += block) {
    const Index len = std::min(block, n - a);
    const double dev = d.segment(a, len).sum() - mean * static_cast<double>(len);
    var += dev * dev;
  }
  se = std::sqrt(var);
}

/// Correlation of two columns after projecting out the columns of X.
double residual_correlation(const MatrixXd& X, const VectorXd& a, const VectorXd& b) {
  const MatrixXd G = X.transpose() * X;
  VectorXd ta, tb;
  if (!solve(G, X.transpose() * a, ta) || !solve(G, X.transpose() * b, tb)) return 1.0;
  const VectorXd ra = a - X * ta, rb = b - X * tb;
  const double na = ra.norm(), nb = rb.norm();
  if (!(na > 0.0) || !(nb > 0.0)) return 1.0;
  return ra.dot(rb) / (na * nb);
}

/// The parameter of the input whose delay actuator_delay tests in equation `eq`: delta_f's
/// derivative in L and Y (L_df, Y_df), the command's gain in the actuator equation (F_cmd).
std::string delayed_input(const std::string& eq) { return eq == "F" ? "F_cmd" : eq + "_df"; }

std::string fmt(double x, int digits = 3) {
  std::ostringstream o;
  o.precision(digits);
  o << x;
  return o.str();
}

}  // namespace

const std::vector<CandidateSpec>& candidate_library() { return effect_registry(); }

// ---------------------------------------------------------------------------------------

namespace {

struct Workflow {
  const DiscrepancyOptions& opt;
  const Vehicle& vehicle;
  const DerivativeModel& model;
  UniformData data;
  Folds folds;
  BatchRule batch;
  double p_critical = 0.0;

  /// Tries `spec` on model `m` in round `round`; fills the trial and, when it passes,
  /// the additions it would make.
  CandidateTrial trial(const CandidateSpec& spec, const Model& m, const std::vector<FoldStats>& base,
                       const std::vector<VectorXd>& base_cv, std::size_t round,
                       std::vector<Addition>& best_adds) const {
    CandidateTrial t;
    t.name = spec.name;
    t.round = round;
    t.p_critical = p_critical;
    for (const auto& need : spec.needs) {
      if (!data.has(need)) {
        t.available = false;
        t.reason = "the data has no " + need;
        return t;
      }
      if (!excited(data.at(need), need)) {
        t.available = false;
        t.reason = need + " is not excited (standard deviation below " + fmt(excitation_floor(need)) + ")";
        return t;
      }
    }
    const std::size_t neq = m.eqs.size();
    const double g = vehicle.gravity_mps2;
    std::vector<Index> delays{0};
    if (spec.scanned) {
      delays.clear();
      const Index kmax = std::max<Index>(1, static_cast<Index>(std::floor(opt.delay_max_s * data.rate_hz + 1e-9)));
      for (Index k = 1; k <= kmax; ++k) delays.push_back(k);
    }
    t.scan_points = delays.size();

    // Statistics of every scan point: per equation fold stats of [X, Z].
    struct Point {
      std::vector<Addition> adds;
      std::vector<FoldStats> stats;  // per equation touched (index by equation)
      std::vector<bool> touched;
      double rss_rel = 0.0;          // sum over equations of RSS_after / RSS_before
    };
    std::vector<Point> points;
    std::vector<double> rss_before(neq);
    for (std::size_t e = 0; e < neq; ++e) rss_before[e] = full_rss(base[e]);
    for (Index k : delays) {
      Point pt;
      pt.adds = candidate_columns(spec, data, model.trim, g, k);
      pt.touched.assign(neq, false);
      pt.stats.resize(neq);
      bool ok = true;
      for (const auto& a : pt.adds) {
        for (const auto& c : a.cols) {
          const bool constant = spec.name == "sensor_bias";
          if (!constant && !excited(c, "")) ok = false;
        }
        std::vector<Addition> all = m.added[a.eq];
        all.push_back(a);
        pt.stats[a.eq] = fold_stats(augmented_design(m.eqs[a.eq], all), m.eqs[a.eq].y, folds);
        pt.touched[a.eq] = true;
      }
      for (std::size_t e = 0; e < neq && ok; ++e) {
        const double r = pt.touched[e] ? full_rss(pt.stats[e]) : rss_before[e];
        if (!std::isfinite(r)) ok = false;
        pt.rss_rel += r / rss_before[e];
      }
      if (!ok) pt.rss_rel = std::numeric_limits<double>::infinity();
      points.push_back(std::move(pt));
    }
    std::size_t best = 0;
    for (std::size_t i = 1; i < points.size(); ++i) {
      if (points[i].rss_rel < points[best].rss_rel) best = i;
    }
    if (!std::isfinite(points[best].rss_rel)) {
      t.available = false;
      t.reason = "its regressors are not excited or cannot be separated from the model's";
      return t;
    }
    const Point& P = points[best];
    if (spec.scanned) t.delay_s = static_cast<double>(delays[best]) / data.rate_hz;

    // Significance: Wald with the coloured covariance, per equation.
    double p_min = 1.0;
    // The candidate enters only the equations where its terms are significant on their own
    // (with the same Bonferroni factors): a term that explains nothing in an equation would
    // only add variance there.
    const double bonferroni = static_cast<double>(P.adds.size()) * static_cast<double>(delays.size());
    std::vector<bool> use_eq(neq, false);
    std::string p_eq;
    for (const auto& a : P.adds) {
      AdditionFit f;
      if (!fit_addition(m, a, P.stats[a.eq], rss_before[a.eq], batch, f)) continue;
      record(m, a, f, t);
      const std::string& eqname = m.eqs[a.eq].name;
      use_eq[a.eq] = f.p * bonferroni <= p_critical;
      if (f.p < p_min) {
        p_min = f.p;
        p_eq = eqname;
      }
      if (spec.scanned) {
        // A delayed input acts (mostly) delayed: with the columns delta_f and
        // delta_f(t - tau) - delta_f the delayed fraction is c / theta_df. In closed loop a
        // feedback-driven correlation of delta_f with the filtered equation error also
        // favours the delayed column, but keeps most of the input instantaneous. (The scan's
        // delay is biased low by the same correlation, which leaves a small instantaneous part
        // with a real delay: the criterion is the fraction, not its significance.)
        const auto it = std::find(m.eqs[a.eq].names.begin(), m.eqs[a.eq].names.end(), delayed_input(eqname));
        if (it != m.eqs[a.eq].names.end()) {
          const Index i = static_cast<Index>(it - m.eqs[a.eq].names.begin());
          const double c = f.theta[f.off];
          const double inst = f.theta[i] - c;
          const double var = f.cov(i, i) + f.cov(f.off, f.off) - 2.0 * f.cov(i, f.off);
          t.instantaneous_f[eqname] = var > 0.0 ? inst * inst / var : std::numeric_limits<double>::infinity();
          t.parameters[delayed_input(eqname) + "_fraction_delayed"] = f.theta[i] != 0.0 ? c / f.theta[i] : 0.0;
        }
      }
    }
    if (spec.scanned) t.parameters["delay_s"] = t.delay_s;

    // Confirmation above the gust band: an unmeasured side wind acts through v - v_g and
    // drives v itself, so in closed loop it correlates the equation error with functions of
    // v (v|v| above all). Its power lies at low frequency; an effect that is a function of the
    // states holds at every frequency. The candidate must stay significant, at
    // opt.gust_band_alpha with the same Bonferroni factors, on the equations high-passed above
    // opt.gust_band_hz (y and every column alike). A constant (sensor_bias) has no content
    // there and is exempt.
    if (!p_eq.empty() && spec.name != "sensor_bias") {
      double p_hp = 1.0;
      for (const auto& a : P.adds) {
        std::vector<Addition> all = m.added[a.eq];
        all.push_back(a);
        const MatrixXd C0 = augmented_design(m.eqs[a.eq], all);
        MatrixXd C(C0.rows(), C0.cols());
        for (Index j = 0; j < C0.cols(); ++j) C.col(j) = high_pass(C0.col(j), opt.gust_band_hz, data.rate_hz);
        const VectorXd y = high_pass(m.eqs[a.eq].y, opt.gust_band_hz, data.rate_hz);
        VectorXd theta;
        const FoldStats fs = fold_stats(C, y, {{0, C.rows()}});
        if (!solve(fs.Gt, fs.bt, theta)) continue;
        const VectorXd resid = y - C * theta;
        const Index block = batch.block(resid);
        const MatrixXd cov = coloured_covariance(C, resid, block);
        const Index kc = static_cast<Index>(a.cols.size());
        const VectorXd th = theta.tail(kc);
        const double wald = th.dot(cov.bottomRightCorner(kc, kc).ldlt().solve(th));
        p_hp = std::min(p_hp, wald_tail(wald, kc, block_count(C.rows(), block)));
      }
      t.highpass_p = std::min(1.0, p_hp * static_cast<double>(P.adds.size()) * static_cast<double>(delays.size()));
    }
    t.p_value = std::min(1.0, p_min * static_cast<double>(P.adds.size()) * static_cast<double>(delays.size()));

    // Held-out: K-fold; a scanned candidate picks its delay on the training folds. Every
    // sample is predicted by a fit that did not see its block; the drop of the squared
    // held-out error is judged against its own spread (next function).
    const std::size_t K = folds.size();
    std::vector<VectorXd> after = base_cv;
    bool cv_ok = true;
    for (std::size_t k = 0; k < K && cv_ok; ++k) {
      std::size_t pick = best;
      if (spec.scanned) {
        double best_rel = std::numeric_limits<double>::infinity();
        for (std::size_t i = 0; i < points.size(); ++i) {
          if (!std::isfinite(points[i].rss_rel)) continue;
          double rel = 0.0;
          for (std::size_t e = 0; e < neq && std::isfinite(rel); ++e) {
            if (!points[i].touched[e]) {
              rel += 1.0;
              continue;
            }
            rel += training_rss(points[i].stats[e], k) / training_rss(base[e], k);
          }
          if (rel < best_rel) {
            best_rel = rel;
            pick = i;
          }
        }
      }
      const auto [a, b] = folds[k];
      for (const auto& add : points[pick].adds) {
        if (!use_eq[add.eq] && std::any_of(use_eq.begin(), use_eq.end(), [](bool b) { return b; })) continue;
        std::vector<Addition> all = m.added[add.eq];
        all.push_back(add);
        const MatrixXd C = augmented_design(m.eqs[add.eq], all);
        const FoldStats& fs = points[pick].stats[add.eq];
        VectorXd th;
        if (!solve(fs.Gt - fs.G[k], fs.bt - fs.b[k], th)) {
          cv_ok = false;
          break;
        }
        after[add.eq].segment(a, b - a) = m.eqs[add.eq].y.segment(a, b - a) - C.middleRows(a, b - a) * th;
      }
    }
    if (!cv_ok) {
      t.reason = "a cross-validation fit is singular (the candidate is not excited in every block)";
      return t;
    }
    heldout_drop(base_cv, after, batch, t.heldout_drop, t.heldout_se);

    const bool significant = t.p_value <= p_critical;
    const bool pse_falls = !p_eq.empty() && t.pse_after.at(p_eq) < t.pse_before.at(p_eq);
    const auto frac = t.parameters.find(delayed_input(p_eq) + "_fraction_delayed");
    const bool consistent = frac == t.parameters.end() || frac->second >= 0.5;
    const bool above_gusts = t.highpass_p <= opt.gust_band_alpha;
    const bool heldout = t.heldout_drop > 0.0 && t.heldout_drop > opt.heldout_sigmas * t.heldout_se;
    t.passed = significant && pse_falls && heldout && consistent && above_gusts;
    std::ostringstream why;
    if (t.passed) {
      why << "passes: p " << fmt(t.p_value) << " <= " << fmt(p_critical) << " (F " << fmt(t.partial_f[p_eq])
          << " in " << p_eq << "), PSE falls, held-out error falls " << fmt(100.0 * t.heldout_drop) << " % (+- "
          << fmt(100.0 * t.heldout_se) << ")";
    } else {
      why << "fails:";
      if (!significant) {
        why << " not significant (p " << fmt(t.p_value) << " > " << fmt(p_critical);
        if (!p_eq.empty()) why << ", F " << fmt(t.partial_f[p_eq]) << " in " << p_eq;
        why << ")";
      }
      if (!pse_falls) why << " PSE does not fall;";
      if (!above_gusts) {
        why << " not significant above the gust band (p " << fmt(t.highpass_p) << " > " << fmt(opt.gust_band_alpha)
            << " on the equations high-passed at " << fmt(opt.gust_band_hz) << " Hz);";
      }
      if (!consistent) {
        why << " most of the input still acts at once (delayed fraction " << fmt(frac->second) << " < 0.5 in " << p_eq
            << "): not a delay;";
      }
      if (!heldout) {
        why << " held-out error change " << fmt(-100.0 * t.heldout_drop) << " % is not a drop beyond "
            << fmt(opt.heldout_sigmas) << " standard errors (" << fmt(100.0 * t.heldout_se) << " %)";
      }
    }
    t.reason = why.str();
    if (t.passed) {
      for (const auto& a : P.adds) {
        if (use_eq[a.eq]) best_adds.push_back(a);
      }
    }
    return t;
  }
};

/// Held-out residual of each equation (every fold predicted by the fit on the others).
std::vector<VectorXd> heldout_residuals(const Model& m, const Folds& folds) {
  std::vector<VectorXd> out;
  for (std::size_t e = 0; e < m.eqs.size(); ++e) {
    const MatrixXd C = m.X(e);
    const FoldStats fs = fold_stats(C, m.eqs[e].y, folds);
    VectorXd r(C.rows());
    for (std::size_t k = 0; k < folds.size(); ++k) {
      VectorXd th;
      const auto [a, b] = folds[k];
      if (!solve(fs.Gt - fs.G[k], fs.bt - fs.b[k], th)) th = VectorXd::Zero(C.cols());
      r.segment(a, b - a) = m.eqs[e].y.segment(a, b - a) - C.middleRows(a, b - a) * th;
    }
    out.push_back(r);
  }
  return out;
}

/// lateral_gust from its signature (it has no deterministic regressor, so it is never tried in
/// the stepwise search). A side wind v_g enters the side-force equation as -Yv v_g: a
/// random force whose spectrum is that of the wind, low-pass (a first-order Gauss-Markov
/// wind: S(f) = A / (1 + (2 pi f tau)^2)). On the residual of the final model:
///   1. excess at low frequency: the mean periodogram of the Y residual below gust_band_hz
///      against its mean in the reference band from 1.5 gust_band_hz to f_ref_hi (the
///      equation noise's level, flat or rising with frequency for differentiated
///      measurements). For a flat background the ratio is F(2 K_lo, 2 K_ref) with K the
///      number of independent bins in each band (the padded bins count n / n_fft each), so
///      the test holds its level; a background rising with frequency makes it conservative.
///      Named only on the evidence every other candidate needs, p <= p_critical (the
///      partial-F rule's tail, 7.7e-6): the residual of a refit closed-loop record is not
///      stationary (manoeuvres come and go), its periodogram ordinates scatter more than
///      chi-square, and at location_alpha (0.01) 2 of 24 generator nulls measured p < 0.01.
///   2. parameters: tau_s and A from a Whittle fit of A / (1 + (2 pi f tau)^2) + N0 to the
///      periodogram, below f_ref_hi, of the Y residual of the model as given (N0 the
///      reference band's level; tau on a log grid 0.02-20 s); the force variance is
///      A / (4 tau) (one-sided PSD), and sigma_mps = sqrt(A / (4 tau)) / |Yv| with the model's
///      Yv. Rough: the model's own errors at low frequency add to it.
/// Sums of a periodogram's ordinates (and of their squares) in the gust band, (0, band_hz],
/// and in the reference band above it, [1.5 band_hz, ref_hi_hz]; bin counts of each.
struct GustBands {
  double lo = 0.0, ref = 0.0, lo2 = 0.0, ref2 = 0.0;
  Index k_lo = 0, k_ref = 0;
};

GustBands gust_bands(const Psd& P, double band_hz, double ref_hi_hz) {
  GustBands b;
  for (Index k = 1; k < P.psd.size(); ++k) {
    const double x = P.psd[k];
    if (P.f_hz[k] <= band_hz) {
      b.lo += x;
      b.lo2 += x * x;
      ++b.k_lo;
    } else if (P.f_hz[k] >= 1.5 * band_hz && P.f_hz[k] <= ref_hi_hz) {
      b.ref += x;
      b.ref2 += x * x;
      ++b.k_ref;
    }
  }
  return b;
}

CandidateTrial gust_trial(const Model& m, const std::vector<VectorXd>& resid,
                          const std::map<std::string, ParameterEstimate>& fit, double rate_hz, double f_ref_hi,
                          const std::vector<VectorXd>& extra, const VectorXd& given_resid, double yv_given,
                          const DiscrepancyOptions& opt, double p_critical) {
  CandidateTrial t;
  t.name = "lateral_gust";
  t.round = m.effect_names.size() + 1;
  t.p_critical = p_critical;
  std::size_t ey = m.eqs.size();
  for (std::size_t e = 0; e < m.eqs.size(); ++e) {
    if (m.eqs[e].name == "Y") ey = e;
  }
  const auto yv = fit.find("Yv");
  if (ey == m.eqs.size() || yv == fit.end() || !(std::fabs(yv->second.value) > 0.0)) {
    t.available = false;
    t.reason = "the model has no side-force equation with Yv to see a side wind through";
    return t;
  }
  // A deterministic effect too weak to enter on its own also leaves low-frequency structure
  // in the residual (a slow (u - u0) v term, say). The signature is taken on the Y residual
  // with every deterministic candidate's Y columns in the fit (`extra`), so that only what no
  // function of the measured states and inputs explains is left: a random force.
  VectorXd r = resid[ey];
  if (!extra.empty()) {
    std::vector<VectorXd> cols = m.eqs[ey].cols;
    for (const auto& a : m.added[ey]) cols.insert(cols.end(), a.cols.begin(), a.cols.end());
    cols.insert(cols.end(), extra.begin(), extra.end());
    const MatrixXd C = design(cols);
    r = m.eqs[ey].y - C * C.completeOrthogonalDecomposition().solve(m.eqs[ey].y);
  }
  const Psd P = periodogram(r, rate_hz);
  const double per_bin = static_cast<double>(r.size()) * P.df_hz / rate_hz;  // independent bins per padded bin
  const GustBands b = gust_bands(P, opt.gust_band_hz, f_ref_hi);
  const double lo = b.lo, ref = b.ref, lo2 = b.lo2, ref2 = b.ref2;
  const Index k_lo = b.k_lo, k_ref = b.k_ref;
  if (k_lo == 0 || k_ref == 0 || !(ref2 > 0.0) || !(lo2 > 0.0)) {
    t.available = false;
    t.reason = "the record is too short or the low-pass too low for the band test";
    return t;
  }
  // Degrees of freedom of each band's sum: 2 per independent bin for chi2_2 ordinates of
  // equal mean; ordinates more scattered than that (a spectrum that varies across the band, a
  // residual that is not Gaussian) have fewer, 4 (sum P)^2 / sum P^2 per padded bin set
  // (Satterthwaite), never more than 2 per independent bin.
  const double d_lo = std::min(2.0 * static_cast<double>(k_lo), 4.0 * lo * lo / lo2) * per_bin;
  const double d_ref = std::min(2.0 * static_cast<double>(k_ref), 4.0 * ref * ref / ref2) * per_bin;
  if (d_lo < 6.0 || d_ref < 6.0) {
    t.available = false;
    t.reason = "the record is too short or the low-pass too low for the band test";
    return t;
  }
  const double N0 = ref / static_cast<double>(k_ref);
  const double ratio = (lo / static_cast<double>(k_lo)) / N0;
  t.partial_f["Y"] = ratio;
  t.p_value = boost::math::cdf(boost::math::complement(boost::math::fisher_f(d_lo, d_ref), ratio));
  t.highpass_p = 1.0;
  if (t.p_value > p_critical) {
    t.reason = "no signature: the Y residual below " + fmt(opt.gust_band_hz) + " Hz is " + fmt(ratio) +
               " times its level above (p " + fmt(t.p_value) + " > " + fmt(p_critical) + ")";
    return t;
  }
  // Size: from the residual of the model as given (its own derivatives), which carries the
  // whole wind force -Yv v_g; the refit's residual does not, since the refit derivatives absorb
  // the part of the wind the vehicle's motion follows (on a rig hover in gusts the refit Yv goes
  // to nearly 0). Whittle fit of A / (1 + (2 pi f tau)^2) + N0 below f_ref_hi, N0 the
  // reference band's level.
  const bool given = given_resid.size() == r.size() && yv_given != 0.0;
  const Psd Pg = given ? periodogram(given_resid, rate_hz) : P;
  const GustBands bg = gust_bands(Pg, opt.gust_band_hz, f_ref_hi);
  const double lo_g = bg.lo, N0g = bg.ref / static_cast<double>(k_ref);
  double best = std::numeric_limits<double>::infinity(), tau_best = 0.0, a_best = 0.0;
  const double excess = std::max(0.0, lo_g / static_cast<double>(k_lo) - N0g);
  for (int i = 0; i <= 60; ++i) {
    const double tau = 0.02 * std::pow(1000.0, i / 60.0);
    for (int j = 0; j <= 60; ++j) {
      const double A = excess * std::pow(10.0, -1.0 + 3.0 * j / 60.0);
      double nll = 0.0;
      for (Index k = 1; k < Pg.psd.size() && Pg.f_hz[k] <= f_ref_hi; ++k) {
        const double w = 2.0 * M_PI * Pg.f_hz[k] * tau;
        const double S = A / (1.0 + w * w) + N0g;
        nll += Pg.psd[k] / S + std::log(S);
      }
      if (nll < best) {
        best = nll;
        tau_best = tau;
        a_best = A;
      }
    }
  }
  const double sigma_force = std::sqrt(a_best / (4.0 * tau_best));
  t.parameters["sigma_mps"] = sigma_force / std::fabs(given ? yv_given : yv->second.value);
  t.parameters["tau_s"] = tau_best;
  // The low band's mean has a relative standard error 1 / sqrt(d_lo / 2); sigma is its square root.
  t.sigma["sigma_mps"] = t.parameters["sigma_mps"] / std::sqrt(2.0 * d_lo);
  t.passed = true;
  t.entered = true;
  t.reason = "entered: the Y residual below " + fmt(opt.gust_band_hz) + " Hz is " + fmt(ratio) +
             " times its level above (p " + fmt(t.p_value) + " <= " + fmt(p_critical) +
             "), a side wind of about " + fmt(t.parameters["sigma_mps"]) + " m/s with tau " + fmt(tau_best) + " s";
  return t;
}

/// Prediction of equation `eq` (scaled as eq.y) by the model as given: its own derivatives,
/// the values of the effects its file carries, and the actuator of the options.
VectorXd given_prediction(const Eq& eq, const DerivativeModel& model, const std::map<std::string, double>& known_values,
                          const DiscrepancyOptions& options) {
  VectorXd out = VectorXd::Zero(eq.y.size());
  for (std::size_t j = 0; j < eq.names.size(); ++j) {
    const auto it = model.derivatives.find(eq.names[j]);
    const auto fx = known_values.find(eq.names[j]);
    if (eq.names[j] == "F_f") {
      out -= options.actuator_pole_radps * eq.cols[j];
    } else if (eq.names[j] == "F_cmd") {
      out += options.actuator_gain * eq.cols[j];
    } else if (it != model.derivatives.end()) {
      out += it->second * eq.cols[j];
    } else if (fx != known_values.end()) {
      out += fx->second * eq.cols[j];
    }
  }
  return out;
}

/// Full-data fit of the model: parameters with coloured sigma, and residuals.
std::map<std::string, ParameterEstimate> full_fit(const Model& m, const BatchRule& batch, std::vector<VectorXd>* residuals) {
  std::map<std::string, ParameterEstimate> out;
  for (std::size_t e = 0; e < m.eqs.size(); ++e) {
    const MatrixXd C = m.X(e);
    VectorXd th;
    const FoldStats fs = fold_stats(C, m.eqs[e].y, {{0, C.rows()}});
    // A candidate enters only with its cross-validation fits solvable; a fit that is only
    // nearly singular on all the data is solved by complete orthogonal decomposition.
    if (!solve(fs.Gt, fs.bt, th)) th = C.completeOrthogonalDecomposition().solve(m.eqs[e].y);
    const VectorXd r = m.eqs[e].y - C * th;
    const MatrixXd cov = coloured_covariance(C, r, batch.block(r));
    const double s2 = r.squaredNorm() / static_cast<double>(std::max<Index>(1, C.rows() - C.cols()));
    const MatrixXd white = s2 * (C.transpose() * C).inverse();
    const auto names = m.names(e);
    for (std::size_t j = 0; j < names.size(); ++j) {
      const Index i = static_cast<Index>(j);
      out[names[j]] = {th[i], std::sqrt(std::max(0.0, white(i, i))), std::sqrt(std::max(0.0, cov(i, i)))};
    }
    if (residuals) residuals->push_back(r);
  }
  return out;
}

// ---------------------------------------------------------------------------------------
// Location.

/// Periodogram peaks of `r` against the median of their neighbourhood (+-20 bins, the
/// centre +-2 bins left out). For a Gaussian process a periodogram ordinate over its
/// spectrum is Exp(1) (chi2_2 / 2) and the local median estimates ln 2 times the
/// spectrum, so P(ratio > x) = exp(-x); the p-value is multiplied by the number of bins
/// scanned (Bonferroni).
void frequency_peaks(const std::string& output, const VectorXd& r, double rate, double f_lo, double f_hi,
                     double alpha, std::vector<FrequencyFinding>& out) {
  const Psd P = periodogram(r, rate);
  const Index nb = P.psd.size();
  const Index half = 20, gap = 2;
  std::vector<Index> bins;
  for (Index k = half; k + half < nb; ++k) {
    if (P.f_hz[k] >= f_lo && P.f_hz[k] <= f_hi) bins.push_back(k);
  }
  if (bins.empty()) return;
  const double M = static_cast<double>(bins.size());
  std::vector<double> nbh;
  FrequencyFinding best;
  bool found = false;
  for (Index k : bins) {
    nbh.clear();
    for (Index j = k - half; j <= k + half; ++j) {
      if (std::abs(j - k) > gap) nbh.push_back(P.psd[j]);
    }
    std::nth_element(nbh.begin(), nbh.begin() + static_cast<long>(nbh.size() / 2), nbh.end());
    const double background = nbh[nbh.size() / 2] / std::log(2.0);
    if (!(background > 0.0)) continue;
    const double ratio = P.psd[k] / background;
    const double p = std::min(1.0, std::exp(-ratio) * M);
    if (p <= alpha && (!found || ratio > best.ratio)) {
      best = {output, P.f_hz[k], ratio, p};
      found = true;
    }
  }
  if (found) out.push_back(best);
}

/// Residual against a nonlinear function of each state and input (x^2 and x^3, which the
/// linear model cannot produce), with the model's regressors: Wald test with the coloured
/// covariance, significant at alpha / (number of signals tested), per equation.
void state_findings(const Model& m, std::size_t e, const UniformData& d, const BatchRule& batch, double alpha,
                    std::vector<StateFinding>& out) {
  std::vector<std::string> signals;
  for (const char* s : {"p", "v", "phi", "delta_f", "u", "w", "delta_t"}) {
    if (d.has(s) && excited(d.at(s), s)) signals.push_back(s);
  }
  const double M = static_cast<double>(signals.size());
  const MatrixXd X = m.X(e);
  VectorXd th0;
  if (!solve(X.transpose() * X, X.transpose() * m.eqs[e].y, th0)) return;
  const double rss0 = (m.eqs[e].y - X * th0).squaredNorm();
  for (const auto& s : signals) {
    const VectorXd& x = d.at(s);
    const double sd = std::sqrt((x.array() - x.mean()).square().mean());
    const VectorXd z = (x.array() - x.mean()) / sd;
    MatrixXd C(X.rows(), X.cols() + 2);
    C << X, z.array().square().matrix(), z.array().cube().matrix();
    VectorXd th;
    if (!solve(C.transpose() * C, C.transpose() * m.eqs[e].y, th)) continue;
    const VectorXd r = m.eqs[e].y - C * th;
    const Index block = batch.block(r);
    const MatrixXd cov = coloured_covariance(C, r, block);
    const VectorXd t2 = th.tail(2);
    const double wald = t2.dot(cov.bottomRightCorner(2, 2).ldlt().solve(t2));
    const double p = std::min(1.0, wald_tail(wald, 2, block_count(C.rows(), block)) * M);
    if (p <= alpha) {
      StateFinding f;
      f.output = m.eqs[e].output;
      f.signal = s;
      f.partial_r = std::sqrt(std::max(0.0, 1.0 - r.squaredNorm() / rss0));
      f.p_value = p;
      out.push_back(f);
    }
  }
}

void time_findings(const std::string& output, const VectorXd& r, const UniformData& d, const Segments& seg,
                   double window_s, std::vector<TimeFinding>& out) {
  const double total = r.squaredNorm();
  const Index n = r.size();
  if (!(total > 0.0) || n == 0) return;
  auto share = [&](Index a, Index b) { return r.segment(a, b - a).squaredNorm() / total; };
  for (const auto& [what, list] : {std::pair<std::string, const std::vector<TimeRange>*>{"manoeuvre", &seg.manoeuvre},
                                   {"hover", &seg.hover}}) {
    for (const auto& [a, b] : sample_ranges(d, *list)) {
      out.push_back({output, what, d.t_s[a], d.t_s[b - 1], share(a, b),
                     static_cast<double>(b - a) / static_cast<double>(n)});
    }
  }
  // The three 1 s windows with the most residual energy.
  const Index w = std::max<Index>(1, static_cast<Index>(std::lround(window_s * d.rate_hz)));
  std::vector<std::pair<double, Index>> windows;
  for (Index a = 0; a + w <= n; a += w) windows.push_back({share(a, a + w), a});
  std::sort(windows.begin(), windows.end(), [](const auto& x, const auto& y) { return x.first > y.first; });
  for (std::size_t i = 0; i < std::min<std::size_t>(3, windows.size()); ++i) {
    const Index a = windows[i].second;
    out.push_back({output, "window", d.t_s[a], d.t_s[a + w - 1], windows[i].first,
                   static_cast<double>(w) / static_cast<double>(n)});
  }
}

}  // namespace

/// sin and cos of h 2 pi f t, h = 1 .. harmonics, in every equation.
std::vector<Addition> harmonic_columns(const VectorXd& t_s, double f_hz, int harmonics, const Model& m) {
  std::vector<Addition> out;
  for (std::size_t e = 0; e < m.eqs.size(); ++e) {
    if (m.eqs[e].name == "F") continue;  // a force or moment, not an actuator input
    Addition a;
    a.eq = e;
    for (int h = 1; h <= harmonics; ++h) {
      const VectorXd arg = (2.0 * M_PI * h * f_hz) * t_s;
      a.names.push_back(m.eqs[e].name + "_sin" + std::to_string(h));
      a.cols.push_back(arg.array().sin().matrix());
      a.names.push_back(m.eqs[e].name + "_cos" + std::to_string(h));
      a.cols.push_back(arg.array().cos().matrix());
    }
    out.push_back(std::move(a));
  }
  return out;
}

/// Frequency in [lo, hi] where the residuals (each normalised by its variance) have the most
/// power at the frequency and its harmonics; samples where `mask` is false count as zero.
double scan_frequency(const std::vector<VectorXd>& resid, double rate, double lo, double hi, int harmonics,
                      const std::vector<bool>& mask) {
  std::vector<Psd> psd;
  for (const auto& r0 : resid) {
    VectorXd r = r0;
    for (Index i = 0; i < r.size(); ++i) {
      if (!mask[static_cast<std::size_t>(i)]) r[i] = 0.0;
    }
    const double var = r.squaredNorm() / static_cast<double>(r.size());
    psd.push_back(periodogram(var > 0.0 ? VectorXd(r / std::sqrt(var)) : r, rate));
  }
  const Psd& p0 = psd.front();
  double best_f = lo, best = -1.0;
  for (Index k = 0; k < p0.f_hz.size(); ++k) {
    const double f = p0.f_hz[k];
    if (f < lo || f > hi) continue;
    double score = 0.0;
    for (const auto& p : psd) {
      for (int h = 1; h <= harmonics; ++h) {
        const Index j = static_cast<Index>(std::lround(h * f / p.df_hz));
        if (j < p.psd.size()) score += p.psd[j];
      }
    }
    if (score > best) {
      best = score;
      best_f = f;
    }
  }
  return best_f;
}

/// The flapping_forcing candidate on wideband data (see the wideband stage of find_discrepancy).
CandidateTrial flapping_trial(const Model& m, const UniformData& d, const Folds& folds, const DiscrepancyOptions& opt,
                              double p_critical, const BatchRule& batch) {
  CandidateTrial t;
  t.name = "flapping_forcing";
  t.round = m.effect_names.size() + 1;
  t.p_critical = p_critical;
  const int H = 2;
  const Index n = d.size();
  const double T = d.t_s[n - 1] - d.t_s[0];
  const double lo = opt.flapping_band_hz[0], hi = opt.flapping_band_hz[1];
  // Independent frequencies of the band: one per 1 / T (the periodogram's resolution).
  t.scan_points = static_cast<std::size_t>(std::max(1.0, std::ceil((hi - lo) * T)));
  const std::size_t neq = m.eqs.size();
  std::vector<VectorXd> resid;
  std::vector<FoldStats> base;
  for (std::size_t e = 0; e < neq; ++e) {
    const MatrixXd X = m.X(e);
    base.push_back(fold_stats(X, m.eqs[e].y, folds));
    VectorXd th;
    if (!solve(base.back().Gt, base.back().bt, th)) {
      t.available = false;
      t.reason = "the model cannot be refit on the wideband data";
      return t;
    }
    resid.push_back(m.eqs[e].y - X * th);
  }
  const VectorXd t0 = d.t_s.array() - d.t_s[0];
  const double f = scan_frequency(resid, d.rate_hz, lo, hi, H, std::vector<bool>(static_cast<std::size_t>(n), true));
  t.parameters["flapping_hz"] = f;
  const std::vector<Addition> adds = harmonic_columns(t0, f, H, m);
  double p_min = 1.0;
  std::string p_eq;
  std::vector<FoldStats> with(neq);
  for (const auto& a : adds) {
    std::vector<Addition> all = m.added[a.eq];
    all.push_back(a);
    with[a.eq] = fold_stats(augmented_design(m.eqs[a.eq], all), m.eqs[a.eq].y, folds);
    AdditionFit fit;
    if (!fit_addition(m, a, with[a.eq], full_rss(base[a.eq]), batch, fit)) continue;
    record(m, a, fit, t);
    const std::string& eqname = m.eqs[a.eq].name;
    for (int h = 1; h <= H; ++h) {
      const double s1 = fit.theta[fit.off + 2 * (h - 1)], c1 = fit.theta[fit.off + 2 * (h - 1) + 1];
      t.parameters[eqname + "_amp" + std::to_string(h)] = std::hypot(s1, c1);
    }
    if (fit.p < p_min) {
      p_min = fit.p;
      p_eq = eqname;
    }
  }
  t.p_value = std::min(1.0, p_min * static_cast<double>(adds.size()) * static_cast<double>(t.scan_points));
  // Held-out: each block predicted with the frequency found without it.
  std::vector<VectorXd> before, after;
  for (std::size_t e = 0; e < neq; ++e) {
    before.push_back(VectorXd(n));
    after.push_back(VectorXd(n));
  }
  for (std::size_t k = 0; k < folds.size(); ++k) {
    const auto [a, b] = folds[k];
    std::vector<bool> mask(static_cast<std::size_t>(n), true);
    for (Index i = a; i < b; ++i) mask[static_cast<std::size_t>(i)] = false;
    const double fk = scan_frequency(resid, d.rate_hz, lo, hi, H, mask);
    const std::vector<Addition> ak = harmonic_columns(t0, fk, H, m);
    for (std::size_t e = 0; e < neq; ++e) {
      const MatrixXd X = m.X(e);
      VectorXd th0;
      if (!solve(base[e].Gt - base[e].G[k], base[e].bt - base[e].b[k], th0)) th0 = VectorXd::Zero(X.cols());
      before[e].segment(a, b - a) = m.eqs[e].y.segment(a, b - a) - X.middleRows(a, b - a) * th0;
      const auto add = std::find_if(ak.begin(), ak.end(), [&](const Addition& x) { return x.eq == e; });
      if (add == ak.end()) {  // an equation without harmonics (the actuator's)
        after[e].segment(a, b - a) = before[e].segment(a, b - a);
        continue;
      }
      std::vector<Addition> all = m.added[e];
      all.push_back(*add);
      const MatrixXd C = augmented_design(m.eqs[e], all);
      const FoldStats fs = fold_stats(C, m.eqs[e].y, folds);
      VectorXd th;
      if (!solve(fs.Gt - fs.G[k], fs.bt - fs.b[k], th)) th = VectorXd::Zero(C.cols());
      after[e].segment(a, b - a) = m.eqs[e].y.segment(a, b - a) - C.middleRows(a, b - a) * th;
    }
  }
  heldout_drop(before, after, batch, t.heldout_drop, t.heldout_se);
  const bool significant = t.p_value <= p_critical;
  const bool pse_falls = !p_eq.empty() && t.pse_after.at(p_eq) < t.pse_before.at(p_eq);
  const bool heldout = t.heldout_drop > 0.0 && t.heldout_drop > opt.heldout_sigmas * t.heldout_se;
  t.passed = significant && pse_falls && heldout;
  std::ostringstream why;
  why << (t.passed ? "passes:" : "fails:") << " at " << fmt(f) << " Hz (band " << fmt(lo) << "-" << fmt(hi) << " Hz, "
      << t.scan_points << " independent frequencies, data low-passed at " << fmt(opt.flapping_cutoff_hz) << " Hz): p "
      << fmt(t.p_value) << (significant ? " <= " : " > ") << fmt(p_critical);
  if (!p_eq.empty()) why << " (F " << fmt(t.partial_f[p_eq]) << " in " << p_eq << ")";
  why << (pse_falls ? ", PSE falls" : ", PSE does not fall") << ", held-out error change " << fmt(-100.0 * t.heldout_drop)
      << " % (spread " << fmt(100.0 * t.heldout_se) << " %)";
  t.reason = why.str();
  return t;
}

/// The model's regression equations on `d`, with the columns of the effects the model file
/// carries (an earlier analysis named them): refit with the derivatives, not tried again.
/// Effects without a column on `d` (flapping forcing on low-passed data) are only listed.
Model build_baseline(const UniformData& d, const std::vector<Equation>& equations, const DerivativeModel& model,
                     const Vehicle& vehicle, const std::string& source, std::vector<std::string>* known,
                     std::map<std::string, double>* known_values) {
  Model m;
  for (const auto& eq : equations) {
    Eq e;
    e.name = eq.name;
    e.output = eq.dependent;
    e.unit = eq.dependent == "v_dot_star" ? "m/s^2" : "rad/s^2";
    e.scale = eq.scale;
    e.y = eq.scale * d.at(eq.dependent);
    for (std::size_t j = 0; j < eq.regressors.size(); ++j) {
      e.names.push_back(eq.parameters[j]);
      e.cols.push_back(d.at(eq.regressors[j]));
    }
    m.eqs.push_back(std::move(e));
  }
  if (has_actuator_equation(d)) {
    // Eq 33 refit: delta_f_dot = F_f delta_f + F_cmd delta_f_cmd (the model as given has
    // F_f = -actuator_pole_radps, F_cmd = actuator_gain: DiscrepancyOptions).
    Eq e;
    e.name = "F";
    e.output = "delta_f_dot";
    e.unit = "rad/s^2";
    e.y = differentiate(d.at("delta_f"), d.rate_hz);
    e.names = {"F_f", "F_cmd"};
    e.cols = {d.at("delta_f"), d.at("delta_f_cmd_applied")};
    m.eqs.push_back(std::move(e));
  }
  m.added.resize(m.eqs.size());
  for (const auto& [name, params] : model.effects) {
    const EffectSpec* spec = find_effect(name);
    if (spec == nullptr) continue;  // an effect the library has no regressor form for
    if (known) known->push_back(name);
    if (known_values) {
      for (const auto& [key, value] : params) (*known_values)[key] = value;
    }
    if (spec->wideband) continue;
    for (const auto& need : spec->needs) {
      if (!d.has(need)) {
        throw DataError(source, -1, -1, need, "the model's effect " + name + " needs " + need + ", not in the data");
      }
    }
    const auto delay = params.find("delay_s");
    const Index k = delay == params.end() ? 0 : std::max<Index>(1, std::lround(delay->second * d.rate_hz));
    for (auto& add : candidate_columns(*spec, d, model.trim, vehicle.gravity_mps2, k)) {
      for (std::size_t j = 0; j < add.names.size(); ++j) {
        m.eqs[add.eq].names.push_back(add.names[j]);
        m.eqs[add.eq].cols.push_back(std::move(add.cols[j]));
      }
    }
  }
  return m;
}

DiscrepancyResult find_discrepancy(const FlightData& data, const DerivativeModel& model, const Vehicle& vehicle,
                                   const DiscrepancyOptions& options) {
  if (model.structure != Structure::kLateral3) {
    throw std::invalid_argument("rig discrepancy works on lateral3 models; '" + model.name + "' is " +
                                to_string(model.structure));
  }
  if (options.folds < 4) throw std::invalid_argument("discrepancy: folds must be >= 4");
  if (!(options.partial_f > 0.0)) throw std::invalid_argument("discrepancy: partial F must be > 0");
  if (!(options.delay_max_s > 0.0)) throw std::invalid_argument("discrepancy: delay_max_s must be > 0");
  for (const auto& name : options.candidates) {
    if (find_effect(name) == nullptr) {
      throw std::invalid_argument("unknown candidate '" + name + "' (known: " + effect_name_list() + ")");
    }
  }

  DiscrepancyResult res;
  res.source = data.source;
  res.model_name = model.name;
  const std::vector<std::string> inputs = options.inputs.empty() ? model.inputs : options.inputs;
  for (const auto& in : inputs) {
    if (!data.has(in)) throw DataError(data.source, -1, -1, in, "the model's input " + in + " is not in the data");
  }
  PreparedData prep = prepare(data, Structure::kLateral3, model.trim, vehicle.gravity_mps2, options.processing);
  add_applied_command(prep.filtered, options.command_latency_s);
  const UniformData& d = prep.filtered;
  const Index n = d.size();
  if (n < static_cast<Index>(50 * options.folds)) {
    throw DataError(data.source, -1, -1, "", std::to_string(n) + " samples are too few for " +
                                                 std::to_string(options.folds) + "-fold cross-validation");
  }
  res.rate_hz = d.rate_hz;
  res.cutoff_hz = options.processing.filter_order > 0 ? options.processing.cutoff_hz : 0.0;
  res.t_s = d.t_s;
  res.samples = static_cast<std::size_t>(n);
  res.folds = options.folds;

  // Baseline equations (the model's structure with the effects the model file carries).
  const auto equations = lateral_equations(Structure::kLateral3, inputs, vehicle);
  std::vector<std::string> known;
  std::map<std::string, double> known_values;
  Model m = build_baseline(d, equations, model, vehicle, data.source, &known, &known_values);

  Workflow wf{options, vehicle, model, d, make_folds(n, options.folds), {}, 0.0};
  wf.batch.min_block = static_cast<Index>(4 * whiteness_lag_step(0, options.processing));
  wf.p_critical = chi_square_survival(options.partial_f, 1.0);

  std::vector<const CandidateSpec*> pool;
  for (const auto& c : candidate_library()) {
    if (options.candidates.empty() ||
        std::find(options.candidates.begin(), options.candidates.end(), c.name) != options.candidates.end()) {
      pool.push_back(&c);
    }
  }

  // Baseline fit and its held-out residuals.
  std::vector<VectorXd> base_resid;
  res.baseline = full_fit(m, wf.batch, &base_resid);
  const std::vector<VectorXd> cv_before = heldout_residuals(m, wf.folds);

  // Stepwise search.
  std::vector<std::string> entered = known;
  for (std::size_t round = 1; round <= options.max_effects; ++round) {
    const std::vector<FoldStats> base = model_stats(m, wf.folds);
    const std::vector<VectorXd> base_cv = heldout_residuals(m, wf.folds);
    struct Pass {
      std::size_t trial;
      std::vector<Addition> adds;
    };
    std::vector<Pass> passing;
    for (const CandidateSpec* spec : pool) {
      if (spec->wideband || spec->stochastic) continue;  // the wideband and signature stages below
      if (std::find(entered.begin(), entered.end(), spec->name) != entered.end()) continue;
      std::vector<Addition> adds;
      res.candidates.push_back(wf.trial(*spec, m, base, base_cv, round, adds));
      if (res.candidates.back().passed) passing.push_back({res.candidates.size() - 1, std::move(adds)});
    }
    if (passing.empty()) break;
    std::size_t best = 0;
    for (std::size_t i = 1; i < passing.size(); ++i) {
      if (res.candidates[passing[i].trial].heldout_drop > res.candidates[passing[best].trial].heldout_drop) best = i;
    }
    // Another passing candidate that explains the same thing: ambiguous.
    for (std::size_t i = 0; i < passing.size(); ++i) {
      if (i == best) continue;
      double rho_max = 0.0;
      for (const auto& a : passing[best].adds) {
        for (const auto& b : passing[i].adds) {
          if (a.eq != b.eq) continue;
          const MatrixXd X = m.X(a.eq);
          for (const auto& ca : a.cols) {
            for (const auto& cb : b.cols) rho_max = std::max(rho_max, std::fabs(residual_correlation(X, ca, cb)));
          }
        }
      }
      if (rho_max > options.collinearity) {
        res.ambiguous.push_back({res.candidates[passing[best].trial].name, res.candidates[passing[i].trial].name});
        res.candidates[passing[i].trial].reason +=
            "; explains the same as " + res.candidates[passing[best].trial].name + " (|rho| " + fmt(rho_max) + ")";
      }
    }
    CandidateTrial& win = res.candidates[passing[best].trial];
    win.entered = true;
    win.reason = "entered: " + win.reason;
    entered.push_back(win.name);
    for (auto& a : passing[best].adds) m.added[a.eq].push_back(std::move(a));
    m.effect_names.push_back(win.name);
    // Candidates that passed with this one but explain the same thing are not tried again.
    for (const auto& pair : res.ambiguous) {
      if (pair[0] == win.name) entered.push_back(pair[1]);
    }
  }

  // Wideband stage: flapping forcing lies above the identification low-pass. The model as
  // it now stands (baseline, known and named effects) is refit on the same data low-passed at
  // flapping_cutoff_hz, and harmonics at a frequency scanned over the flapping band are tried
  // with the same entry rule (Bonferroni over the independent frequencies of the band).
  const auto flapping = std::find_if(pool.begin(), pool.end(), [](const CandidateSpec* c) { return c->wideband; });
  if (flapping != pool.end() && std::find(known.begin(), known.end(), (*flapping)->name) == known.end()) {
    ProcessingOptions wide_proc = options.processing;
    wide_proc.filter_order = 10;
    wide_proc.cutoff_hz = std::min(options.flapping_cutoff_hz, 0.4 * options.processing.rate_hz);
    PreparedData wide = prepare(data, Structure::kLateral3, model.trim, vehicle.gravity_mps2, wide_proc);
    add_applied_command(wide.filtered, options.command_latency_s);
    Model wm = build_baseline(wide.filtered, equations, model, vehicle, data.source, nullptr, nullptr);
    for (const auto& name : m.effect_names) {
      const CandidateSpec& spec = *find_effect(name);
      Index k = 0;
      for (const auto& t : res.candidates) {
        if (t.name == name && t.entered && spec.scanned) k = std::lround(t.delay_s * wide.filtered.rate_hz);
      }
      for (auto& a : candidate_columns(spec, wide.filtered, model.trim, vehicle.gravity_mps2, k)) wm.added[a.eq].push_back(a);
    }
    BatchRule wide_batch = wf.batch;
    wide_batch.min_block = static_cast<Index>(4 * whiteness_lag_step(0, wide_proc));
    CandidateTrial t = flapping_trial(wm, wide.filtered, wf.folds, options, wf.p_critical, wide_batch);
    if (t.passed) {
      t.entered = true;
      t.reason = "entered: " + t.reason;
      NamedEffect eff;
      eff.name = t.name;
      eff.parameters = t.parameters;
      eff.sigma = t.sigma;
      res.effects.push_back(eff);
      m.effect_names.push_back(t.name);
    }
    res.candidates.push_back(std::move(t));
  }

  // The augmented fit and the gap after.
  std::vector<VectorXd> aug_resid;
  res.augmented = full_fit(m, wf.batch, &aug_resid);
  const std::vector<VectorXd> cv_after = heldout_residuals(m, wf.folds);
  // A side wind has no regressor: named from its signature in the final residual.
  const auto gust = std::find_if(pool.begin(), pool.end(), [](const CandidateSpec* c) { return c->stochastic; });
  CandidateTrial gust_result;
  const double f_ref_hi =
      options.processing.filter_order > 0 ? 0.6 * options.processing.cutoff_hz : 0.45 * d.rate_hz;
  if (gust != pool.end() && std::find(known.begin(), known.end(), (*gust)->name) == known.end()) {
    std::vector<VectorXd> extra;  // Y columns of every deterministic candidate the data supports
    for (const auto& c : candidate_library()) {
      if (c.scanned || c.wideband || c.stochastic) continue;
      if (std::find(m.effect_names.begin(), m.effect_names.end(), c.name) != m.effect_names.end()) continue;
      if (std::find(known.begin(), known.end(), c.name) != known.end()) continue;
      if (!std::all_of(c.needs.begin(), c.needs.end(), [&](const std::string& n) { return d.has(n) && excited(d.at(n), n); })) {
        continue;
      }
      for (auto& a : candidate_columns(c, d, model.trim, vehicle.gravity_mps2, 0)) {
        if (m.eqs[a.eq].name != "Y") continue;
        for (auto& col : a.cols) extra.push_back(std::move(col));
      }
    }
    VectorXd given_resid;
    double yv_given = 0.0;
    for (std::size_t e = 0; e < m.eqs.size(); ++e) {
      if (m.eqs[e].name != "Y" || !model.derivatives.count("Yv")) continue;
      given_resid = m.eqs[e].y - given_prediction(m.eqs[e], model, known_values, options);
      yv_given = model.derivatives.at("Yv");
    }
    gust_result = gust_trial(m, aug_resid, res.augmented, d.rate_hz, f_ref_hi, extra, given_resid, yv_given, options,
                             wf.p_critical);
    res.candidates.push_back(gust_result);
  }
  for (const auto& name : m.effect_names) {
    if (name == "flapping_forcing") continue;  // named with its parameters by the wideband stage
    NamedEffect eff;
    eff.name = name;
    const CandidateSpec& spec = *find_effect(name);
    for (const auto& term : spec.terms) {
      const auto it = res.augmented.find(term.parameter);
      if (it == res.augmented.end()) continue;
      eff.parameters[term.parameter] = it->second.value;
      eff.sigma[term.parameter] = it->second.sigma_coloured;
    }
    for (const auto& t : res.candidates) {
      if (t.name == name && t.entered && spec.scanned) eff.parameters["delay_s"] = t.delay_s;
    }
    res.effects.push_back(std::move(eff));
  }

  if (gust_result.entered) res.effects.push_back({gust_result.name, gust_result.parameters, gust_result.sigma});

  // Location, on the baseline structure's residual.
  const Segments seg = find_segments(d, options.segments);
  const double f_hi = options.processing.filter_order > 0 ? 0.8 * options.processing.cutoff_hz : 0.45 * d.rate_hz;
  for (std::size_t e = 0; e < m.eqs.size(); ++e) {
    const VectorXd r = base_resid[e] / m.eqs[e].scale;
    time_findings(m.eqs[e].output, r, d, seg, options.window_s, res.located.time);
    frequency_peaks(m.eqs[e].output, r, d.rate_hz, 0.5, f_hi, options.location_alpha / 2.0, res.located.frequency);
  }
  {
    Model base_model = m;
    for (auto& a : base_model.added) a.clear();
    for (std::size_t e = 0; e < m.eqs.size(); ++e) {
      state_findings(base_model, e, d, wf.batch, options.location_alpha / 2.0, res.located.state);
    }
  }

  // Gap table.
  const std::size_t lag_step = whiteness_lag_step(0, options.processing);
  double gb = 0.0, ga = 0.0;
  for (std::size_t e = 0; e < m.eqs.size(); ++e) {
    const Eq& eq = m.eqs[e];
    OutputGap g;
    g.output = eq.output;
    g.unit = eq.unit;
    const VectorXd model_fit = given_prediction(eq, model, known_values, options);
    const VectorXd y = eq.y / eq.scale;
    const double sst = (y.array() - y.mean()).square().sum();
    const VectorXd rb = cv_before[e] / eq.scale, ra = cv_after[e] / eq.scale;
    g.rmse_model = std::sqrt((eq.y - model_fit).squaredNorm() / static_cast<double>(n)) / eq.scale;
    g.rmse_before = std::sqrt(rb.squaredNorm() / static_cast<double>(n));
    g.rmse_after = std::sqrt(ra.squaredNorm() / static_cast<double>(n));
    g.fit_before_pct = 100.0 * (1.0 - rb.norm() / std::sqrt(sst));
    g.fit_after_pct = 100.0 * (1.0 - ra.norm() / std::sqrt(sst));
    g.white_before = residual_whiteness(rb, d.rate_hz, options.whiteness_lags, lag_step).white;
    g.white_after = residual_whiteness(ra, d.rate_hz, options.whiteness_lags, lag_step).white;
    for (const auto& f : res.located.frequency) {
      if (f.output != eq.output) continue;
      const Psd pb = periodogram(rb, d.rate_hz), pa = periodogram(ra, d.rate_hz);
      const Index k = static_cast<Index>(std::lround(f.f_hz / pb.df_hz));
      g.peak_psd_before = pb.psd[k];
      g.peak_psd_after = pa.psd[k];
    }
    g.measured = y;
    g.predicted_before = y - rb;
    g.predicted_after = y - ra;
    gb += rb.squaredNorm() / sst;
    ga += ra.squaredNorm() / sst;
    res.gap.push_back(g);
  }
  res.gap_before = gb / static_cast<double>(m.eqs.size());
  res.gap_after = ga / static_cast<double>(m.eqs.size());
  res.gap_metric =
      "mean over the equations (L, Y, and F when the data has the actuator command) of the held-out squared equation error divided by the sum of squares of the "
      "dependent about its mean (1 - R^2 on data the fit did not see, " + std::to_string(options.folds) +
      "-fold cross-validation over contiguous blocks)";

  // Verdict.
  const bool structure_found = !res.located.frequency.empty() || !res.located.state.empty();
  if (!res.ambiguous.empty()) {
    res.verdict = "ambiguous";
  } else if (!res.effects.empty()) {
    res.verdict = "effects";
  } else if (structure_found) {
    res.verdict = "unexplained";
  } else {
    res.verdict = "none";
  }
  std::ostringstream s;
  if (res.verdict == "effects" || res.verdict == "ambiguous") {
    s << "named:";
    for (const auto& e : res.effects) s << " " << e.name;
    for (const auto& pair : res.ambiguous) s << "; " << pair[0] << " and " << pair[1] << " explain the same thing";
    s << "; held-out gap " << fmt(res.gap_before) << " -> " << fmt(res.gap_after);
    if (gust_result.entered) {
      s << " (lateral_gust is random: it has no regressor and leaves the gap as it is; its evidence is the "
           "residual spectrum)";
    }
  } else if (res.verdict == "unexplained") {
    s << "no candidate passes, but the residual has structure:";
    for (const auto& f : res.located.frequency) s << " " << f.output << " peak at " << fmt(f.f_hz) << " Hz;";
    for (const auto& f : res.located.state) s << " " << f.output << " depends nonlinearly on " << f.signal << ";";
  } else {
    s << "nothing significant: no candidate passes and the residual shows no structure";
  }
  res.summary = s.str();

  // The augmented model.
  DerivativeModel& am = res.augmented_model;
  am = model;
  am.name = model.name + "_augmented";
  am.source = "rig discrepancy " + data.source + " on " + model.name;
  am.inputs = inputs;
  am.derivatives.clear();
  am.published_sigma.clear();
  am.published_eigenvalues.clear();
  std::vector<std::string> names = stability_derivative_names(Structure::kLateral3);
  for (const auto& in : inputs) {
    for (const auto& nm : control_derivative_names(Structure::kLateral3, in)) names.push_back(nm);
  }
  for (const auto& nm : names) {
    am.derivatives[nm] = res.augmented.at(nm).value;
    am.published_sigma[nm] = res.augmented.at(nm).sigma_coloured;
  }
  am.effects.clear();
  for (const auto& name : known) {
    const auto& spec = *find_effect(name);
    for (const auto& term : spec.terms) {
      const auto it = res.augmented.find(term.parameter);
      if (it != res.augmented.end()) am.effects[name][term.parameter] = it->second.value;
    }
    const auto& given = model.effects.at(name);
    if (given.count("delay_s")) am.effects[name]["delay_s"] = given.at("delay_s");
    if (spec.stochastic) am.effects[name] = given;
  }
  for (const auto& e : res.effects) am.effects[e.name] = e.parameters;
  return res;
}

}  // namespace nimble::ident
