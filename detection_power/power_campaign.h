#pragma once
/// How long to fly: `rig discrepancy --power`. By simulation with the rig's own plant, sensors,
/// controller and estimator (the in-process executor), the probability that the discrepancy
/// workflow names a plant effect of a given size with a scenario as it is, over a grid of sizes
/// and record lengths, and the record length at which it names it with the target probability.
///
/// Flights. Every cell (size, length) flies the scenario (with the user's --set) with the effect
/// at that size (effect_size.h) for that length (record_length.h), once per flight index
/// 0..flights-1, flight i with seed flight_seed(campaign seed, i): the same seeds in every cell
/// (common random numbers: the cells differ by the effect and the length, not by the noise,
/// which makes the curves smoother than independent seeds would). Each flight is flown in
/// process and its messages become flight data in memory as rig_log.h reads a log
/// (power_flight.h); the workflow (discrepancy/discrepancy.h, options as rig discrepancy's) runs on it
/// against the model. Flights run in `jobs` worker processes forked once after every cell's run
/// plan is loaded; a worker that dies costs the flight it was flying (counted as failed) and is
/// replaced.
///
/// Per cell: the probability of naming the effect (among the named effects; an ambiguous pair
/// that holds it does not count) with its 95 % Wilson score interval; how often another effect
/// is named (a wrong name, or an effect the scenario itself flies), and by name; how often any
/// alarm is raised (a verdict other than none); runs that were not ok; flights that failed.
///
/// Recommended length per size: where the curve of the size's cells against the length reaches
/// the target (power_curve.h: monotone fit, probit against sqrt(length) between the two lengths
/// that bracket it). The grid's lengths find the bracket; with the default lengths (the
/// scenario's block times 1, 2, 4) a size that does not reach the target by the longest gets
/// a cell at twice that, up to 16 blocks. Then `refine` rounds fly one more cell per size at the
/// interpolated length, kept within the middle half of the bracket in sqrt(length) (a safeguarded
/// secant: from an end far below the target the plain secant creeps up from one side) and
/// rounded to 0.01 s, and interpolate again on all its cells: near the target the curve is
/// steep (50 points of probability within a second of record on the 30 deg nonlinear doublet),
/// and the grid alone would leave the recommendation seconds off. The smallest size named with the target
/// probability at each grid length is interpolated the same way, linearly in |size|.
///
/// Verification (`verify` > 0): the recommended length of every size that has one is flown with
/// `verify` fresh seeds (flight_seed(campaign seed + 1000003, i), none of the curve's) and the
/// rate at which the effect is named there is reported with its interval: the check that the
/// recommendation holds (about the target, within the interval).

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "discrepancy/discrepancy.h"
#include "launcher/run_plan.h"
#include "detection_power/power_curve.h"
#include "detection_power/power_flight.h"

namespace nimble::detection_power {

struct PowerOptions {
  std::string scenario_file;
  std::vector<Override> overrides;  ///< --set, applied before the effect's and the length's
  std::string model_file;           ///< the model the workflow checks
  std::string vehicle_file;         ///< empty: the model's
  ident::DiscrepancyOptions discrepancy;
  std::string effect;  ///< plant effect (effect_size.h)
  std::vector<double> sizes;
  /// Record lengths of the grid [s]; empty: the scenario's block times 1, 2, 4, doubled on to 16
  /// blocks for a size that has not reached the target.
  std::vector<double> lengths_s;
  int flights = 100;       ///< per cell
  std::uint64_t seed = 1;  ///< the campaign's seed
  int jobs = 1;
  double target = 0.9;   ///< the probability a recommended length reaches
  int refine = 3;        ///< rounds of refinement of each recommended length
  int verify = 0;        ///< fresh flights at each recommended length
  bool progress = true;  ///< progress line on stderr
  /// A campaign directory (campaign/result_files.h) keeping each flight's outcome as it finishes
  /// (empty: none): the same campaign started again there flies only the flights it lacks.
  std::string result_dir;
};

/// One cell: a size flown for a length.
struct PowerCell {
  double size = 0.0;
  double length_s = 0.0;
  int repetitions = 1;
  std::string kind;  ///< grid, longer, refined or verification
  std::vector<FlightOutcome> flights;
  Proportion named;                        ///< the effect named
  Proportion other;                        ///< some other effect named
  Proportion alarm;                        ///< any verdict but none
  std::map<std::string, int> other_names;  ///< how often each other effect was named
  std::map<std::string, int> verdicts;     ///< how often each verdict was given (effects, none, ...)
  int not_ok = 0;                          ///< runs whose verdict was not ok (the workflow still ran)
  int failed = 0;                          ///< flights with no workflow result (FlightOutcome::error)
  /// FlightOutcome's times summed over the cell's flights [s].
  double flight_s = 0.0, build_s = 0.0, workflow_s = 0.0, flight_cpu_s = 0.0, workflow_cpu_s = 0.0;
};

/// One size's curve against the record length.
struct SizeCurve {
  double size = 0.0;
  std::vector<std::size_t> cells;  ///< into PowerResult::cells, by length
  Crossing length;                 ///< the recommended length [s]
};

struct PowerResult {
  std::string scenario;  ///< its name
  std::string model;
  std::string effect, parameter, unit, named_as;
  double block_s = 0.0;
  double target = 0.9;
  int flights = 0;
  std::uint64_t seed = 1;
  int jobs = 1;
  std::vector<double> sizes, lengths_s;   ///< the grid
  std::vector<PowerCell> cells;           ///< the grid's (by size, then length), then the longer and refined ones
  std::vector<SizeCurve> curves;          ///< per size
  std::vector<Crossing> size_for_length;  ///< per grid length: the smallest size named with the target
  /// Per size with a recommended length (size 0 excepted): its fresh seeds flown there.
  std::vector<PowerCell> verification;
  double wall_s = 0.0;   ///< flying and analysing, plans loaded before
  double setup_s = 0.0;  ///< loading the grid's plans

  /// The grid's cell of size `s` and length `l` (indices into sizes and lengths_s).
  const PowerCell& cell(std::size_t s, std::size_t l) const { return cells.at(s * lengths_s.size() + l); }
};

/// Runs the campaign. @throws ConfigError naming the file, key and value (a bad scenario, or a
/// size the plant refuses); std::invalid_argument for a bad effect, size or length.
PowerResult run_power(const PowerOptions& options);

}  // namespace nimble::detection_power
