// The discrepancy workflow (discrepancy/discrepancy.h), part: the held-out gap: each equation's error
// before and after, the scalar gap, and the gap in the band where each named effect's evidence
// lives (BandGap), beside the gap in the identification band.

#include "discrepancy/discrepancy_parts.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "ident/metrics.h"
#include "ident/spectrum.h"

namespace nimble::ident::discrepancy_parts {

namespace {

/// Sum of squares of each periodogram bin of x (the mean at 0 Hz), so that they add up to
/// x' x: bin k holds n psd_k df (Parseval), bin 0 also n mean^2.
VectorXd bin_energy(const VectorXd& x, const Psd& P) {
  const double n = static_cast<double>(x.size());
  VectorXd e = P.psd * (n * P.df_hz);
  e[0] += n * x.mean() * x.mean();
  return e;
}

double dependent_ss(const VectorXd& y) { return (y.array() - y.mean()).square().sum(); }

}  // namespace

double band_energy(const VectorXd& x, double rate_hz, double lo_hz, double hi_hz) {
  const Psd P = periodogram(x, rate_hz);
  const VectorXd e = bin_energy(x, P);
  double sum = 0.0;
  for (Index k = 0; k < e.size(); ++k) {
    if (P.f_hz[k] >= lo_hz && P.f_hz[k] <= hi_hz) sum += e[k];
  }
  return sum;
}

std::pair<double, double> energy_band(const VectorXd& x, double rate_hz, double share) {
  const Psd P = periodogram(x, rate_hz);
  const VectorXd e = bin_energy(x, P);
  const double total = e.sum();
  const double T = static_cast<double>(x.size()) / rate_hz;
  if (!(total > 0.0)) return {0.0, 1.0 / T};
  const double lo_q = 0.5 * (1.0 - share) * total, hi_q = 0.5 * (1.0 + share) * total;
  double cum = 0.0, lo = 0.0, hi = P.f_hz[P.f_hz.size() - 1];
  bool have_lo = false;
  for (Index k = 0; k < e.size(); ++k) {
    cum += e[k];
    if (!have_lo && cum >= lo_q) {
      lo = P.f_hz[k];
      have_lo = true;
    }
    if (cum >= hi_q) {
      hi = P.f_hz[k];
      break;
    }
  }
  return {lo, std::max(hi, lo + 1.0 / T)};  // at least the record's resolution
}

BandGap band_gap(const std::string& name, const Model& m, const std::vector<std::size_t>& eqs,
                 const std::vector<VectorXd>& before, const std::vector<VectorXd>& after, double rate_hz, double lo_hz,
                 double hi_hz, const std::vector<VectorXd>* contribution) {
  BandGap g;
  g.name = name;
  g.lo_hz = lo_hz;
  g.hi_hz = hi_hz;
  double explained = 0.0;  // the share of the held-out error in the band the effect's contribution could remove
  for (std::size_t e : eqs) {
    g.equations.push_back(m.eqs[e].name);
    const double sst = dependent_ss(m.eqs[e].y);
    if (!(sst > 0.0)) continue;
    const double b = band_energy(before[e], rate_hz, lo_hz, hi_hz);
    g.before += b / sst;
    g.after += band_energy(after[e], rate_hz, lo_hz, hi_hz) / sst;
    if (contribution && b > 0.0) explained += band_energy((*contribution)[e], rate_hz, lo_hz, hi_hz) / b;
  }
  const double k = static_cast<double>(std::max<std::size_t>(1, eqs.size()));
  g.before /= k;
  g.after /= k;
  explained /= k;
  if (contribution && g.before > 0.0 && g.after > kBandShrink * g.before) {
    std::ostringstream note;
    note << "what the effect adds beyond the model's own regressors is " << std::lround(100.0 * explained)
         << " % of the held-out error in its band: the rest is noise no term of the model removes";
    g.note = note.str();
  }
  return g;
}

/// The gap table: each equation's held-out error before and after, and the mean gap.
void gap_table(const UniformData& d, const DerivativeModel& model, const DiscrepancyOptions& options,
               const std::map<std::string, double>& known_values, const Model& m,
               const std::vector<VectorXd>& cv_before, const std::vector<VectorXd>& cv_after, DiscrepancyResult& res) {
  // Gap table.
  const Index n = d.size();
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
    const Whiteness wb = residual_whiteness(rb, d.rate_hz, options.whiteness_lags, lag_step);
    g.white_before = wb.white;
    g.white_after = residual_whiteness(ra, d.rate_hz, options.whiteness_lags, lag_step).white;
    g.white_tested = wb.tested;
    if (!wb.tested && e == 0) res.notes.push_back(wb.note);
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
      "mean over the equations (L, Y, and F when the data has the actuator command) of the held-out squared equation "
      "error divided by the sum of squares of the "
      "dependent about its mean (1 - R^2 on data the fit did not see, " +
      std::to_string(options.folds) + "-fold cross-validation over contiguous blocks)";
}

/// The gap in the identification band, in the band of each named effect's fitted contribution
/// (kEffectBandShare of its energy, in the equations it entered), and the wideband stage's bands.
void gap_bands(const UniformData& d, const DiscrepancyOptions& options, const Model& m,
               const std::vector<VectorXd>& cv_before, const std::vector<VectorXd>& cv_after, std::vector<BandGap> wide,
               DiscrepancyResult& res) {
  BandGap id;
  id.name = "identification band";
  for (const auto& eq : m.eqs) id.equations.push_back(eq.name);
  id.hi_hz = res.cutoff_hz > 0.0 ? res.cutoff_hz : 0.5 * d.rate_hz;
  id.before = res.gap_before;
  id.after = res.gap_after;
  res.gap_bands.push_back(id);
  for (const auto& e : res.effects) {
    const CandidateSpec* spec = effects::find_definition(e.name);
    if (spec == nullptr || !spec->stochastic()) continue;
    // A side wind has no regressor: its band (below the gust band, the side-force equation) is
    // where its evidence is, and the gap there stays as it is.
    for (std::size_t k = 0; k < m.eqs.size(); ++k) {
      if (m.eqs[k].name != "Y") continue;
      BandGap g = band_gap(e.name, m, {k}, cv_before, cv_after, d.rate_hz, 0.0, options.gust_band_hz, nullptr);
      g.note =
          "random: a side wind has no regressor, so no model term removes it; its evidence is the side-force "
          "residual's excess below the gust band";
      res.gap_bands.push_back(std::move(g));
    }
  }
  for (const auto& name : m.effect_names) {
    // The effect's parameters: a library effect's terms, or a found term's one coefficient.
    std::vector<std::string> params;
    if (is_found_term(name)) {
      params.push_back(name.substr(std::string(kTermPrefix).size()));
    } else {
      const CandidateSpec& spec = *effects::find_definition(name);
      if (spec.wideband() || spec.stochastic()) continue;
      for (const auto& t : spec.terms) params.push_back(t.parameter);
    }
    std::vector<std::size_t> eqs;
    std::vector<VectorXd> contribution(m.eqs.size(), VectorXd::Zero(d.size()));
    for (std::size_t e = 0; e < m.eqs.size(); ++e) {
      for (const auto& add : m.added[e]) {
        const bool mine = std::any_of(params.begin(), params.end(), [&](const std::string& p) {
          return std::find(add.names.begin(), add.names.end(), p) != add.names.end();
        });
        if (!mine) continue;
        for (std::size_t j = 0; j < add.cols.size(); ++j) {
          const auto it = res.augmented.find(add.names[j]);
          if (it == res.augmented.end()) continue;
          contribution[e] +=
              (m.eqs[e].w.size() ? VectorXd(add.cols[j].cwiseProduct(m.eqs[e].w)) : add.cols[j]) * it->second.value;
        }
        if (std::find(eqs.begin(), eqs.end(), e) == eqs.end()) eqs.push_back(e);
      }
    }
    if (eqs.empty()) continue;
    // The band from the equation where the contribution is largest against the dependent.
    std::size_t e_max = eqs.front();
    double share_max = -1.0;
    for (std::size_t e : eqs) {
      const VectorXd& y = m.eqs[e].y;
      const double share = contribution[e].squaredNorm() / std::max(1e-300, (y.array() - y.mean()).square().sum());
      if (share > share_max) {
        share_max = share;
        e_max = e;
      }
    }
    const auto [lo, hi] = energy_band(contribution[e_max], d.rate_hz, kEffectBandShare);
    // What the effect adds beyond the baseline's own regressors: its contribution with them
    // projected out (a v|v| column is mostly v).
    std::vector<VectorXd> unique = contribution;
    for (std::size_t e : eqs) {
      const MatrixXd X = augmented_design(m.eqs[e], {});
      VectorXd th;
      if (solve(X.transpose() * X, X.transpose() * contribution[e], th)) unique[e] -= X * th;
    }
    res.gap_bands.push_back(band_gap(is_found_term(name) ? "term " + params.front() : name, m, eqs, cv_before, cv_after,
                                     d.rate_hz, lo, hi, &unique));
  }
  for (auto& b : wide) res.gap_bands.push_back(std::move(b));
}

}  // namespace nimble::ident::discrepancy_parts
