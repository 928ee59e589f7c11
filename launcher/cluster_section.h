#pragma once
/// The scenario's `cluster:` section: where a Slurm campaign (campaign/slurm.h) runs. The run plan
/// reads it (launcher/run_plan.cc), so `rig check` names a bad value before a campaign is
/// submitted.

#include <cstddef>
#include <string>

#include "scenario/scenario.h"

namespace nimble::launcher {

/// The `cluster` settings of a Slurm campaign: command-line options over the scenario's
/// `cluster:` section over these defaults.
struct ClusterSettings {
  std::string partition;                ///< empty: the cluster's default partition
  std::string account;                  ///< empty: the user's default account
  std::string time_limit = "01:00:00";  ///< per task, as sbatch --time takes it
  int cpus_per_task = 1;                ///< runs at a time within a task
  int memory_mb_per_cpu = 0;            ///< sbatch --mem-per-cpu [MB]; 0: the cluster's default
  std::size_t chunk_size = 0;           ///< runs per array task; 0: about four tasks per CPU of this machine
  std::string rig;                      ///< the rig executable as the nodes see it (default: this one)
};

/// Reads a resolved scenario's `cluster:` section (absent: the defaults); load_run_plan checks
/// it, so `rig check` names a bad value before a campaign is submitted.
/// @throws ConfigError naming the key and value.
ClusterSettings cluster_settings_from(const Scenario& scenario);

}  // namespace nimble::launcher
