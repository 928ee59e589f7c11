#pragma once
/// A campaign of `rig sweep` kept in a directory, so that it can run anywhere, be split any way,
/// be interrupted and finished later, and be merged whenever its runs are there.
///
///   DIR/campaign.json      the manifest: scenario file, --set overrides, --vary sets and their
///                          configuration digests, seeds, clock, chunk size, backend, cluster settings
///   DIR/scenario.yaml      the resolved scenario of the first parameter set (for the record)
///   DIR/runs/run-NNNNNN.json  one file per finished run, written atomically (temporary name,
///                          fsync, rename): a half-written file is never merged; its first line
///                          names the campaign, so another's is refused (the campaigns' one result
///                          model, result_files.h: the same manifest, lock and result files as
///                          rig reproduce thesis --dir and rig discrepancy --power --dir)
///   DIR/logs/              each run's LCM log, if the campaign keeps them
///   DIR/slurm/             the batch script, the job ids submitted and each task's output
///   DIR/result.json, DIR/result.csv  the merged result (sweep_json, sweep_csv)
///
/// Run i flies parameter set i / S with seed first_seed + i % S (S seeds per set): a run's seed
/// depends on the campaign and its index alone, never on the machine, the task or the order in
/// which runs finish, so the merged result is the same however the campaign was split.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "campaign/result_files.h"
#include "campaign/sweep.h"
#include "launcher/cluster_section.h"

namespace nimble::campaign {

inline constexpr const char* kBackendLocal = "local";
inline constexpr const char* kBackendSlurm = "slurm";

/// What makes two sweeps different: the sweep's keys of its manifest (result_files.h's Manifest,
/// DIR/campaign.json), written and read by nlohmann's to_json/from_json (campaign.cc).
struct SweepManifest {
  std::string scenario;       ///< its name
  std::string scenario_file;  ///< absolute
  /// Where `rig sweep` was started: relative paths in --set and --vary values resolve here, on
  /// every node too (tasks and --resume run in it).
  std::string working_dir;
  std::vector<Override> overrides;  ///< --set, applied to every run
  std::vector<Vary> vary;
  std::vector<std::string> set_digests;  ///< each set's configuration digest when the campaign was made
  uint64_t first_seed = 1, last_seed = 1;
  std::string clock;
  double trace_hz = 0.0;  ///< > 0: every run's report carries a trace (rig sweep --report)
  std::string logs_dir;   ///< keep each run's LCM log here (empty: none kept)
  std::string backend = kBackendLocal;
  launcher::ClusterSettings cluster;
};

/// A sweep kept in its directory: its manifest, the parameter sets it describes, and the files.
struct Campaign : SweepManifest {
  std::string dir;                 ///< absolute
  std::vector<ParameterSet> sets;  ///< from vary (parameter_sets), in the order of set_digests
  double created_unix_s = 0.0;     ///< when the campaign was made (the manifest's "made")
  /// Its directory's manifest and result files: held by this process (create_campaign,
  /// open_campaign) or written beside the one that holds it (load_campaign: an array task).
  ResultFiles results;

