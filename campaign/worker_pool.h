#pragma once
/// The campaigns' one worker pool: work items run in forked worker processes, each worker forked
/// once and then taking one item after another, so that what the parent built before (run plans,
/// models) costs nothing per item, and an item that crashes its worker costs only that item.
/// `rig sweep`'s local backend (campaign.h), every Slurm task's share of a campaign,
/// `rig reproduce thesis` (reproduce/) and `rig discrepancy --power` (detection_power/) fly their
/// runs through it; the last two through run_kept() (result_files.h), which keeps each result in
/// a campaign directory.

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace nimble::campaign {

/// What the pool does with item i. Only `work` runs in a worker; the others run in the caller.
struct PoolWork {
  /// Does item i and returns one line (a newline in it becomes a space).
  std::function<std::string(std::size_t)> work;
  /// The result of an item whose worker died on it, given how the worker ended ("killed by
  /// signal 11", "exit code 3"); the worker is replaced while items remain.
  std::function<std::string(std::size_t, const std::string&)> died;
  /// Item i goes to a worker now (optional).
  std::function<void(std::size_t)> started;
  /// Item i is done with this result, and `done` items are (optional): a campaign writes each
  /// run's result as it comes, so an interrupted one keeps every finished run.
  std::function<void(std::size_t, const std::string&, std::size_t done)> finished;
  /// The results go to `finished` only and are returned empty: a campaign of many large results
  /// (the sweep's runs, each kept in its file) does not hold them all in memory.
  bool forget = false;
};

/// How a child process ended, from its wait status: "exit code N" or "killed by signal S" (the
/// words a campaign's result files and a died() callback give).
std::string exit_description(int status);

/// Does every item i in [0, n) once, in min(jobs, n) forked workers, and returns the results by
/// index. A worker does not outlive the caller (it is killed if the caller dies). The caller must
/// have no other threads running (fork).
/// @throws std::runtime_error if a pipe or fork fails.
std::vector<std::string> run_in_workers(std::size_t n, int jobs, const PoolWork& pool);

}  // namespace nimble::campaign
