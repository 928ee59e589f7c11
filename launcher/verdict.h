#pragma once
/// The verdict of a run: a pure function of how the run ended and what the vehicle did.

#include <map>
#include <string>

#include "launcher/run_monitor.h"
#include "launcher/run_plan.h"

namespace nimble::launcher {

/// Real-time health of a run, from what each process reported on TIMING_HEALTH.
struct TimingVerdict {
  bool judged = false;      ///< real time only: lockstep and in process have no deadlines
  bool degraded = false;    ///< some fraction above its threshold
  std::string worst;        ///< the process with the worst fraction (relative to its threshold)
  double worst_fraction = 0.0;
  std::string text;         ///< one line: what was worst, against which threshold
};

struct Verdict {
  int exit_code = kRunOk;  ///< one of the kRun* codes
  std::string text;        ///< "ok", "completed, vehicle NOT controlled", "failed: ...", "interrupted"
  bool controlled = false; ///< TRUTH seen, finite, |phi| and |theta| within the judge's limits
  bool hover = false;      ///< controlled and the final state within the hover limits
  TimingVerdict timing;
};

/// Judges real-time health: for each process, the fraction of its cycles that overran
/// (overruns / loops) and, per stream channel it received, the fraction that arrived late.
/// Above judge.max_overrun_fraction or judge.max_late_fraction the run is degraded; the worst
/// is named (for a late channel: the receiving process, and the channel's publishers).
/// `realtime` false: not judged.
TimingVerdict judge_timing(const std::map<std::string, TimingSummary>& timing, const JudgeConfig& judge,
                           bool realtime);

/// Judges a run. `failure`: what stopped it early (empty if nothing did; only its first line
/// goes into the text); `interrupted`: stopped by the user.
/// With `timing` degraded, an otherwise "ok" run says "real-time degraded: ..." and, if
/// `strict_timing`, exits kRunTimingDegraded.
/// `failsafe` (from failsafe_of()): the controller took its failsafe; a run that was not
/// stopped otherwise then exits kRunFailsafe and says so.
Verdict judge_run(const FlightSummary& flight, const JudgeConfig& judge, bool interrupted,
                  const std::string& failure, const TimingVerdict& timing = {}, bool strict_timing = false,
                  const std::string& failsafe = "");

/// The first CODE_FAILSAFE fault of the run ("process: message"), or "".
std::string failsafe_of(const RunMonitor& monitor);

}  // namespace nimble::launcher
