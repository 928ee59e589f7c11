#pragma once
/// The verdict of a run: a pure function of how the run ended and what the vehicle did.

#include <map>
#include <string>
#include <vector>

#include "launcher/run_monitor.h"
#include "launcher/run_plan.h"

namespace nimble::launcher {

/// Real-time health of a run, from what each process reported on TIMING_HEALTH.
struct TimingVerdict {
  bool judged = false;    ///< real time only: lockstep and in process have no deadlines
  bool degraded = false;  ///< some fraction above its threshold
  std::string worst;      ///< the process with the worst fraction (relative to its threshold)
  double worst_fraction = 0.0;
  std::string text;  ///< one line: what was worst, against which threshold
};

/// An oscillation of the roll tracking error that does not die out (find_oscillation).
struct Oscillation {
  bool detected = false;
  bool growing = false;        ///< every peak above the one a cycle before; else sustained
  double frequency_hz = 0.0;   ///< over all the cycles it lasted
  double amplitude_deg = 0.0;  ///< its largest peak [deg]
  double damping_ratio = 0.0;  ///< of the amplitude over the cycles that showed it [-]
  double start_s = 0.0;        ///< when the cycles that showed it began [s]
  int cycles = 0;              ///< how many it lasted, at its amplitude and period
  std::string text;            ///< e.g. "roll oscillation 2.1 Hz +-31 deg growing from t = 3.6 s"
};

/// How the roll followed the controller's reference, from the run's TrackingSummary.
struct TrackingVerdict {
  bool judged = false;  ///< the run had a controller (CONTROLLER_STATUS)
  bool lost = false;    ///< an error bound exceeded, or an oscillation
  double rms_deg = 0.0, max_deg = 0.0, max_at_s = 0.0;
  Oscillation oscillation;
  /// What was lost, e.g. "roll oscillation 2.1 Hz +-31 deg growing from t = 3.6 s; roll
  /// tracking error rms 17.4 deg (limit 14 deg)"; "" if nothing was.
  std::string text;
};

struct Verdict {
  int exit_code = kRunOk;  ///< one of the kRun* codes
  /// "ok", "completed, vehicle NOT controlled", "completed, roll oscillation ...", "failed: ...",
  /// "interrupted"
  std::string text;
  bool controlled = false;  ///< TRUTH seen, finite, |phi| and |theta| within the judge's limits
  bool hover = false;       ///< controlled and the final state within the hover limits
  TimingVerdict timing;
  TrackingVerdict tracking;
};

/// Judges real-time health: for each process, the fraction of its cycles that overran
/// (overruns / loops) and, per stream channel it received, the fraction that arrived late.
/// Above judge.max_overrun_fraction or judge.max_late_fraction the run is degraded; the worst
/// is named (for a late channel: the receiving process, and the channel's publishers).
/// `realtime` false: not judged.
TimingVerdict judge_timing(const std::map<std::string, TimingSummary>& timing, const JudgeConfig& judge, bool realtime);

/// Judges roll tracking: the RMS and the largest error against judge.max_tracking_rms_deg and
/// judge.max_tracking_error_deg, and the error's half-cycles for an oscillation
/// (find_oscillation). A run without tracking samples is not judged.
TrackingVerdict judge_tracking(const TrackingSummary& tracking, const JudgeConfig& judge);

/// The first oscillation in `half_cycles` (the last, still in progress, is left out): a window of
/// judge.oscillation_cycles cycles in which every half-cycle's |peak| reaches
/// judge.oscillation_amplitude_deg and the roll reference moved less than
/// judge.oscillation_reference_still_deg, every full period (two half-cycles in a row) is within
/// judge.oscillation_period_tolerance of their mean, and the amplitude decays with a damping
/// ratio below judge.oscillation_max_damping (from the least-squares slope of the log of the mean
/// |peak| of each two half-cycles in a row). It is growing if every |peak| of that window exceeds the one a
/// cycle before. It lasts while the windows after it keep the amplitude, reference and period.
Oscillation find_oscillation(const std::vector<TrackingHalfCycle>& half_cycles, const JudgeConfig& judge);

/// Judges a run. `failure`: what stopped it early (empty if nothing did; only its first line
/// goes into the text); `interrupted`: stopped by the user.
/// With `timing` degraded, an otherwise "ok" run says "real-time degraded: ..." and, if
/// `strict_timing`, exits kRunTimingDegraded.
/// `failsafe` (from failsafe_of()): the controller took its failsafe; a run that was not
/// stopped otherwise then exits kRunFailsafe and says so.
/// `tracking` lost (judge_tracking()): a controlled run exits kRunNotTracking and says
/// "completed, " and what was lost; a run not controlled names its oscillation, if any.
Verdict judge_run(const FlightSummary& flight, const JudgeConfig& judge, bool interrupted, const std::string& failure,
                  const TimingVerdict& timing = {}, bool strict_timing = false, const std::string& failsafe = "",
                  const TrackingVerdict& tracking = {});

/// The first CODE_FAILSAFE fault of the run ("process: message"), or "".
std::string failsafe_of(const RunMonitor& monitor);

}  // namespace nimble::launcher
