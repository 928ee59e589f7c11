// The discrepancy workflow (discrepancy/discrepancy.h), part: the candidates found in the residual's
// spectrum: the lateral gust from its signature in the residual (its bands against the
// reference), the flapping forcing scanned over its band.

#include "discrepancy/discrepancy_parts.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include <boost/math/distributions/fisher_f.hpp>

#include "core/chi_square.h"
#include "ident/metrics.h"
#include "ident/spectrum.h"

namespace nimble::ident::discrepancy_parts {

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

/// The Whittle fit of a first-order wind spectrum A / (1 + (2 pi f tau)^2) + N0 below f_ref_hi
/// (tau on a log grid 0.02-20 s, A from a tenth to a hundred times the low band's excess), and the
/// 95 % interval of tau from its profile.
struct WindFit {
  double tau = 0.0, a = 0.0, tau_lo = 0.0, tau_hi = 0.0;
  double tau_min = 0.0;  ///< the band's premise: the shortest tau with 90 % of the variance below it
  bool reaches = false;  ///< the interval reaches tau_min or beyond
};

WindFit fit_wind(const Psd& Pg, double excess, double N0g, double f_ref_hi, double per_bin, double band_hz) {
  WindFit out;
  double best = std::numeric_limits<double>::infinity();
  std::vector<double> profile(61, std::numeric_limits<double>::infinity());  // over tau, A fitted
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
      profile[static_cast<std::size_t>(i)] = std::min(profile[static_cast<std::size_t>(i)], nll);
      if (nll < best) {
        best = nll;
        out.tau = tau;
        out.a = A;
      }
    }
  }
  // The band's premise: a wind whose correlation time puts 90 % of its variance below the gust
  // band, tau >= tan(0.45 pi) / (2 pi band_hz) (0.50 s at 2 Hz). The profile's 95 % interval: the
  // likelihood ratio scaled by the independent bins per padded bin, against chi2_1's 3.84.
  out.tau_min = std::tan(0.45 * M_PI) / (2.0 * M_PI * band_hz);
  out.tau_lo = out.tau_hi = out.tau;
  for (int i = 0; i <= 60; ++i) {
    const double tau = 0.02 * std::pow(1000.0, i / 60.0);
    if (2.0 * per_bin * (profile[static_cast<std::size_t>(i)] - best) > 3.841458820694124) continue;
    out.tau_lo = std::min(out.tau_lo, tau);
    out.tau_hi = std::max(out.tau_hi, tau);
    out.reaches = out.reaches || tau >= out.tau_min;
  }
  return out;
}

CandidateTrial gust_trial(const CandidateSpec& spec, const Model& m, const GustEvidence& evidence,
                          const DiscrepancyOptions& opt, double p_critical) {
  const std::vector<VectorXd>& resid = evidence.resid;
  const auto& fit = evidence.fit;
  const double rate_hz = evidence.rate_hz, f_ref_hi = evidence.f_ref_hi, yv_given = evidence.yv_given;
  const std::vector<VectorXd>& extra = evidence.extra;
  const VectorXd& given_resid = evidence.given_resid;
  CandidateTrial t;
  t.name = spec.name;
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
  const WindFit fit_w =
      fit_wind(Pg, std::max(0.0, lo_g / static_cast<double>(k_lo) - N0g), N0g, f_ref_hi, per_bin, opt.gust_band_hz);
  const double tau_best = fit_w.tau, a_best = fit_w.a, tau_lo = fit_w.tau_lo, tau_hi = fit_w.tau_hi,
               tau_min = fit_w.tau_min;
  const bool reaches = fit_w.reaches;
  // A low-frequency excess whose spectrum excludes every tau of the band's premise is a random
  // force broader than a wind, coloured process noise like the rest of the equation error that
  // every test allows for, not a side wind: no name and no alarm.
  t.signature["tau_lo_s"] = tau_lo;
  t.signature["tau_hi_s"] = tau_hi;
  t.signature["tau_min_s"] = tau_min;
  if (!reaches) {
    t.parameters["tau_s"] = tau_best;
    t.reason = "no signature: the Y residual's low-frequency excess (" + fmt(ratio) + " times its level above " +
               fmt(opt.gust_band_hz) + " Hz, p " + fmt(t.p_value) + ") has a spectrum of tau " + fmt(tau_best) +
               " s [" + fmt(tau_lo) + ", " + fmt(tau_hi) + "], shorter than the " + fmt(tau_min) +
               " s of a wind with 90 % of its variance below the band: coloured process noise, not a side wind";
    return t;
  }
  const double sigma_force = std::sqrt(a_best / (4.0 * tau_best));
  t.parameters["sigma_mps"] = sigma_force / std::fabs(given ? yv_given : yv->second.value);
  t.parameters["tau_s"] = tau_best;
  // The low band's mean has a relative standard error 1 / sqrt(d_lo / 2); sigma is its square root.
  t.sigma["sigma_mps"] = t.parameters["sigma_mps"] / std::sqrt(2.0 * d_lo);
  t.passed = true;
  t.entered = true;
  t.reason = "entered: the Y residual below " + fmt(opt.gust_band_hz) + " Hz is " + fmt(ratio) +
             " times its level above (p " + fmt(t.p_value) + " <= " + fmt(p_critical) + "), a side wind of about " +
             fmt(t.parameters["sigma_mps"]) + " m/s with tau " + fmt(tau_best) + " s";
  return t;
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

/// The wideband candidate `spec` (the flapping forcing) on wideband data (see the wideband stage of
/// find_discrepancy).
CandidateTrial flapping_trial(const CandidateSpec& spec, const Model& m, const UniformData& d, const Folds& folds,
                              const DiscrepancyOptions& opt, double p_critical, const BatchRule& batch,
                              std::vector<VectorXd>* heldout_before, std::vector<VectorXd>* heldout_after) {
  CandidateTrial t;
  t.name = spec.name;
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
  if (heldout_before) *heldout_before = before;
  if (heldout_after) *heldout_after = after;
  const bool significant = t.p_value <= p_critical;
  const bool pse_falls = !p_eq.empty() && t.pse_after.at(p_eq) < t.pse_before.at(p_eq);
  const bool heldout = t.heldout_drop > 0.0 && t.heldout_drop > opt.heldout_sigmas * t.heldout_se;
  t.passed = significant && pse_falls && heldout;
  std::ostringstream why;
  why << (t.passed ? "passes:" : "fails:") << " at " << fmt(f) << " Hz (band " << fmt(lo) << "-" << fmt(hi) << " Hz, "
      << t.scan_points << " independent frequencies, data low-passed at " << fmt(opt.flapping_cutoff_hz) << " Hz): p "
      << fmt(t.p_value) << (significant ? " <= " : " > ") << fmt(p_critical);
  if (!p_eq.empty()) why << " (F " << fmt(t.partial_f[p_eq]) << " in " << p_eq << ")";
  why << (pse_falls ? ", PSE falls" : ", PSE does not fall") << ", held-out error change "
      << fmt(-100.0 * t.heldout_drop) << " % (spread " << fmt(100.0 * t.heldout_se) << " %)";
  t.reason = why.str();
  return t;
}

}  // namespace nimble::ident::discrepancy_parts
