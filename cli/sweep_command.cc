/// `rig sweep`: a Monte Carlo campaign over a scenario (campaign/sweep.h), on this machine or on
/// a Slurm cluster (campaign/campaign.h, campaign/slurm.h).
///
///   rig sweep SCENARIO --seeds A-B [--vary ...] [--backend local|slurm] [--dir DIR] ...
///   rig sweep --resume DIR      finish a campaign that was interrupted
///   rig sweep collect DIR       merge a campaign whose runs are there
///   rig sweep task DIR --task K one array task's runs (what the batch script runs)

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "cmdline/args.h"
#include "cli/commands.h"
#include "core/output_file.h"
#include "campaign/campaign.h"
#include "campaign/slurm.h"
#include "campaign/sweep.h"
#include "campaign/sweep_report.h"
#include "transport/clock.h"

namespace nimble::cli {
namespace {

namespace fs = std::filesystem;

/// Exit code of a campaign that ended with runs missing (tasks failed or cancelled, retries spent).
constexpr int kExitIncomplete = 3;

constexpr const char* kSweepDescription =
    "Flies the scenario once per seed A..B and per combination of the --vary values (each --vary\n"
    "multiplies the parameter sets). Run i flies set i / S with seed A + i % S (S seeds per set), so\n"
    "the result is the same wherever and however the runs are split. --backend local (default) flies\n"
    "N runs at a time on this machine, each in its own child process; --backend slurm writes the\n"
    "campaign to DIR (on a file system the cluster's nodes share) and submits it as one array job,\n"
    "each task a chunk of runs. Prints per parameter set the controlled rate and percentiles across\n"
    "runs of the extremes, state ranges and estimator errors, and each run that was not ok.\n"
    "\n"
    "  rig sweep --resume DIR    flies (or submits) the runs of DIR that have no result yet\n"
    "  rig sweep collect DIR     merges DIR's runs (exit 3 naming the missing ones if some are)\n"
    "  rig sweep task DIR --task K   one array task's runs (the batch script runs it)";

constexpr const char* kSweepFooter =
    "Exit code: 0 every run ok, 1 some run not ok, 2 bad input, 3 runs without a result (a task failed\n"
    "or was cancelled and --retries are spent; `rig sweep --resume DIR` finishes them).\n"
    "Example: rig sweep rig_configs/id_doublet_train_fast.yaml --seeds 1-20 \\\n"
    "           --vary model=rig_configs/models/nimble_lateral_set1.yaml,rig_configs/models/nimble_lateral_set2.yaml\n"
    "         rig sweep rig_configs/hover.yaml --seeds 1-200 --backend slurm --dir /shared/c1 --partition short";

/// Where the merged result goes.
struct Outputs {
  std::string json_file, csv_file, report_dir;
  bool progress = true;
};

void add_outputs(cmdline::CommandLine& cl, Outputs& o) {
  cl.add_json(o.json_file, "the sets and a 'runs' list (seed, verdict, figures; `machine` fields say where it ran)");
  cl->add_option("--csv", o.csv_file, "one row per run (machine_* columns say where it ran)")->type_name("FILE");
  cl->add_option("--report", o.report_dir,
                 "per parameter set the envelopes of p, v and phi across seeds (median, 5-95 %) and the controlled "
                 "rate with its 95 % Wilson interval: CSV, JSON, SVG plots and index.html in DIR")
      ->type_name("DIR");
  cl->add_flag("--no-progress", "no progress line on stderr")->each([&o](const std::string&) { o.progress = false; });
}

bool write_text(const std::string& file, const std::string& text) {
  if (file.empty()) return true;
  if (file == "-") {
    std::cout << text;
    return true;
  }
  try {
    write_file(file, text);
    return true;
  } catch (const OutputError& e) {
    std::cerr << "rig sweep: " << e.what() << "\n";
    return false;
  }
}

/// Merges the campaign, writes DIR/result.json and DIR/result.csv (kept campaigns) and what
/// the options ask for, prints the summary; returns the exit code.
int finish(const campaign::Campaign& c, const Outputs& o, bool keep, int jobs, double wall_s) {
  campaign::SweepResult result;
  try {
    result = campaign::merge_campaign(c);
  } catch (const campaign::ForeignResult& e) {
    std::cerr << "rig sweep: " << e.what() << "\n";
    return cmdline::kExitUsage;
  } catch (const std::exception& e) {
    std::cerr << "rig sweep: campaign " << c.dir << " incomplete: " << e.what() << "\n"
              << "  `rig sweep --resume " << c.dir << "` flies the missing runs\n";
    return kExitIncomplete;
  }
  result.jobs = c.backend == campaign::kBackendSlurm ? c.cluster.cpus_per_task : jobs;
  if (wall_s > 0) result.wall_time_s = wall_s;
  const std::string json = campaign::sweep_json(result) + "\n", csv = campaign::sweep_csv(result);
  campaign::write_sweep_text(o.json_file == "-" ? std::cerr : std::cout, result);
  bool written = write_text(o.json_file, json);
  written = write_text(o.csv_file, csv) && written;
  try {
    if (keep) {
      write_file(c.dir + "/result.json", json);
      write_file(c.dir + "/result.csv", csv);
      (o.json_file == "-" ? std::cerr : std::cout) << "campaign " << c.dir << ": result.json, result.csv\n";
    }
    if (!o.report_dir.empty()) {
      if (c.trace_hz <= 0) {
        std::cerr << "rig sweep: the campaign was made without --report, so its runs carry no trace: the report "
                     "gives the controlled rates without envelopes\n";
      }
      campaign::write_sweep_report(result, o.report_dir);
      (o.json_file == "-" ? std::cerr : std::cout) << "report " << o.report_dir << "/index.html\n";
    }
  } catch (const std::exception& e) {
    std::cerr << "rig sweep: " << e.what() << "\n";
    written = false;
  }
  if (!written) return cmdline::kExitUsage;
  for (const auto& run : result.runs) {
    if (run.exit_code != launcher::kRunOk) return 1;
  }
  return 0;
}

campaign::ProgressFn progress_fn(bool enabled, std::size_t total, std::size_t already, int64_t start_ns) {
  if (!enabled) return {};
  const bool tty = ::isatty(STDERR_FILENO);
  return [=](std::size_t finished, std::size_t not_ok) {
    campaign::progress_bar(already + finished, total, not_ok,
                           static_cast<double>(transport::monotonic_ns() - start_ns) / 1e9, tty);
  };
}

/// Submits the campaign's tasks that miss runs, waits, resubmits up to `retries` times.
/// Returns 0 when every run has a result, kExitIncomplete otherwise (having named the tasks).
int run_on_slurm(const campaign::Campaign& c, int retries, bool wait, bool progress, int64_t start_ns) {
  for (int attempt = 0;; ++attempt) {
    const std::vector<std::size_t> tasks = campaign::tasks_with_missing_runs(c);
    if (tasks.empty()) return 0;
    const std::string job = campaign::submit_tasks(c, tasks);
    std::cerr << "rig sweep: submitted Slurm job " << job << " (array tasks " << campaign::array_spec(tasks) << " of "
              << c.chunk_count() << ", up to " << c.cluster.chunk_size << " runs each) for " << c.dir << "\n";
    if (!wait) {
      std::cout << job << "\n";
      std::cerr << "  `rig sweep collect " << c.dir << "` merges the runs when they are there\n";
      return 0;
    }
    if (attempt == 0) {
      std::cerr << "  waiting (Ctrl-C leaves the job running: `rig sweep collect " << c.dir << "` later)\n";
    }
    campaign::wait_for_job(c, job, tasks, [&](std::size_t finished, std::size_t) {
      if (progress) {
        campaign::progress_bar(finished, c.run_count(), SIZE_MAX,
                               static_cast<double>(transport::monotonic_ns() - start_ns) / 1e9,
                               ::isatty(STDERR_FILENO));
      }
    });
    const std::vector<std::string> lines = campaign::describe_missing(c, job, tasks);
    if (lines.empty()) return 0;
    for (const auto& line : lines) std::cerr << "rig sweep: " << line << "\n";
    if (attempt >= retries) {
      std::cerr << "rig sweep: " << campaign::missing_runs(c).size() << " runs without a result"
                << (retries > 0 ? " after " + std::to_string(retries) + " retr" + (retries == 1 ? "y" : "ies") : "")
                << "; `rig sweep --resume " << c.dir << "` submits them again\n";
      return kExitIncomplete;
    }
    std::cerr << "rig sweep: retry " << attempt + 1 << " of " << retries << ": resubmitting the tasks that miss runs\n";
  }
}

int default_jobs() { return static_cast<int>(std::max(1u, std::thread::hardware_concurrency())); }

int task_command(const std::vector<std::string>& args) {
  std::string dir;
  std::size_t task = 0;
  int jobs = 0;
  cmdline::CommandLine cl("rig sweep task",
                          "Flies the runs of one array task of a campaign that have no result yet (what the "
                          "campaign's batch script runs on a node), each run's result file written atomically.");
  cl->add_option("dir", dir, "the campaign directory")->required();
  cl->add_option("--task", task, "the array task (SLURM_ARRAY_TASK_ID)")->required();
  cl->add_option("--jobs", jobs, "runs at a time (default: the campaign's CPUs per task)")->check(CLI::Range(1, 1024));
  if (const auto done = cl.parse(args)) return *done;
  try {
    const campaign::Campaign c = campaign::load_campaign(dir);
    if (task >= c.chunk_count()) {
      return cl.fail("--task " + std::to_string(task) + ": the campaign has tasks 0-" +
                     std::to_string(c.chunk_count() - 1));
    }
    campaign::enter_working_dir(c);
    campaign::check_campaign_inputs(c);
    const char* job = std::getenv("SLURM_ARRAY_JOB_ID");
    const std::string where =
        (job ? "slurm job " + std::string(job) + " " : std::string()) + "task " + std::to_string(task);
    const std::vector<std::size_t> runs = c.chunk(task);
    std::cerr << "rig sweep task: " << c.dir << " task " << task << ", runs " << runs.front() << "-" << runs.back()
              << "\n";
    campaign::fly_campaign_runs(c, runs, jobs > 0 ? jobs : c.cluster.cpus_per_task, where, {});
    const std::vector<bool> done = campaign::finished_runs(c);
    for (const std::size_t i : runs) {
      if (!done[i]) {
        std::cerr << "rig sweep task: " << c.run_name(i) << " has no result\n";
        return 1;
      }
    }
    return 0;
  } catch (const ConfigError& e) {
    std::cerr << "rig sweep task: config error: " << e.what() << "\n";
  } catch (const std::exception& e) {
    std::cerr << "rig sweep task: " << e.what() << "\n";
  }
  return cmdline::kExitUsage;
}

int collect_command(const std::vector<std::string>& args) {
  std::string dir;
  Outputs o;
  cmdline::CommandLine cl("rig sweep collect",
                          "Merges a campaign's runs (rig sweep --backend slurm --no-wait, or one that was "
                          "interrupted): the summary, DIR/result.json and DIR/result.csv. Runs without a "
                          "result are named, with the Slurm jobs still running, and exit 3.");
  cl->add_option("dir", dir, "the campaign directory")->required();
  add_outputs(cl, o);
  if (const auto done = cl.parse(args)) return *done;
  try {
    const campaign::Campaign c = campaign::open_campaign(dir);
    if (c.backend == campaign::kBackendSlurm) {
      for (const auto& line : campaign::jobs_still_running(c)) std::cerr << "rig sweep collect: " << line << "\n";
    }
    return finish(c, o, true, 0, 0.0);
  } catch (const std::exception& e) {
    std::cerr << "rig sweep collect: " << e.what() << "\n";
    return cmdline::kExitUsage;
  }
}

/// The sweep's own options: the scenario, seeds, --vary sets, how many at a time, clock, overrides
/// and logs; returns the options --seeds and --jobs (whether they were given).
std::pair<CLI::Option*, CLI::Option*> add_sweep_options(cmdline::CommandLine& cl, campaign::SweepOptions& o) {
  cl->add_option("scenario", o.base.scenario_file, "the scenario file");
  auto* seeds = cl->add_option("--seeds", "the seeds A-B, each flown once per parameter set")->type_name("A-B");
  cmdline::each_value(
      seeds, [&o](const std::string& v) { std::tie(o.first_seed, o.last_seed) = campaign::parse_seed_range(v); });
  cmdline::each_value(
      cl->add_option("--vary", "a parameter and its values (repeatable; the sets are every combination)")
          ->type_name("KEY=V1,V2,...")
          ->allow_extra_args(false)
          ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll),
      [&o](const std::string& v) { o.vary.push_back(campaign::parse_vary(v)); });
  auto* jobs = cl->add_option("--jobs", o.jobs, "local: runs at a time (default: one per CPU)")
                   ->check(CLI::Range(1, 256))
                   ->type_name("N");
  cl->add_option("--clock", o.base.clock, "inprocess (default), lockstep or realtime")
      ->check(CLI::IsMember({std::string(launcher::kClockInprocess), std::string(launcher::kClockLockstep),
                             std::string(launcher::kClockRealtime)}));
  cmdline::each_value(cl->add_option("--set", "override one scenario value in every run, parsed as YAML (repeatable)")
                          ->type_name("KEY.PATH=VALUE")
                          ->allow_extra_args(false)
                          ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll),
                      [&o](const std::string& v) { o.base.overrides.push_back(parse_override(v)); });
  cl->add_option("--logs", o.logs_dir, "keep each run's LCM log in DIR (slurm: on the shared file system)")
      ->type_name("DIR");
  return {seeds, jobs};
}

