// The discrepancy workflow (discrepancy/discrepancy.h), part: data compatibility, the sensors' own errors
// estimated from the kinematics before any aerodynamic term (discrepancy/data_compatibility.h).

#include "discrepancy/data_compatibility.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <boost/math/distributions/normal.hpp>
#include <boost/math/distributions/students_t.hpp>

#include "discrepancy/discrepancy_compat_parts.h"
#include "discrepancy/discrepancy_parts.h"
#include "discrepancy/discrepancy_pool_parts.h"
#include "ident/identify.h"

namespace nimble::ident {

namespace {

using namespace discrepancy_parts;

std::string num(double x) { return fmt(x, 4); }

/// The two-sided normal quantile of alpha (2.576 at 0.01): the signatures' comparisons and the
/// offset's test against zero.
double two_sided_z(double alpha) {
  return boost::math::quantile(boost::math::complement(boost::math::normal(), 0.5 * alpha));
}

/// Median interval between a channel's stamps [s] (0 for fewer than 2 samples).
double median_interval(const Channel& c) {
  if (c.t_s.size() < 2) return 0.0;
  std::vector<double> d(c.t_s.size() - 1);
  for (std::size_t i = 1; i < c.t_s.size(); ++i) d[i - 1] = c.t_s[i] - c.t_s[i - 1];
  std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
  return d[d.size() / 2];
}

/// A least-squares fit with its coloured covariance. Rows outside a subset are zero in X and y,
/// so the batch means run over the record's own contiguous blocks.
struct LsFit {
  VectorXd theta;
  MatrixXd cov;
  double blocks = 0.0;
  bool ok = false;
};

LsFit fit(const MatrixXd& X, const VectorXd& y, Index min_block) {
  LsFit f;
  const MatrixXd G = X.transpose() * X;
  const Eigen::LDLT<MatrixXd> ldlt(G);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().array() > 1e-12 * G.diagonal().maxCoeff()).all()) return f;
  f.theta = ldlt.solve(X.transpose() * y);
  const VectorXd e = y - X * f.theta;
  const BatchRule rule{min_block};
  const Index block = rule.block(e);
  f.cov = coloured_covariance(X, e, block);
  f.blocks = block_count(X.rows(), block);
  f.ok = f.theta.allFinite() && f.cov.allFinite();
  return f;
}

double sd(const MatrixXd& cov, const VectorXd& g) { return std::sqrt(std::max(0.0, g.dot(cov * g))); }

/// tau of a fit on [x_L, xdot_L, (1)]: L / rate + beta / a, and its standard deviation.
void tau_of(const LsFit& f, double shift_s, double& tau, double& sigma) {
  const double a = f.theta[0], beta = f.theta[1];
  tau = shift_s + beta / a;
  VectorXd g = VectorXd::Zero(f.theta.size());
  g[0] = -beta / (a * a);
  g[1] = 1.0 / a;
  sigma = sd(f.cov, g);
}

/// k of a fit: 1 / a - 1, and its standard deviation.
void scale_of(const LsFit& f, double& k, double& sigma) {
  const double a = f.theta[0];
  k = 1.0 / a - 1.0;
  VectorXd g = VectorXd::Zero(f.theta.size());
  g[0] = -1.0 / (a * a);
  sigma = sd(f.cov, g);
}

/// b of a fit with an intercept (last column): -c / a, and its standard deviation.
void bias_of(const LsFit& f, double& b, double& sigma) {
  const Index q = f.theta.size();
  const double a = f.theta[0], c = f.theta[q - 1];
  b = -c / a;
  VectorXd g = VectorXd::Zero(q);
  g[0] = c / (a * a);
  g[q - 1] = -1.0 / a;
  sigma = sd(f.cov, g);
}

/// An estimate and its standard deviation.
struct ValueSd {
  double value = 0.0;
  double sd = 0.0;
};

/// A signature test: two estimates of one error, compared in `unit`.
struct SignatureTest {
  std::string what;        ///< what is compared, for the note ("bias in the first and the second half")
  std::string unit;        ///< the unit of the values ("" for a ratio)
  double tolerance = 0.0;  ///< a difference up to this is no difference [unit]
  double alpha = 0.05;     ///< the test's level (two-sided)
  double factor = 1.0;     ///< a fit's estimate times this is in `unit`
};

