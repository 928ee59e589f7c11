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
/// (power_flight.h); the workflow (ident/discrepancy.h, options as rig discrepancy's) runs on it
/// against the model. Flights run in `jobs` worker processes forked once after every cell's run
/// plan is loaded; a worker that dies costs the flight it was flying (counted as failed) and is
/// replaced.
///
/// Per cell: the probability of naming the effect (among the named effects; an ambiguous pair
/// that holds it does not count) with its 95 % Wilson score interval; how often another effect
/// is named (a wrong name, or an effect the scenario itself flies), and by name; how often any
/// alarm is raised (a verdict other than none); runs that were not ok; flights that failed.
///
/// Recommended length per size (recommend()): the smallest length whose naming probability
/// reaches the target on the curve. The cell estimates along the lengths are first made
/// non-decreasing (pool-adjacent-violators, weighted by flights); then between the two lengths
/// that bracket the target, the probit of the probability, Phi^-1(P), is interpolated linearly
/// in sqrt(length). The Wald statistic of an effect grows with the record's information, in
/// proportion to its length, so its normal approximation gives P = Phi(c sqrt(L) - z), a straight
/// line in those coordinates. Estimates of 0 or 1 are taken as 0.5 / n from the end. Below the
/// shortest length flown or beyond the longest the answer says so instead of extrapolating. The
/// smallest size named with the target probability at each length is interpolated the same way,
/// linearly in |size| (the statistic's non-centrality grows with the size).
///
/// Verification (`verify` > 0): the recommended length of every size that has one is flown with
/// `verify` fresh seeds (flight_seed(campaign seed + 1000003, i), none of the curve's) and the
/// rate at which the effect is named there is reported with its interval: the check that the
/// recommendation holds (about the target, within the interval).

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "ident/discrepancy.h"
#include "launcher/run_plan.h"
#include "power/power_flight.h"

namespace nimble::power {

struct PowerOptions {
  std::string scenario_file;
  std::vector<Override> overrides;   ///< --set, applied before the effect's and the length's
  std::string model_file;            ///< the model the workflow checks
  std::string vehicle_file;          ///< empty: the model's
  ident::DiscrepancyOptions discrepancy;
  std::string effect;                ///< plant effect (effect_size.h)
  std::vector<double> sizes;
  std::vector<double> lengths_s;     ///< empty: the scenario's block times 1, 2, 4, 8
  int flights = 100;                 ///< per cell
  std::uint64_t seed = 1;            ///< the campaign's seed
  int jobs = 1;
  double target = 0.9;               ///< the probability a recommended length reaches
  int verify = 0;                    ///< fresh flights at the recommended length
  bool progress = true;              ///< progress line on stderr
};

/// A proportion with its 95 % Wilson score interval.
struct Proportion {
  int count = 0, n = 0;
  double p = 0.0, lo = 0.0, hi = 1.0;
};
/// count of n with its Wilson score interval at z (1.96: 95 %).
Proportion wilson(int count, int n, double z = 1.959963984540054);

/// One cell of the grid.
struct PowerCell {
  double size = 0.0;
  double length_s = 0.0;
  int repetitions = 1;
  std::vector<FlightOutcome> flights;
  Proportion named;                       ///< the effect named
  Proportion other;                       ///< some other effect named
  Proportion alarm;                       ///< any verdict but none
  std::map<std::string, int> other_names; ///< how often each other effect was named
  int not_ok = 0;                         ///< runs whose verdict was not ok (the workflow still ran)
  int failed = 0;                         ///< flights with no workflow result (FlightOutcome::error)
  /// FlightOutcome's times summed over the cell's flights [s].
  double flight_s = 0.0, build_s = 0.0, workflow_s = 0.0, flight_cpu_s = 0.0, workflow_cpu_s = 0.0;
};

/// The answer for one size, or one length.
struct Recommendation {
  bool reached = false;     ///< the target lies within the grid flown
  double value = 0.0;       ///< the length [s] (or the size) that reaches it; NaN if not reached
  std::string note;         ///< how: "interpolated between 12 and 24 s", "at or below 6 s", "not reached by 48 s"
};

struct PowerResult {
  std::string scenario;     ///< its name
  std::string model;
  std::string effect, parameter, unit, named_as;
  double block_s = 0.0;
  double target = 0.9;
  int flights = 0;
  std::uint64_t seed = 1;
  int jobs = 1;
  std::vector<double> sizes, lengths_s;
  std::vector<PowerCell> cells;            ///< by size, then by length
  std::vector<Recommendation> length_for_size;  ///< per size
  std::vector<Recommendation> size_for_length;  ///< per length
  /// Per size with a recommended length (size 0 excepted): its fresh seeds flown there.
  std::vector<PowerCell> verification;
  double wall_s = 0.0;                     ///< flying and analysing, plans loaded before
  double setup_s = 0.0;                    ///< loading every cell's plan

  const PowerCell& cell(std::size_t size_index, std::size_t length_index) const {
    return cells.at(size_index * lengths_s.size() + length_index);
  }
};

/// Runs the campaign. @throws ConfigError naming the file, key and value (a bad scenario, or a
/// size the plant refuses); std::invalid_argument for a bad effect, size or length.
PowerResult run_power(const PowerOptions& options);

/// The target crossing along `x` (increasing) of the proportions `p` (counts of n), as
/// described above: probit against sqrt(x) (sqrt_x) or x.
Recommendation crossing(const std::vector<double>& x, const std::vector<Proportion>& p, double target, bool sqrt_x);

}  // namespace nimble::power