  std::size_t seeds_per_set() const { return static_cast<std::size_t>(last_seed - first_seed + 1); }
  std::size_t run_count() const { return sets.size() * seeds_per_set(); }
  std::size_t set_of(std::size_t run) const { return run / seeds_per_set(); }
  uint64_t seed_of(std::size_t run) const { return first_seed + run % seeds_per_set(); }
  std::size_t chunk_count() const;
  /// The runs of array task `task`: [task * chunk_size, ...).
  std::vector<std::size_t> chunk(std::size_t task) const;
  std::size_t task_of(std::size_t run) const { return run / cluster.chunk_size; }
  /// "set 2 seed 17" for messages.
  std::string run_name(std::size_t run) const;
  /// The run's key among the result files: run-NNNNNN.
  std::string run_key(std::size_t run) const;
  std::string run_file(std::size_t run) const { return files().file(run_key(run)); }
  const ResultFiles& files() const { return results; }
  std::string runs_dir() const { return files().runs_dir(); }
  std::string slurm_dir() const { return dir + "/slurm"; }
};

/// What `rig sweep` asks for, turned into a campaign.
struct CampaignRequest {
  SweepOptions sweep;
  std::string dir;  ///< empty: a new directory under rig_campaigns/
  std::string backend = kBackendLocal;
  launcher::ClusterSettings cluster;  ///< from the scenario's `cluster:` with the options over it
  bool report = false;                ///< traces for --report
};

/// The directory of a sweep that keeps none (no --dir): rig_sweep_<pid>_<n> under TMPDIR, made
/// fresh (what a stale one held removed), and removed when this goes out of scope, whatever
/// happened meanwhile (an error, an interrupted flight).
class TemporaryCampaignDir {
 public:
  TemporaryCampaignDir();
  ~TemporaryCampaignDir();
  TemporaryCampaignDir(const TemporaryCampaignDir&) = delete;
  TemporaryCampaignDir& operator=(const TemporaryCampaignDir&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

/// Loads every set's plan (a bad value in any set stops here, naming it) and takes the directory
/// through open_result_dir() (one writer; a new or empty directory gets the manifest and
/// scenario.yaml, one that holds this same campaign is taken to be finished: files().made() says
/// which; anything else is refused untouched).
/// @throws ConfigError (bad scenario values), OutputBusy (another process holds the directory),
///         std::runtime_error (the directory holds something else), ForeignResult.
Campaign create_campaign(const CampaignRequest& request);

/// Reads DIR/campaign.json and takes DIR as its one writer (rig sweep --resume, collect), its
/// partial files removed and its result files checked.
/// @throws as load_campaign(), and OutputBusy, ForeignResult.
Campaign open_campaign(const std::string& dir);

/// Reads DIR/campaign.json without taking DIR: for an array task, which writes its runs' results
/// while the `rig sweep` that submitted it holds DIR.
/// @throws std::runtime_error naming the file and what is wrong with it.
Campaign load_campaign(const std::string& dir);

/// Changes to the campaign's working directory.
/// @throws std::runtime_error if it is not there (not on a shared file system?).
void enter_working_dir(const Campaign& campaign);

/// Checks that the scenario and the files it names still give each set's digest of the manifest.
/// @throws ConfigError naming the set, if the scenario or a file it names changed.
void check_campaign_inputs(const Campaign& campaign);

/// The runs that have a result file, as flags by run index.
std::vector<bool> finished_runs(const Campaign& campaign);
/// The runs without a result file.
std::vector<std::size_t> missing_runs(const Campaign& campaign);

/// Progress of a campaign: runs finished (of all), runs not ok among them.
using ProgressFn = std::function<void(std::size_t finished, std::size_t not_ok)>;

/// Flies `runs` of the campaign that have no result file yet, `jobs` at a time, in the campaigns'
/// worker pool through run_kept() (result_files.h), and writes each one's result file as it
/// finishes. A run that crashes is a failed run with a result file, not a failed campaign.
/// `where` names the task in the result files (e.g. "slurm job 12 task 3"; empty: local).
void fly_campaign_runs(const Campaign& campaign, const std::vector<std::size_t>& runs, int jobs,
                       const std::string& where, const ProgressFn& progress);

/// The merged result from the result files.
/// @throws std::runtime_error naming the missing runs (the first few) or a damaged file;
///         ForeignResult naming a file that is not this campaign's.
SweepResult merge_campaign(const Campaign& campaign);

/// A one-line progress bar on stderr (a line per tenth of the campaign when not a terminal);
/// `failed` SIZE_MAX: not known (runs finished elsewhere), not shown.
void progress_bar(std::size_t done, std::size_t total, std::size_t failed, double wall_s, bool tty);

/// `s` without leading and trailing blanks (spaces, tabs, line ends).
std::string trim(const std::string& s);
/// The last line of `file` that is not blank, trimmed (empty if none or no file): what a run or
/// a task said last before it ended.
std::string last_line(const std::string& file);

}  // namespace nimble::campaign