/// Whether two estimates of the same error agree: their difference beyond the tolerance, against
/// its standard deviation, within the two-sided normal quantile of alpha. `note` says so.
bool agree(const ValueSd& a, const ValueSd& b, const SignatureTest& t, std::string& note) {
  const double z = two_sided_z(t.alpha);
  const double sd_diff = std::hypot(a.sd, b.sd);
  const double excess = std::max(0.0, std::fabs(a.value - b.value) - t.tolerance);
  const bool ok = excess <= z * sd_diff;
  note = t.what + ": " + num(a.value) + " +- " + num(a.sd) + " and " + num(b.value) + " +- " + num(b.sd) + " " +
         t.unit +
         (ok ? " agree" : " differ beyond the tolerance (" + num(excess / sd_diff) + " sd, limit " + num(z) + ")");
  return ok;
}

/// Tests one error: its excess over the tolerance, the interval.
void test_error(SensorError& e, double blocks, double p_critical) {
  const double tq = boost::math::quantile(boost::math::students_t(std::max(1.0, blocks - 1.0)), 0.975);
  e.interval[0] = e.value - tq * e.sigma;
  e.interval[1] = e.value + tq * e.sigma;
  const double excess = std::max(0.0, std::fabs(e.value) - e.tolerance);
  const double w = e.sigma > 0.0 ? (excess / e.sigma) * (excess / e.sigma) : (excess > 0.0 ? INFINITY : 0.0);
  e.p_value = wald_tail(w, 1, blocks);
  e.significant = e.p_value <= p_critical;
}

/// The columns of the kinematic regression at a shift of L samples over rows [r0, r0 + n): x, its
/// derivative (the shift's refinement), with `tc` (the rows' times from their middle [s]) the
/// derivative times tc (a drift of the shift: the clock's rate), and with `intercept` a constant.
MatrixXd kin_design(const VectorXd& x, const VectorXd& xd, Index r0, Index n, Index L, bool intercept,
                    const VectorXd* tc = nullptr) {
  MatrixXd X(n, 2 + (tc ? 1 : 0) + (intercept ? 1 : 0));
  X.col(0) = x.segment(r0 + L, n);
  X.col(1) = xd.segment(r0 + L, n);
  if (tc) X.col(2) = xd.segment(r0 + L, n).cwiseProduct(*tc);
  if (intercept) X.col(X.cols() - 1).setOnes();
  return X;
}

/// The clock's drift of a fit with the drift column (the third): gamma / a [s/s], and its sd.
void drift_of(const LsFit& f, double& d, double& sigma) {
  const double a = f.theta[0], gamma = f.theta[2];
  d = gamma / a;
  VectorXd g = VectorXd::Zero(f.theta.size());
  g[0] = -gamma / (a * a);
  g[2] = 1.0 / a;
  sigma = sd(f.cov, g);
}

/// The whole-sample shift of x (in -M..M) that fits y best (least RSS with a gain and an offset).
Index best_shift(const VectorXd& x, const VectorXd& y, Index r0, Index n, Index M) {
  std::vector<double> s1(static_cast<std::size_t>(x.size()) + 1, 0.0), s2(s1.size(), 0.0);
  for (Index i = 0; i < x.size(); ++i) {
    s1[static_cast<std::size_t>(i) + 1] = s1[static_cast<std::size_t>(i)] + x[i];
    s2[static_cast<std::size_t>(i) + 1] = s2[static_cast<std::size_t>(i)] + x[i] * x[i];
  }
  const VectorXd ys = y.segment(r0, n);
  const double N = static_cast<double>(n), sy = ys.sum();
  Index best = 0;
  double best_rss = INFINITY;
  for (Index L = -M; L <= M; ++L) {
    const auto a = static_cast<std::size_t>(r0 + L), b = static_cast<std::size_t>(r0 + L + n);
    const double sx = s1[b] - s1[a], sxx = s2[b] - s2[a] - sx * sx / N;
    const double sxy = x.segment(r0 + L, n).dot(ys) - sx * sy / N;
    if (sxx <= 0.0) continue;
    const double rss = -sxy * sxy / sxx;  // RSS minus the constant centred sum of squares of y
    if (rss < best_rss) {
      best_rss = rss;
      best = L;
    }
  }
  return best;
}