/// The campaign's options: backend, directory, --resume, and the Slurm settings over the
/// scenario's cluster section.
void add_campaign_options(cmdline::CommandLine& cl, campaign::CampaignRequest& req, std::string& resume_dir,
                          int& retries, bool& no_wait, std::size_t& chunk, launcher::ClusterSettings& cli_cluster) {
  cl->add_option("--backend", req.backend, "local (default) or slurm")
      ->check(CLI::IsMember({std::string(campaign::kBackendLocal), std::string(campaign::kBackendSlurm)}));
  cl->add_option(
        "--dir", req.dir,
        "the campaign directory (slurm: on a file system every node sees; default rig_campaigns/<name>-<time>; "
        "local: kept only if given)")
      ->type_name("DIR");
  cl->add_option("--resume", resume_dir, "finish the campaign in DIR: fly or submit the runs without a result")
      ->type_name("DIR");
  cl->add_option("--retries", retries, "slurm: resubmit the tasks that left runs without a result up to N times")
      ->check(CLI::Range(0, 100))
      ->type_name("N");
  cl->add_flag("--no-wait", no_wait, "slurm: print the job id and return; `rig sweep collect DIR` merges later");
  cl->add_option("--chunk", chunk,
                 "slurm: runs per array task (default: cluster.chunk_size, else 100 in process, "
                 "4 lockstep, 1 real time)")
      ->check(CLI::Range(1, 1000000))
      ->type_name("N");
  cl->add_option("--partition", cli_cluster.partition, "slurm: the partition (default: cluster.partition)");
  cl->add_option("--account", cli_cluster.account, "slurm: the account (default: cluster.account)");
  cl->add_option("--time", cli_cluster.time_limit,
                 "slurm: each task's time limit (default: cluster.time_limit, 01:00:00)")
      ->type_name("TIME");
  cl->add_option("--cpus-per-task", cli_cluster.cpus_per_task,
                 "slurm: CPUs of each task, its runs at a time (default: cluster.cpus_per_task, 1)")
      ->check(CLI::Range(1, 1024));
  cl->add_option("--mem-per-cpu", cli_cluster.memory_mb_per_cpu, "slurm: memory per CPU [MB] (default: the cluster's)")
      ->check(CLI::Range(0, 1 << 24));
  cl->add_option("--rig", cli_cluster.rig, "slurm: the rig executable as the nodes see it (default: this one)")
      ->type_name("PATH");
  cli_cluster.time_limit.clear();
  cli_cluster.cpus_per_task = 0;
  cli_cluster.memory_mb_per_cpu = -1;
}

