// The discrepancy workflow (ident/discrepancy.h), part: the signatures that confirm a name. A
// candidate that met the alarm rule is named only if what else its effect predicts holds on the
// held-out data (DiscrepancyOptions::signature_checks; docs/discrepancy.md, "Effects outside the
// library, and signatures").

#include "ident/discrepancy_parts.h"

#include <cmath>
#include <numeric>
#include <vector>

#include <boost/math/distributions/students_t.hpp>

namespace nimble::ident::discrepancy_parts {

/// sensor_bias's signature. A bias b of the rate sensor enters wherever p does: in the L and Y
/// equations (the constant the candidate fits) and in the kinematic relation phi_dot = p (lateral
/// trim, theta0 = 0), where the measured p exceeds phi's derivative by b. In each held-out block
/// (the cross-validation folds, contiguous) b_k = (integral of p - increase of phi) / duration,
/// over the steps of the block's own grid (a jump of the time line, between pooled flights, is
/// skipped); the blocks' mean is tested against 0 with Student's t on K - 1 degrees of freedom
/// (the blocks' scatter is the estimate's, whatever the noise's colour), two-sided, at
/// gust_band_alpha like the confirmation above the gust band: a confirmation of a candidate that
/// met the alarm rule already, so it can withdraw a name but raise no new alarm.
void Workflow::sensor_bias_signature(CandidateTrial& t) const {
  t.signature_holds = true;
  if (!data.has("p") || !data.has("phi")) return;
  const VectorXd& p = data.at("p");
  const VectorXd& phi = data.at("phi");
  const double step = 1.0 / data.rate_hz;
  std::vector<double> b;
  for (const auto& [a, e] : folds) {
    double integral = 0.0, rise = 0.0, duration = 0.0;
    for (Index i = a + 1; i < e; ++i) {
      const double dt = data.t_s[i] - data.t_s[i - 1];
      if (!(dt > 0.0) || dt > 1.5 * step) continue;
      integral += 0.5 * (p[i] + p[i - 1]) * dt;
      rise += phi[i] - phi[i - 1];
      duration += dt;
    }
    if (duration > 0.0) b.push_back((integral - rise) / duration);
  }
  const double K = static_cast<double>(b.size());
  if (b.size() < 3) return;
  const double mean = std::accumulate(b.begin(), b.end(), 0.0) / K;
  double ss = 0.0;
  for (double x : b) ss += (x - mean) * (x - mean);
  const double se = std::sqrt(ss / (K - 1.0) / K);
  double p_value = 1.0;
  if (se > 0.0) {
    p_value = 2.0 * boost::math::cdf(boost::math::complement(boost::math::students_t(K - 1.0), std::fabs(mean) / se));
  } else if (mean != 0.0) {
    p_value = 0.0;
  }
  t.signature["kinematic_bias_radps"] = mean;
  t.signature["sigma_radps"] = se;
  t.signature["blocks"] = K;
  t.signature["p_value"] = p_value;
  t.signature_holds = p_value <= opt.gust_band_alpha;
}

}  // namespace nimble::ident::discrepancy_parts
