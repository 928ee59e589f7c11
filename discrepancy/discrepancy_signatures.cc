// The discrepancy workflow (discrepancy/discrepancy.h), part: the signatures that confirm a name. A
// candidate that met the alarm rule is named only if what else its effect predicts holds on the
// held-out data (DiscrepancyOptions::signature_checks; docs/discrepancy.md, "Effects outside the
// library, and signatures").

#include "discrepancy/discrepancy_parts.h"

#include <cmath>
#include <limits>
#include <string>
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

/// lateral_inflow's signature: one side force from sideslip, odd in v, whose roll moment is that
/// force at the inflow's arm, L_vv = arm Y_vv. Tested as L_vv - arm Y_vv = 0 with the two
/// equations' coloured sigmas, two-sided at gust_band_alpha, unless the ratio L_vv / (arm Y_vv)
/// is within inflow_arm_factor of 1 (closed-loop estimates of both carry biases their sigmas do
/// not hold). A side force too small to see agrees with a small roll moment; a v|v| roll moment
/// with no side force of its size beside it (or a side force of the other sign) is a moment the
/// library does not have.
///
/// The arm itself is an assumption (the plant file's ratio), not part of the form: when the side
/// force and the roll moment each met the partial-F rule and have the same sign, the data shows
/// one v|v| force acting at some arm, the form of the lateral inflow, and only the assumed arm
/// disagrees. The name is kept with the measured arm, L_vv / Y_vv, its 95 % interval (delta
/// method on the two coloured sigmas) and the assumption it contradicts (CandidateTrial::
/// contradicts): a user with another vehicle learns that an inflow acts and where.
void Workflow::inflow_arm_signature(CandidateTrial& t) const {
  const auto L = t.parameters.find("L_vv"), Y = t.parameters.find("Y_vv");
  const auto sL = t.sigma.find("L_vv"), sY = t.sigma.find("Y_vv");
  if (L == t.parameters.end() || Y == t.parameters.end() || sL == t.sigma.end() || sY == t.sigma.end()) return;
  const double a = opt.inflow_arm_m;
  const double diff = L->second - a * Y->second;
  const double sd = std::sqrt(sL->second * sL->second + a * a * sY->second * sY->second);
  const double z = sd > 0.0 ? diff / sd : 0.0;
  const double p = std::erfc(std::fabs(z) / std::sqrt(2.0));
  const double ratio = Y->second != 0.0 ? L->second / (a * Y->second) : std::numeric_limits<double>::infinity();
  t.signature["arm_z"] = z;
  t.signature["arm_p"] = p;
  t.signature["arm_ratio"] = ratio;
  const bool within = ratio >= 1.0 / opt.inflow_arm_factor && ratio <= opt.inflow_arm_factor;
  if (p > opt.gust_band_alpha || within) return;
  const auto met = [&](const char* eq) {
    const auto F = t.partial_f.find(eq);
    return F != t.partial_f.end() && F->second >= opt.partial_f;
  };
  if (met("L") && met("Y") && ratio > 0.0) {
    const double arm = L->second / Y->second;
    const double rel = std::hypot(sL->second / L->second, sY->second / Y->second);
    const double lo = arm * (1.0 - 1.96 * rel), hi = arm * (1.0 + 1.96 * rel);
    t.signature["arm_m"] = arm;
    t.signature["arm_lo_m"] = lo;
    t.signature["arm_hi_m"] = hi;
    t.contradicts = "arm " + fmt(arm) + " m [" + fmt(lo) + ", " + fmt(hi) + "], outside the assumed " + fmt(a) +
                    " m x/ " + fmt(opt.inflow_arm_factor) + " (inflow_arm_m, inflow_arm_factor)";
    return;
  }
  t.signature_holds = false;
  t.signature_note = "its roll moment is not its side force at the inflow's arm (L_vv " + fmt(L->second) + ", Y_vv " +
                     fmt(Y->second) + ", arm " + fmt(a) + " m: their ratio " + fmt(ratio) +
                     " of the arm's, L_vv - arm Y_vv " + fmt(z) + " sigma from 0, p " + fmt(p) +
                     "), and the two do not both meet the partial-F rule with one sign: not the lateral inflow";
}

void Workflow::signature(const CandidateSpec& spec, const Model& m, const ScanPoint& P, CandidateTrial& t) const {
  std::string reason;  // the failed signature's reason, when it is not "fails its signature: " + the note
  if (spec.signature == effects::Signature::kInflow) {
    inflow_arm_signature(t);
  } else if (spec.constant()) {
    // sensor_bias and constant_load fit the same constant; the kinematics tell which it is.
    sensor_bias_signature(t);
    const bool biased = t.signature_holds;
    const std::string figures = "kinematic bias " + fmt(t.signature["kinematic_bias_radps"]) + " rad/s, sigma " +
                                fmt(t.signature["sigma_radps"]);
    if (spec.signature == effects::Signature::kRateGyroBias && !biased) {
      t.signature_note = "a constant fits but p carries no bias against phi's derivative (" + figures + ", p " +
                         fmt(t.signature["p_value"]) + "): not a rate-sensor bias";
      reason = "fails its signature: it " + t.reason.substr(std::string("passes: ").size()) +
               ", but p carries no bias against phi's derivative (" + figures + " over " + fmt(t.signature["blocks"]) +
               " blocks, p " + fmt(t.signature["p_value"]) + " > " + fmt(opt.gust_band_alpha) +
               "): a constant moment or force, or the mean of another effect, not a "
               "rate-sensor bias";
    } else if (spec.signature == effects::Signature::kConstantLoad) {
      // A constant load's signature is the sensor bias's absent: p agrees with phi's derivative.
      t.signature_holds = !biased;
      if (biased) {
        t.signature_note = "a constant fits and p carries a bias against phi's derivative (" + figures + ", p " +
                           fmt(t.signature["p_value"]) + "): a rate-sensor bias, not a load";
      }
    }
  }
  // Every effect: its form is the data's (discrepancy_terms.cc).
  if (t.signature_holds) rival_form_signature(spec, m, P, t);
  if (!t.signature_holds) {
    t.passed = false;
    t.reason = reason.empty() ? "fails its signature: " + t.signature_note : reason;
  }
}

}  // namespace nimble::ident::discrepancy_parts