/// Flies (or submits) the runs of a campaign this process holds that have no result yet: `rig
/// sweep --resume DIR`, or `rig sweep ... --dir DIR` again on the same campaign.
int finish_campaign(const campaign::Campaign& c, int retries, bool no_wait, int n_jobs, const Outputs& out,
                    int64_t start_ns) {
  campaign::enter_working_dir(c);
  campaign::check_campaign_inputs(c);
  const std::size_t missing = campaign::missing_runs(c).size();
  std::cerr << "rig sweep: resuming " << c.dir << ": " << missing << " of " << c.run_count()
            << " runs without a result\n";
  if (c.backend == campaign::kBackendSlurm) {
    const std::vector<std::string> running = campaign::jobs_still_running(c);
    if (!running.empty()) {
      for (const auto& line : running) std::cerr << "rig sweep: " << line << "\n";
      std::cerr << "rig sweep: wait for it (`rig sweep collect " << c.dir << "`) or scancel it before --resume\n";
      return cmdline::kExitUsage;
    }
    const int code = run_on_slurm(c, retries, !no_wait, out.progress, start_ns);
    if (code != 0 || no_wait) return code;
    return finish(c, out, true, 0, 0.0);
  }
  campaign::fly_campaign_runs(c, campaign::missing_runs(c), n_jobs, "",
                              progress_fn(out.progress, c.run_count(), c.run_count() - missing, start_ns));
  return finish(c, out, true, n_jobs, 0.0);
}