/// Rows of X and y kept where `keep` is true, the others zero (see LsFit).
LsFit fit_subset(MatrixXd X, VectorXd y, const std::vector<char>& keep, Index min_block) {
  for (Index i = 0; i < y.size(); ++i) {
    if (!keep[static_cast<std::size_t>(i)]) {
      X.row(i).setZero();
      y[i] = 0.0;
    }
  }
  return fit(X, y, min_block);
}

/// The rows of a regression: design, response, and the block length of its sandwich variance.
struct Rows {
  const MatrixXd& X;
  const VectorXd& y;
  Index min_block = 1;
};

/// An error's estimate on the rows in `part` and on the others (as fit_subset), compared by agree();
/// true (nothing against it) when a part cannot be fitted.
bool parts_agree(const Rows& rows, const std::vector<char>& part, void (*estimate)(const LsFit&, double&, double&),
                 const SignatureTest& t, std::string& note) {
  std::vector<char> rest(part.size());
  for (std::size_t i = 0; i < part.size(); ++i) rest[i] = !part[i];
  const LsFit f1 = fit_subset(rows.X, rows.y, part, rows.min_block),
              f2 = fit_subset(rows.X, rows.y, rest, rows.min_block);
  if (!f1.ok || !f2.ok) {
    note = t.what + ": a part could not be fitted";
    return true;
  }
  ValueSd e1, e2;
  estimate(f1, e1.value, e1.sd);
  estimate(f2, e2.value, e2.sd);
  return agree({t.factor * e1.value, t.factor * e1.sd}, {t.factor * e2.value, t.factor * e2.sd}, t, note);
}

/// The two sides of the kinematic relation on the record low-passed as for identification: the
/// gyro side x (p, plus tan(theta) (q sin(phi) + r cos(phi)) where q, r and theta are recorded),
/// its derivative, and phi's derivative y.
struct Kinematics {
  UniformData u;
  VectorXd x, xd, y;
  std::string equation;
};

Kinematics kinematics(const FlightData& data, const ProcessingOptions& processing) {
  const bool full = data.has("q") && data.has("r") && data.has("theta");
  FlightData sub;
  sub.source = data.source;
  for (const char* c : {"p", "phi", "q", "r", "theta"}) {
    if (data.has(c) && (full || std::string(c) == "p" || std::string(c) == "phi")) sub.channels[c] = data.at(c);
  }
  Kinematics k;
  k.u = process(sub, processing);
  k.x = k.u.at("p");
  const VectorXd& phi = k.u.at("phi");
  if (full) {
    const VectorXd &q = k.u.at("q"), &r = k.u.at("r"), &th = k.u.at("theta");
    k.x.array() += th.array().tan() * (q.array() * phi.array().sin() + r.array() * phi.array().cos());
  }
  k.equation = full ? "phi_dot = p + tan(theta) (q sin(phi) + r cos(phi))" : "phi_dot = p";
  k.y = differentiate(phi, k.u.rate_hz);
  k.xd = differentiate(k.x, k.u.rate_hz);
  return k;
}

/// A time offset's signature: a pure time shift, the same lag below and above p's RMS frequency.
void offset_signature(const Kinematics& k, Index r0, Index n, Index L, Index min_block,
                      const ProcessingOptions& processing, double alpha, SensorError& offset) {
  const double fs = k.u.rate_hz;
  const double f_split = std::clamp(std::sqrt(k.xd.squaredNorm() / std::max(1e-300, k.x.squaredNorm())) / (2.0 * M_PI),
                                    0.5, 0.8 * (processing.filter_order > 0 ? processing.cutoff_hz : 0.5 * fs));
  const VectorXd xh = high_pass(k.x, f_split, fs), yh = high_pass(k.y, f_split, fs);
  const VectorXd xl = k.x - xh, yl = k.y - yh;
  const LsFit fh = fit(kin_design(xh, differentiate(xh, fs), r0, n, L, false), yh.segment(r0, n), min_block);
  const LsFit fl = fit(kin_design(xl, differentiate(xl, fs), r0, n, L, true), yl.segment(r0, n), min_block);
  if (!fl.ok || !fh.ok) return;
  const double shift_s = static_cast<double>(L) / fs;
  ValueSd low, high;
  tau_of(fl, shift_s, low.value, low.sd);
  tau_of(fh, shift_s, high.value, high.sd);
  const SignatureTest t{"lag below and above " + num(f_split) + " Hz", "s", offset.tolerance, alpha};
  offset.signature_holds = agree(low, high, t, offset.signature_note);
}

}  // namespace

