#pragma once
/// The Slurm backend of `rig sweep`: a campaign (campaign/campaign.h) as one array job, each
/// task a chunk of runs flown by `rig sweep task DIR --task K` on whichever node Slurm gives it.
/// The rig talks to Slurm through its client commands (sbatch, squeue, scontrol), as a user
/// would; nothing needs Slurm's accounting database.

#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include "campaign/campaign.h"

namespace nimble::campaign {

/// The result of a command run by the backend.
struct CommandOutput {
  int exit_code = -1;  ///< -1: could not be started
  std::string out, err;
};
/// Runs argv[0] (searched on PATH) with the arguments, capturing stdout and stderr.
CommandOutput run_command(const std::vector<std::string>& argv);

/// "0-3,7,9-10" for sbatch --array.
std::string array_spec(std::vector<std::size_t> tasks);

/// Writes DIR/slurm/sweep.sbatch (every task of the campaign; sbatch's --array chooses which
/// are submitted) and returns its path.
std::string write_batch_script(const Campaign& campaign);

/// Submits the array tasks `tasks` of the campaign (sbatch --parsable --array=...); records the
/// job id with its tasks in DIR/slurm/jobs.txt and returns it.
/// @throws std::runtime_error with sbatch's own words if it refuses, or if it is not installed.
std::string submit_tasks(const Campaign& campaign, const std::vector<std::size_t>& tasks);

/// The jobs submitted for the campaign, oldest first.
std::vector<std::string> campaign_jobs(const Campaign& campaign);

/// Array tasks of `job` that Slurm still has pending or running (squeue), by task: its state.
/// Empty when the job is over (or Slurm forgot it).
/// @throws std::runtime_error if squeue cannot be run or fails otherwise.
std::map<std::size_t, std::string> active_tasks(const std::string& job);

/// The campaign's jobs that Slurm still has tasks of, each as "Slurm job J still has tasks
/// 3-4 (RUNNING)" (the state of its first such task); empty when none.
std::vector<std::string> jobs_still_running(const Campaign& campaign);

/// How each array task of a finished `job` ended (scontrol show job, while Slurm remembers the
/// job: MinJobAge), e.g. "COMPLETED exit 0:0", "CANCELLED exit 0:15", "FAILED exit 3:0".
std::map<std::size_t, std::string> task_outcomes(const std::string& job);

/// Waits for the job's tasks on the campaign's runs: returns when every run of `tasks` has a
/// result file or Slurm has no task of the job left. `progress` gets the campaign's finished runs.
void wait_for_job(const Campaign& campaign, const std::string& job, const std::vector<std::size_t>& tasks,
                  const ProgressFn& progress);

/// One line per task of `tasks` that left runs without results: its runs, how it ended (from
/// Slurm, or its output file's last line) and which runs are missing.
std::vector<std::string> describe_missing(const Campaign& campaign, const std::string& job,
                                          const std::vector<std::size_t>& tasks);

/// The array tasks that hold the runs without results.
std::vector<std::size_t> tasks_with_missing_runs(const Campaign& campaign);

}  // namespace nimble::campaign