/// Makes the campaign the request asks for (the scenario's cluster section, then the options over
/// it) and flies it here or on Slurm; a local campaign without --dir is removed after.
int fly_campaign(campaign::CampaignRequest& req, const launcher::ClusterSettings& cli_cluster, std::size_t chunk,
                 const Outputs& out, int retries, bool no_wait, int64_t start_ns) {
  const campaign::SweepOptions& o = req.sweep;
  const bool slurm = req.backend == campaign::kBackendSlurm;
  // The scenario's cluster section, then the options over it.
  req.cluster = launcher::cluster_settings_from(launcher::load_run_plan(o.base).scenario);
  if (!cli_cluster.partition.empty()) req.cluster.partition = cli_cluster.partition;
  if (!cli_cluster.account.empty()) req.cluster.account = cli_cluster.account;
  if (!cli_cluster.time_limit.empty()) req.cluster.time_limit = cli_cluster.time_limit;
  if (cli_cluster.cpus_per_task > 0) req.cluster.cpus_per_task = cli_cluster.cpus_per_task;
  if (cli_cluster.memory_mb_per_cpu >= 0) req.cluster.memory_mb_per_cpu = cli_cluster.memory_mb_per_cpu;
  if (!cli_cluster.rig.empty()) req.cluster.rig = fs::absolute(cli_cluster.rig).string();
  if (chunk > 0) req.cluster.chunk_size = chunk;
  req.report = !out.report_dir.empty();
  const bool keep = slurm || !req.dir.empty();
  std::optional<campaign::TemporaryCampaignDir> temporary;  // removed on return, whatever happened
  if (!keep) req.dir = temporary.emplace().path();
  const campaign::Campaign c = campaign::create_campaign(req);
  if (!c.files().made()) return finish_campaign(c, retries, no_wait, o.jobs, out, start_ns);  // the same campaign
  int code = 0;
  if (slurm) {
    code = run_on_slurm(c, retries, !no_wait, out.progress, start_ns);
    if (code == 0 && !no_wait) code = finish(c, out, true, 0, 0.0);
  } else {
    campaign::fly_campaign_runs(c, campaign::missing_runs(c), o.jobs, "",
                                progress_fn(out.progress, c.run_count(), 0, start_ns));
    code = finish(c, out, keep, o.jobs, static_cast<double>(transport::monotonic_ns() - start_ns) / 1e9);
  }
  return code;
}

}  // namespace

