#pragma once
/// `rig sweep`: a Monte Carlo campaign over a scenario. Every combination of the --vary values
/// (a parameter set) is flown with every seed of the range; each run is the scenario's run
/// plan with that set's overrides and seed, flown in process (or, with another clock, by
/// `rig run` itself). The summary gives, per parameter set, the controlled rate and
/// percentiles across runs of the state ranges, extremes and estimator errors; every run's
/// seed, verdict and figures are kept for the JSON and CSV.

#include <cstdint>
#include <iosfwd>
#include <map>
#include <string>
#include <vector>

#include "launcher/run_plan.h"

namespace nimble::campaign {

/// One --vary key=v1,v2,...
struct Vary {
  std::string key;
  std::vector<std::string> values;
};

/// Parses "key=v1,v2,...": commas inside brackets or braces belong to a value, so
/// `processes=[plant,controller],[plant]` is two values.
/// @throws std::invalid_argument naming the text.
Vary parse_vary(const std::string& text);
/// Parses a seed range "A-B" (A <= B) or a single seed "A".
/// @throws std::invalid_argument naming the text.
std::pair<uint64_t, uint64_t> parse_seed_range(const std::string& text);

/// One parameter set: the overrides of one combination of --vary values.
struct ParameterSet {
  std::string label;                ///< "key=value key2=value2", or "scenario as given" if nothing varies
  std::vector<Override> overrides;  ///< applied after the sweep's own --set overrides
};
/// Every combination of the values, the first --vary varying slowest.
std::vector<ParameterSet> parameter_sets(const std::vector<Vary>& vary);

/// A run's p, v and phi against rig time: TRUTH sampled on a fixed grid t_k = k dt_s from 0
/// (the first TRUTH at or after each grid time), for the campaign report's envelopes.
struct RunTrace {
  double dt_s = 0.0;              ///< grid step [s]; 0: no trace
  std::vector<double> p, v, phi;  ///< roll rate [rad/s], lateral velocity [m/s], roll [rad]; same length
  std::size_t size() const { return p.size(); }
};

/// The figures of one run that the sweep keeps.
struct SweepRun {
  std::size_t set = 0;  ///< index into the parameter sets
  uint64_t seed = 0;
  int exit_code = -1;
  std::string verdict;  ///< the run's result text, or why it could not run
  bool controlled = false;
  bool hover = false;
  double sim_time_s = 0.0;
  /// Where and how fast it ran: the merged JSON's and CSV's `machine` fields, the only ones
  /// that depend on the machine, the backend, the jobs or the chunk size.
  double wall_time_s = 0.0, speed_x_realtime = 0.0;
  std::string host;
  std::map<std::string, double> figures;  ///< by kSweepFigures name; absent if the run had none
  RunTrace trace;                         ///< empty if the run had no TRUTH or no trace was asked for
};

/// A quantity summarised across runs: its key in SweepRun::figures, its label and unit.
struct SweepFigure {
  const char* key;
  const char* label;
};
/// The quantities of the summary, in order.
const std::vector<SweepFigure>& sweep_figures();

/// Percentile `pct` in [0, 100] of `values` (linear interpolation between order statistics,
/// as numpy's default); NaN for no values.
double percentile(std::vector<double> values, double pct);

struct SweepOptions {
  launcher::RunOptions base;  ///< scenario, --set, --clock (default inprocess), bin_dir
  uint64_t first_seed = 1, last_seed = 1;
  std::vector<Vary> vary;
  int jobs = 1;          ///< runs at once (each in its own child process)
  std::string logs_dir;  ///< keep each run's LCM log here (empty: none kept)
  bool progress = true;  ///< progress bar on stderr
};

struct SweepResult {
  std::string scenario;
  std::string clock;
  std::vector<ParameterSet> sets;
  std::vector<SweepRun> runs;  ///< by set, then by seed
  // How it ran (the `machine` fields): not part of the result's meaning.
  double wall_time_s = 0.0;
  int jobs = 1;  ///< runs at a time (local), CPUs per task (slurm)
  std::string backend = "local";
  std::size_t chunk_size = 0;  ///< runs per array task (slurm); 0: local
};

/// The summary table.
void write_sweep_text(std::ostream& out, const SweepResult& result);
/// The sweep as JSON: the sets with their statistics and a `runs` list (seed, verdict, figures).
/// What depends on where and how it ran sits in `machine` objects (the campaign's and each
/// run's); everything else is the same for the same campaign on any backend, jobs or chunks.
std::string sweep_json(const SweepResult& result);
/// One CSV row per run; the columns that depend on the machine are named machine_*.
std::string sweep_csv(const SweepResult& result);

}  // namespace nimble::campaign
