#pragma once
/// The verdict of a run: a pure function of how the run ended and what the vehicle did.

#include <string>

#include "launcher/run_monitor.h"
#include "launcher/run_plan.h"

namespace nimble::launcher {

struct Verdict {
  int exit_code = kRunOk;  ///< one of the kRun* codes
  std::string text;        ///< "ok", "completed, vehicle NOT controlled", "failed: ...", "interrupted"
  bool controlled = false; ///< TRUTH seen, finite, |phi| and |theta| within the judge's limits
  bool hover = false;      ///< controlled and the final state within the hover limits
};

/// Judges a run. `failure`: what stopped it early (empty if nothing did; only its first line
/// goes into the text); `interrupted`: stopped by the user.
Verdict judge_run(const FlightSummary& flight, const JudgeConfig& judge, bool interrupted,
                  const std::string& failure);

}  // namespace nimble::launcher