int run_sweep_command(const std::vector<std::string>& args) {
  if (!args.empty() && args[0] == "task") return task_command({args.begin() + 1, args.end()});
  if (!args.empty() && args[0] == "collect") return collect_command({args.begin() + 1, args.end()});

  campaign::CampaignRequest req;
  campaign::SweepOptions& o = req.sweep;
  o.jobs = default_jobs();
  Outputs out;
  std::string resume_dir, chunk_text;
  bool no_wait = false;
  int retries = 0;
  launcher::ClusterSettings cli_cluster;
  std::size_t chunk = 0;
  cmdline::CommandLine cl("rig sweep", kSweepDescription);
  cl->footer(kSweepFooter);
  const auto [seeds, jobs] = add_sweep_options(cl, o);
  add_outputs(cl, out);
  add_campaign_options(cl, req, resume_dir, retries, no_wait, chunk, cli_cluster);
  if (const auto done = cl.parse(args)) return *done;

  const int64_t start_ns = transport::monotonic_ns();
  try {
    if (!resume_dir.empty()) {
      if (!o.base.scenario_file.empty() || seeds->count() > 0) {
        return cl.fail("--resume DIR takes the campaign's own scenario and seeds; give neither");
      }
      const int n_jobs = jobs->count() > 0 ? o.jobs : default_jobs();
      return finish_campaign(campaign::open_campaign(resume_dir), retries, no_wait, n_jobs, out, start_ns);
    }

    if (o.base.scenario_file.empty()) return cl.fail("a scenario file (or --resume DIR) is required");
    if (seeds->count() == 0) return cl.fail("--seeds is required: A-B, the seeds each parameter set is flown with");
    const bool slurm = req.backend == campaign::kBackendSlurm;
    if (!slurm && (no_wait || retries > 0)) return cl.fail("--no-wait and --retries are for --backend slurm");
    return fly_campaign(req, cli_cluster, chunk, out, retries, no_wait, start_ns);
  } catch (const ConfigError& e) {
    std::cerr << "rig sweep: config error: " << e.what() << "\n";
    return cmdline::kExitUsage;
  } catch (const std::exception& e) {
    std::cerr << "rig sweep: " << e.what() << "\n";
    return cmdline::kExitUsage;
  }
}

}  // namespace nimble::cli
