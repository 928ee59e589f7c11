#include "launcher/verdict.h"

#include <cmath>

namespace nimble::launcher {

Verdict judge_run(const FlightSummary& f, const JudgeConfig& jc, bool interrupted, const std::string& failure) {
  constexpr double kRad = M_PI / 180.0;
  Verdict v;
  v.controlled = f.samples > 0 && f.finite && f.max_abs_phi <= jc.max_phi_deg * kRad &&
                 f.max_abs_theta <= jc.max_theta_deg * kRad;
  v.hover = v.controlled && std::fabs(f.final_phi) <= jc.hover_phi_deg * kRad &&
            std::fabs(f.final_p) <= jc.hover_p_radps && std::fabs(f.final_v) <= jc.hover_v_mps;
  if (interrupted) {
    v.exit_code = kRunInterrupted;
    v.text = "interrupted";
  } else if (!failure.empty()) {
    v.exit_code = kRunFailed;
    v.text = "failed: " + failure.substr(0, failure.find('\n'));
  } else if (!v.controlled) {
    v.exit_code = kRunNotControlled;
    v.text = "completed, vehicle NOT controlled";
  } else {
    v.exit_code = kRunOk;
    v.text = "ok";
  }
  return v;
}

}  // namespace nimble::launcher