CompatibilityResult check_compatibility(const FlightData& data, const ProcessingOptions& processing,
                                        const CompatibilityOptions& options, double p_critical, std::size_t folds,
                                        std::size_t min_block) {
  if (!(options.max_offset_s >= 0.0) || !(options.scale_tolerance >= 0.0) || !(options.bias_tolerance_radps >= 0.0) ||
      !(options.time_tolerance_s >= 0.0) || !(options.signature_alpha > 0.0 && options.signature_alpha < 1.0)) {
    throw std::invalid_argument(
        "discrepancy: invalid compatibility options (offsets and tolerances >= 0, alpha in (0, 1))");
  }
  CompatibilityResult res;
  res.source = data.source;
  if (!data.has("p") || !data.has("phi")) {
    res.note = "the record lacks p or phi: the kinematics cannot be checked";
    return res;
  }
  const Kinematics k = kinematics(data, processing);
  const UniformData& u = k.u;
  const VectorXd &x = k.x, &y = k.y, &xd = k.xd;
  const double fs = u.rate_hz;
  res.equation = k.equation;
  const Index M = static_cast<Index>(std::ceil(options.max_offset_s * fs));
  const Index r0 = M + 4, n = u.size() - 2 * r0;
  if (n < static_cast<Index>(50 * folds)) {
    res.note = "the record is too short for the kinematic check with offsets up to " + num(options.max_offset_s) + " s";
    return res;
  }
  const VectorXd ys = y.segment(r0, n);
  const Index L = best_shift(x, y, r0, n, M);
  const VectorXd tc = u.t_s.segment(r0, n).array() - 0.5 * (u.t_s[r0] + u.t_s[r0 + n - 1]);
  res.t_mid_s = 0.5 * (u.t_s[r0] + u.t_s[r0 + n - 1]);
  const MatrixXd X = kin_design(x, xd, r0, n, L, true, &tc);
  const LsFit f = fit(X, ys, static_cast<Index>(min_block));
  if (!f.ok || std::fabs(f.theta[0]) < 0.1) {
    res.note = "p does not follow phi's derivative (no gain between them): the kinematics cannot be checked";
    return res;
  }
  res.ran = true;
  res.samples = static_cast<std::size_t>(n);
  res.blocks = f.blocks;
  const double shift_s = static_cast<double>(L) / fs;

  const auto error = [](const std::string& name, const char* unit) {
    SensorError e;
    e.name = name;
    e.channel = "p";
    e.against = "phi";
    e.unit = unit;
    return e;
  };
  SensorError scale = error(kSensorScaleError, "-"), offset = error(kTimeOffsetError, "s"),
              bias = error(kSensorBiasError, "rad/s"), drift = error(kClockDriftError, "ppm");
  scale_of(f, scale.value, scale.sigma);
  tau_of(f, shift_s, offset.value, offset.sigma);
  bias_of(f, bias.value, bias.sigma);
  drift_of(f, drift.value, drift.sigma);
  drift.value *= 1e6;
  drift.sigma *= 1e6;
  scale.tolerance = options.scale_tolerance;
  bias.tolerance = options.bias_tolerance_radps;
  offset.tolerance = options.time_tolerance_s > 0.0
                         ? options.time_tolerance_s
                         : std::max(median_interval(data.at("p")), median_interval(data.at("phi")));
  // A drift that moves the offset by its tolerance over the record.
  drift.tolerance = 1e6 * offset.tolerance / std::max(1e-9, u.t_s[r0 + n - 1] - u.t_s[r0]);
  for (SensorError* e : {&scale, &offset, &bias, &drift}) test_error(*e, f.blocks, p_critical);

  const auto mb = static_cast<Index>(min_block);
  const double alpha = options.signature_alpha;
  std::vector<char> first(static_cast<std::size_t>(n)), small(static_cast<std::size_t>(n));
  VectorXd ax = X.col(0).cwiseAbs();
  std::vector<double> sorted(ax.data(), ax.data() + ax.size());
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2), sorted.end());
  for (Index i = 0; i < n; ++i) {
    first[static_cast<std::size_t>(i)] = i < n / 2;
    small[static_cast<std::size_t>(i)] = ax[i] <= sorted[sorted.size() / 2];
  }
  const Rows rows{X, ys, mb};
  // A scale grows with the signal: the same scale on the samples of small and of large |p|.
  if (scale.significant) {
    const SignatureTest t{"scale on the smaller and the larger half of |p|", "", scale.tolerance, alpha};
    scale.signature_holds = parts_agree(rows, small, scale_of, t, scale.signature_note);
  }
  // A bias is constant, a clock's rate even: the same in both halves of the record (a half's drift
  // moves the offset by the tolerance in twice the rate).
  if (bias.significant) {
    const SignatureTest t{"bias in the first and the second half", "rad/s", bias.tolerance, alpha};
    bias.signature_holds = parts_agree(rows, first, bias_of, t, bias.signature_note);
  }
  if (drift.significant) {
    const SignatureTest t{"drift in the first and the second half", "ppm", 2.0 * drift.tolerance, alpha, 1e6};
    drift.signature_holds = parts_agree(rows, first, drift_of, t, drift.signature_note);
  }
  if (offset.significant) offset_signature(k, r0, n, L, mb, processing, alpha, offset);
  const double z_alpha = two_sided_z(alpha);
  for (SensorError* e : {&scale, &offset, &bias, &drift}) {
    e->named = e->significant && e->signature_holds;
    // An offset is taken out below its tolerance too, once it is told from zero at the signatures'
    // level: one left in the record moves p against delta_f by as much, which the aerodynamic search
    // (more sensitive) fits as a lag of the flap input (a rig flight with a 500 ppm drift: 4.5 ms at
    // the middle, under the 5 ms tolerance, named lag(delta_f, 0.004)). One not told from zero is
    // left (moving p by an estimate of zero adds its own error). A drift, scale or bias is
    // corrected when significant: below tolerance it is within the sensor's calibration.
    e->corrected = e->significant || (e == &offset && std::fabs(offset.value) > z_alpha * offset.sigma);
    res.errors.push_back(*e);
  }

  // As recorded: phi_dot = x (a = 1, tau = 0, c = 0, nothing fitted); corrected: held out.
  const double var = (ys.array() - ys.mean()).square().sum();
  if (var > 0.0) {
    res.kinematic_gap_before = (ys - x.segment(r0, n)).squaredNorm() / var;
    res.kinematic_gap_after = heldout_residual(X, ys, make_folds(n, folds)).squaredNorm() / var;
  }
  return res;
}

