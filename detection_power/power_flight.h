#pragma once
/// One flight of a power analysis: a run plan flown in process with one seed, its messages
/// turned into flight data as they are published (ident::RigLogAssembler, the log reader's own
/// code, fed in the log's order: the workflow sees what `rig discrepancy <log>` would read), and
/// the discrepancy workflow run on it.

#include <cstdint>
#include <string>
#include <vector>

#include "core/model.h"
#include "core/vehicle.h"
#include "discrepancy/discrepancy.h"
#include "launcher/run_plan.h"

namespace nimble::detection_power {

/// What the workflow is asked on every flight: `rig discrepancy <log> --model M`.
struct FlightCheck {
  DerivativeModel model;
  Vehicle vehicle;
  ident::DiscrepancyOptions options;
};

/// What one flight gave.
struct FlightOutcome {
  std::uint64_t seed = 0;
  int run_exit = -1;                   ///< the run's verdict (launcher/run_plan.h kRun*), -1: not flown
  bool analysed = false;               ///< the workflow ran on the flight's data
  std::string error;                   ///< why the flight or the workflow did not complete ("" if it did)
  std::string verdict;                 ///< the workflow's verdict (effects, ambiguous, unexplained, none)
  std::vector<std::string> named;      ///< the effects it named
  std::vector<std::string> ambiguous;  ///< the candidates of its ambiguous pairs
  double flight_s = 0.0;               ///< wall time of the flight, building its processes included [s]
  double build_s = 0.0;                ///< of which building the processes [s]
  double workflow_s = 0.0;             ///< wall time of the workflow [s]
  /// CPU time of this process [s] during the flight (both of its threads: the flight and the
  /// one that records and assembles its messages) and during the workflow: what the flight costs
  /// a core, whatever else the machine runs.
  double flight_cpu_s = 0.0, workflow_cpu_s = 0.0;
};

/// `plan` with seed `seed`: what load_run_plan() gives with --seed (the scenario's seed and the
/// `seed` key of its tree, which the configuration digest covers). The tree is cloned first: the
/// copies of a plan share one tree (YAML nodes are references), and the others keep their seed.
void set_seed(launcher::RunPlan& plan, std::uint64_t seed);

/// Flies `plan` with `seed` in process and runs the workflow on it. `log_file` (optional) also
/// records the flight's LCM log. Never throws for a flight or workflow that fails: the outcome
/// says why.
FlightOutcome fly_and_check(launcher::RunPlan plan, std::uint64_t seed, const FlightCheck& check,
                            const std::string& log_file = "");

/// The flight data of `plan` flown with `seed`, as the workflow gets it (states from the
/// estimator when the run has one, rig_log.h). `log_file`: as above.
/// @throws std::runtime_error if the run fails; DataError if its messages lack a channel.
ident::FlightData fly_to_data(launcher::RunPlan plan, std::uint64_t seed, const std::string& log_file = "");

/// The seed of flight `index` of a campaign with seed `campaign_seed`: a hash of the two
/// (splitmix64), within the scenario's seed range [0, 9e15).
std::uint64_t flight_seed(std::uint64_t campaign_seed, std::uint64_t index);

}  // namespace nimble::detection_power
