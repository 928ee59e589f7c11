// The discrepancy workflow (discrepancy/discrepancy.h), part: several flights at once: joined end to
// end with their own folds and noise levels, and each flight's estimate of a named effect with
// the test that they agree.

#include "discrepancy/discrepancy_parts.h"
#include "discrepancy/discrepancy_pool_parts.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "core/chi_square.h"

namespace nimble::ident::discrepancy_parts {

UniformData join_flights(const std::vector<UniformData>& flights, std::vector<std::pair<Index, Index>>& rows) {
  if (flights.empty()) throw std::invalid_argument("discrepancy: no flight to pool");
  UniformData out;
  out.rate_hz = flights.front().rate_hz;
  out.source = flights.front().source;
  Index n = 0;
  for (const auto& f : flights) {
    if (std::fabs(f.rate_hz - out.rate_hz) > 1e-9 * out.rate_hz) {
      throw std::invalid_argument("discrepancy: flights resampled at different rates");
    }
    n += f.size();
  }
  for (std::size_t i = 1; i < flights.size(); ++i) out.source += " + " + flights[i].source;
  out.t_s.resize(n);
  std::vector<std::string> names;
  for (const auto& entry : flights.front().signals) {
    const std::string& name = entry.first;
    if (std::all_of(flights.begin(), flights.end(), [&name](const UniformData& f) { return f.has(name); })) {
      names.push_back(name);
    }
  }
  for (const auto& name : names) out.signals[name].resize(n);
  rows.clear();
  Index a = 0;
  double t_end = 0.0;
  for (const auto& f : flights) {
    const Index k = f.size();
    const double shift = (a == 0 ? 0.0 : t_end + 1.0 / out.rate_hz) - f.t_s[0];
    out.t_s.segment(a, k) = f.t_s.array() + shift;
    for (const auto& name : names) out.signals[name].segment(a, k) = f.at(name);
    rows.push_back({a, a + k});
    a += k;
    t_end = out.t_s[a - 1];
  }
  return out;
}

Folds flight_folds(const std::vector<std::pair<Index, Index>>& rows, std::size_t k) {
  Folds out;
  for (const auto& [a, b] : rows) {
    for (const auto& [fa, fb] : make_folds(b - a, k)) out.push_back({a + fa, a + fb});
  }
  return out;
}

std::vector<std::vector<double>> weight_flights(Model& m, const std::vector<VectorXd>& resid,
                                                const std::vector<std::pair<Index, Index>>& rows) {
  std::vector<std::vector<double>> level(rows.size(), std::vector<double>(m.eqs.size(), 0.0));
  for (std::size_t e = 0; e < m.eqs.size(); ++e) {
    const double pool = std::sqrt(resid[e].squaredNorm() / static_cast<double>(resid[e].size()));
    VectorXd w(resid[e].size());
    for (std::size_t f = 0; f < rows.size(); ++f) {
      const auto [a, b] = rows[f];
      level[f][e] = std::sqrt(resid[e].segment(a, b - a).squaredNorm() / static_cast<double>(b - a));
      w.segment(a, b - a).setConstant(level[f][e] > 0.0 && pool > 0.0 ? pool / level[f][e] : 1.0);
    }
    Eq& eq = m.eqs[e];
    eq.y = eq.y.cwiseProduct(w);
    for (auto& c : eq.cols) c = c.cwiseProduct(w);
    eq.w = w;
  }
  return level;
}

namespace {

/// The final model's equation e on rows [a, b) only: its design, dependent and parameter names.
struct Slice {
  MatrixXd X;
  VectorXd y;
  std::vector<std::string> names;
};

Slice slice(const Model& m, std::size_t e, Index a, Index b) {
  const MatrixXd X = m.X(e);
  return {X.middleRows(a, b - a), m.eqs[e].y.segment(a, b - a), m.names(e)};
}

}  // namespace

void flight_consistency(const Model& m, const BatchRule& batch, const std::vector<std::pair<Index, Index>>& rows,
                        double alpha, DiscrepancyResult& res) {
  for (const auto& effect : m.effect_names) {
    const CandidateSpec* spec = effects::find_definition(effect);
    if (spec == nullptr || spec->terms.empty()) continue;
    FlightConsistency c;
    c.effect = effect;
    std::vector<double> contribution(rows.size(), 0.0);
    for (std::size_t e = 0; e < m.eqs.size(); ++e) {
      // The effect's parameters in this equation.
      const std::vector<std::string> names = m.names(e);
      std::vector<Index> idx;
      for (const auto& t : spec->terms) {
        const auto it = std::find(names.begin(), names.end(), t.parameter);
        if (it != names.end() && t.equation == m.eqs[e].name) idx.push_back(static_cast<Index>(it - names.begin()));
      }
      if (idx.empty()) continue;
      const Index k = static_cast<Index>(idx.size());
      std::vector<VectorXd> theta;
      std::vector<MatrixXd> info;  // inverse covariances of the flights' estimates
      for (std::size_t f = 0; f < rows.size(); ++f) {
        const Slice s = slice(m, e, rows[f].first, rows[f].second);
        VectorXd th;
        if (!solve(s.X.transpose() * s.X, s.X.transpose() * s.y, th)) {
          th = s.X.completeOrthogonalDecomposition().solve(s.y);
        }
        const VectorXd r = s.y - s.X * th;
        const MatrixXd cov = coloured_covariance(s.X, r, batch.block(r));
        VectorXd t(k);
        MatrixXd C(k, k);
        for (Index i = 0; i < k; ++i) {
          t[i] = th[idx[static_cast<std::size_t>(i)]];
          for (Index j = 0; j < k; ++j)
            C(i, j) = cov(idx[static_cast<std::size_t>(i)], idx[static_cast<std::size_t>(j)]);
          res.flights[f].parameters[names[static_cast<std::size_t>(idx[static_cast<std::size_t>(i)])]] = t[i];
          res.flights[f].sigma[names[static_cast<std::size_t>(idx[static_cast<std::size_t>(i)])]] =
              std::sqrt(std::max(0.0, C(i, i)));
        }
        theta.push_back(t);
        info.push_back(C.ldlt().solve(MatrixXd::Identity(k, k)));
      }
      MatrixXd I = MatrixXd::Zero(k, k);
      VectorXd b = VectorXd::Zero(k);
      for (std::size_t f = 0; f < rows.size(); ++f) {
        I += info[f];
        b += info[f] * theta[f];
      }
      const VectorXd mean = I.ldlt().solve(b);
      for (std::size_t f = 0; f < rows.size(); ++f) {
        const VectorXd dev = theta[f] - mean;
        const double q = dev.dot(info[f] * dev);
        contribution[f] += q;
        c.q += q;
      }
      c.dof += static_cast<double>((rows.size() - 1) * static_cast<std::size_t>(k));
    }
    if (c.dof <= 0.0) continue;
    c.p_value = chi_square_survival(c.q, c.dof);
    c.same = c.p_value > alpha;
    if (!c.same) {
      const auto worst = std::max_element(contribution.begin(), contribution.end()) - contribution.begin();
      c.differs = res.flights[static_cast<std::size_t>(worst)].source;
    }
    res.consistency.push_back(c);
  }
}

}  // namespace nimble::ident::discrepancy_parts