FlightData corrected_record(const FlightData& data, const CompatibilityResult& result,
                            const CompatibilityOptions& options) {
  double k = 0.0, tau = 0.0, b = 0.0, drift = 0.0;
  bool any = false;
  for (const auto& e : result.errors) {
    if (!e.corrected) continue;
    any = true;
    if (e.name == kSensorScaleError) k = e.value;
    if (e.name == kTimeOffsetError) tau = e.value;
    if (e.name == kSensorBiasError) b = e.value;
    if (e.name == kClockDriftError) drift = 1e-6 * e.value;
  }
  if (!any) return data;
  FlightData out = data;
  if (tau != 0.0 || drift != 0.0) {
    // The offset at the record's middle and the drift about it, on the attitude's clock.
    for (const auto& c : options.imu_channels) {
      auto it = out.channels.find(c);
      if (it == out.channels.end()) continue;
      for (double& t : it->second.t_s) t -= tau + drift * (t - result.t_mid_s);
    }
  }
  if (k != 0.0 || b != 0.0) {
    for (double& v : out.channels.at("p").values) v = (v - b) / (1.0 + k);
  }
  return out;
}

}  // namespace nimble::ident

namespace nimble::ident::discrepancy_parts {

namespace {

/// The baseline structure's held-out RMSE per equation output on one flight as recorded.
std::map<std::string, double> baseline_rmse(const FlightData& recorded, const DerivativeModel& model,
                                            const Vehicle& vehicle, const std::vector<std::string>& inputs,
                                            const DiscrepancyOptions& options) {
  PreparedData prep = prepare(recorded, Structure::kLateral3, model.trim, vehicle.gravity_mps2, options.processing);
  add_applied_command(prep.filtered, options.command_latency_s);
  const UniformData& d = prep.filtered;
  const Model m = build_baseline(d, lateral_equations(Structure::kLateral3, inputs, vehicle), model, vehicle,
                                 recorded.source, nullptr, nullptr);
  const std::vector<VectorXd> cv = heldout_residuals(m, flight_folds({{0, d.size()}}, options.folds));
  std::map<std::string, double> rmse;
  for (std::size_t e = 0; e < m.eqs.size(); ++e) {
    rmse[m.eqs[e].output] = std::sqrt(cv[e].squaredNorm() / static_cast<double>(cv[e].size())) / m.eqs[e].scale;
  }
  return rmse;
}

const char* parameter_of(const std::string& error) {
  if (error == kSensorScaleError) return "scale_factor";
  if (error == kTimeOffsetError) return "offset_s";
  if (error == kClockDriftError) return "drift_ppm";
  return "bias_radps";
}

}  // namespace

FlightData compatibility_stage(const FlightData& recorded, const DerivativeModel& model, const Vehicle& vehicle,
                               const std::vector<std::string>& inputs, const DiscrepancyOptions& options,
                               DiscrepancyResult& res) {
  if (!options.compatibility.enabled) return recorded;
  const auto start = std::chrono::steady_clock::now();
  CompatibilityResult c =
      check_compatibility(recorded, options.processing, options.compatibility, alarm_p_critical(options), options.folds,
                          static_cast<std::size_t>(batch_min_block(options)));
  FlightData out = corrected_record(recorded, c, options.compatibility);
  for (const SensorError& e : c.errors) {
    if (e.corrected) {
      c.corrections.push_back(e.name == kTimeOffsetError
                                  ? "the IMU's channels restamped by " + num(-e.value) + " s" +
                                        (e.significant ? "" : " (within its tolerance, told from zero)")
                              : e.name == kClockDriftError ? "the IMU's stamps rescaled by " + num(-e.value) +
                                                                 " ppm about t = " + num(c.t_mid_s) + " s"
                              : e.name == kSensorScaleError ? "p divided by 1 + " + num(e.value)
                                                            : "p less its bias " + num(e.value) + " rad/s");
    }
    if (!e.named) continue;
    NamedEffect n;
    n.name = e.name;
    n.channel = e.channel;
    n.against = e.name == kTimeOffsetError || e.name == kClockDriftError ? e.against : "";
    n.unit = e.unit;
    n.flight = recorded.source;
    n.coefficient = e.value;
    n.interval[0] = e.interval[0];
    n.interval[1] = e.interval[1];
    n.parameters[parameter_of(e.name)] = e.value;
    n.sigma[parameter_of(e.name)] = e.sigma;
    res.effects.push_back(std::move(n));
  }
  if (std::any_of(c.errors.begin(), c.errors.end(), [](const SensorError& e) { return e.significant; })) {
    c.rmse_uncorrected = baseline_rmse(recorded, model, vehicle, inputs, options);
  }
  c.elapsed_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  res.compatibility.push_back(std::move(c));
  return out;
}

std::size_t sensor_findings(DiscrepancyResult& res) {
  std::size_t tests = 0;
  const CompatibilityResult* unchecked = nullptr;  // the first flight whose kinematics were not checked
  for (const CompatibilityResult& c : res.compatibility) {
    if (!c.ran) {
      if (unchecked == nullptr) unchecked = &c;
      continue;
    }
    tests += c.errors.size();
    for (const SensorError& e : c.errors) {
      if (!e.significant || e.signature_holds) continue;
      SignatureFinding f;
      f.candidate = e.name;
      f.equations = {"kinematics"};
      f.note = "the kinematics of " + c.source + " show a significant " + e.name + " of " + e.channel + " (" +
               num(e.value) + " " + e.unit + ") without its signature: " + e.signature_note +
               "; the record was corrected for it, unnamed";
      res.located.signature.push_back(std::move(f));
    }
  }
  const auto delay = std::find_if(res.effects.begin(), res.effects.end(), [](const NamedEffect& e) {
    const CandidateSpec* spec = effects::find_definition(e.name);
    return spec != nullptr && spec->scan == effects::Scan::kDelay;
  });
  if (delay != res.effects.end() && unchecked != nullptr) {
    // Without the kinematic check a late gyro and a late actuator look alike in L and Y.
    res.ambiguous.push_back({delay->name, kTimeOffsetError});
    res.notes.push_back(delay->name + " could be a time offset of the IMU: the kinematics of " + unchecked->source +
                        " were not checked (" + unchecked->note +
                        "); a record with p and phi, p excited, tells them apart (a time offset shows in phi_dot = p)");
  }
  return tests;
}

}  // namespace nimble::ident::discrepancy_parts
