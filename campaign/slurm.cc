#include "campaign/slurm.h"

#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "core/descriptors.h"
#include "core/output_file.h"
#include "transport/clock.h"

namespace nimble::campaign {

// One run is the launcher's (run plan, executors, report); a campaign flies many.
using namespace launcher;
namespace {

namespace fs = std::filesystem;

/// How often the campaign's result files are counted while waiting [ms] (a listing of the runs
/// directory: slower for large campaigns on a network file system), and how often Slurm is asked
/// whether the job still has tasks [ms] (a cluster's controller is shared: not too often).
constexpr int kFilePollMs = 100;
constexpr int kFilePollLargeMs = 1000;
constexpr std::size_t kLargeCampaignRuns = 5000;
constexpr int kQueuePollMs = 2000;

std::string shell_quote(const std::string& s) {
  std::string q = "'";
  for (const char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::string job_name(const std::string& scenario) {
  std::string name = "rig-sweep-";
  for (const char c : scenario) name += std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' ? c : '_';
  return name.substr(0, 64);
}

std::string runs_text(const Campaign& c, const std::vector<std::size_t>& runs) {
  if (runs.empty()) return "no runs";
  if (runs.size() == 1) return "run " + std::to_string(runs[0]) + " (" + c.run_name(runs[0]) + ")";
  return "runs " + std::to_string(runs.front()) + "-" + std::to_string(runs.back()) + " (" + c.run_name(runs.front()) +
         " to " + c.run_name(runs.back()) + ")";
}

}  // namespace

CommandOutput run_command(const std::vector<std::string>& argv) {
  CommandOutput r;
  int out_pipe[2], err_pipe[2];
  if (::pipe(out_pipe) != 0) return r;
  if (::pipe(err_pipe) != 0) {
    ::close(out_pipe[0]);
    ::close(out_pipe[1]);
    return r;
  }
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::dup2(out_pipe[1], STDOUT_FILENO);
    ::dup2(err_pipe[1], STDERR_FILENO);
    ::close(out_pipe[0]);
    ::close(err_pipe[0]);
    ::close(out_pipe[1]);
    ::close(err_pipe[1]);
    close_descriptors_from(STDERR_FILENO + 1);
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    ::execvp(args[0], args.data());
    ::_exit(127);
  }
  ::close(out_pipe[1]);
  ::close(err_pipe[1]);
  if (pid < 0) {
    ::close(out_pipe[0]);
    ::close(err_pipe[0]);
    return r;
  }
  pollfd fds[2] = {{out_pipe[0], POLLIN, 0}, {err_pipe[0], POLLIN, 0}};
  std::string* sinks[2] = {&r.out, &r.err};
  int open_fds = 2;
  char buf[4096];
  while (open_fds > 0) {
    if (::poll(fds, 2, -1) < 0) {
      if (errno == EINTR) continue;
      break;
    }
    for (int k = 0; k < 2; ++k) {
      if (fds[k].fd < 0 || (fds[k].revents & (POLLIN | POLLHUP | POLLERR)) == 0) continue;
      const ssize_t n = ::read(fds[k].fd, buf, sizeof buf);
      if (n > 0) {
        sinks[k]->append(buf, static_cast<std::size_t>(n));
      } else if (n == 0 || errno != EINTR) {
        ::close(fds[k].fd);
        fds[k].fd = -1;
        --open_fds;
      }
    }
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  if (r.exit_code == 127 && r.out.empty() && r.err.empty()) r.exit_code = -1;  // not found
  return r;
}

std::string array_spec(std::vector<std::size_t> tasks) {
  std::sort(tasks.begin(), tasks.end());
  tasks.erase(std::unique(tasks.begin(), tasks.end()), tasks.end());
  std::string spec;
  for (std::size_t k = 0; k < tasks.size();) {
    std::size_t j = k;
    while (j + 1 < tasks.size() && tasks[j + 1] == tasks[j] + 1) ++j;
    spec += (spec.empty() ? "" : ",") + std::to_string(tasks[k]);
    if (j > k) spec += "-" + std::to_string(tasks[j]);
    k = j + 1;
  }
  return spec;
}

std::string write_batch_script(const Campaign& c) {
  fs::create_directories(c.slurm_dir());
  const ClusterSettings& k = c.cluster;
  std::ostringstream s;
  s << "#!/bin/bash\n"
    << "# rig sweep campaign '" << c.scenario << "': " << c.run_count() << " runs in " << c.chunk_count()
    << " array tasks of up to " << k.chunk_size << " runs.\n"
    << "# Each task flies its runs (" << k.cpus_per_task << " at a time) and writes one result file per run into\n"
    << "# " << c.runs_dir() << ";\n"
    << "# the campaign directory must be on a file system that every node sees at this path.\n"
    << "# Submitted by rig sweep with sbatch --array=<tasks> (the tasks still missing runs);\n"
    << "# `rig sweep collect " << c.dir << "` merges the runs, `rig sweep --resume " << c.dir << "` finishes them.\n"
    << "#SBATCH --job-name=" << job_name(c.scenario) << "\n"
    << "#SBATCH --output=" << c.slurm_dir() << "/task-%A_%a.out\n"
    << "#SBATCH --cpus-per-task=" << k.cpus_per_task << "\n"
    << "#SBATCH --ntasks=1\n"
    << "#SBATCH --time=" << k.time_limit << "\n";
  if (!k.partition.empty()) s << "#SBATCH --partition=" << k.partition << "\n";
  if (!k.account.empty()) s << "#SBATCH --account=" << k.account << "\n";
  if (k.memory_mb_per_cpu > 0) s << "#SBATCH --mem-per-cpu=" << k.memory_mb_per_cpu << "\n";
  s << "set -euo pipefail\n"
    << "exec " << shell_quote(k.rig) << " sweep task " << shell_quote(c.dir)
    << " --task \"$SLURM_ARRAY_TASK_ID\" --jobs \"${SLURM_CPUS_PER_TASK:-" << k.cpus_per_task << "}\"\n";
  const std::string file = c.slurm_dir() + "/sweep.sbatch";
  write_file(file, s.str());
  fs::permissions(file, fs::perms::owner_all | fs::perms::group_read | fs::perms::others_read);
  return file;
}

std::string submit_tasks(const Campaign& c, const std::vector<std::size_t>& tasks) {
  const std::string script = write_batch_script(c);
  const std::string spec = array_spec(tasks);
  const CommandOutput r = run_command({"sbatch", "--parsable", "--array=" + spec, "--chdir=" + c.working_dir, script});
  if (r.exit_code == -1) {
    throw std::runtime_error(
        "sbatch not found: the slurm backend needs Slurm's client commands on PATH "
        "(Debian: slurm-client) and a cluster to submit to");
  }
  if (r.exit_code != 0) {
    throw std::runtime_error("sbatch refused the campaign's job (exit " + std::to_string(r.exit_code) +
                             "): " + trim(r.err + r.out));
  }
  // --parsable: "jobid" or "jobid;cluster".
  std::string job = trim(r.out);
  job = job.substr(0, job.find(';'));
  if (job.empty() || job.find_first_not_of("0123456789") != std::string::npos) {
    throw std::runtime_error("sbatch gave no job id: '" + trim(r.out) + "'");
  }
  append_to_file(c.slurm_dir() + "/jobs.txt", job + " " + spec + "\n");
  return job;
}

std::vector<std::string> campaign_jobs(const Campaign& c) {
  std::vector<std::string> jobs;
  std::ifstream in(c.slurm_dir() + "/jobs.txt");
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream ss(line);
    std::string job;
    if (ss >> job) jobs.push_back(job);
  }
  return jobs;
}

std::map<std::size_t, std::string> active_tasks(const std::string& job) {
  // -r: one line per array task, pending ones too; %K the task id, %T the state.
  const CommandOutput r = run_command({"squeue", "-h", "-r", "-j", job, "-o", "%K %T"});
  if (r.exit_code == -1) throw std::runtime_error("squeue not found (Debian: slurm-client)");
  std::map<std::size_t, std::string> active;
  if (r.exit_code != 0) {
    // A job Slurm no longer holds is over.
    if (r.err.find("Invalid job id") != std::string::npos) return active;
    throw std::runtime_error("squeue failed for job " + job + ": " + trim(r.err + r.out));
  }
  std::istringstream in(r.out);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string id, state;
    if (!(ls >> id >> state)) continue;
    // A pending array record may read "0-7" or "3,5"; every task in it is pending.
    std::istringstream parts(id);
    std::string part;
    while (std::getline(parts, part, ',')) {
      const auto dash = part.find('-');
      const auto percent = part.find('%');
      if (percent != std::string::npos) part.erase(percent);
      try {
        if (dash == std::string::npos) {
          active[std::stoul(part)] = state;
        } else {
          for (std::size_t t = std::stoul(part.substr(0, dash)); t <= std::stoul(part.substr(dash + 1)); ++t) {
            active[t] = state;
          }
        }
      } catch (const std::exception&) {
        // Not a task id ("N/A" for a job that is no array): nothing to track.
      }
    }
  }
  return active;
}

std::vector<std::string> jobs_still_running(const Campaign& c) {
  std::vector<std::string> lines;
  for (const auto& job : campaign_jobs(c)) {
    const auto active = active_tasks(job);
    if (active.empty()) continue;
    std::vector<std::size_t> tasks;
    for (const auto& kv : active) tasks.push_back(kv.first);
    lines.push_back("Slurm job " + job + " still has tasks " + array_spec(tasks) + " (" + active.begin()->second + ")");
  }
  return lines;
}

std::map<std::size_t, std::string> task_outcomes(const std::string& job) {
  std::map<std::size_t, std::string> out;
  const CommandOutput r = run_command({"scontrol", "-o", "show", "job", job});
  if (r.exit_code != 0) return out;
  static const std::regex task_re(R"(ArrayTaskId=(\d+))"), state_re(R"(JobState=(\S+))"), exit_re(R"( ExitCode=(\S+))"),
      reason_re(R"( Reason=(\S+))");
  std::istringstream in(r.out);
  std::string line;
  while (std::getline(in, line)) {
    std::smatch task, state, exit, reason;
    if (!std::regex_search(line, task, task_re) || !std::regex_search(line, state, state_re)) continue;
    std::string text = state[1].str();
    if (std::regex_search(line, exit, exit_re)) text += " exit " + exit[1].str();
    if (std::regex_search(line, reason, reason_re) && reason[1].str() != "None") text += " (" + reason[1].str() + ")";
    out[std::stoul(task[1].str())] = text;
  }
  return out;
}

void wait_for_job(const Campaign& c, const std::string& job, const std::vector<std::size_t>& tasks,
                  const ProgressFn& progress) {
  std::set<std::size_t> watched;
  for (const std::size_t t : tasks) {
    for (const std::size_t i : c.chunk(t)) watched.insert(i);
  }
  int64_t next_queue_ns = 0;
  std::size_t last_finished = SIZE_MAX;
  for (;;) {
    const std::vector<bool> done = finished_runs(c);
    const std::size_t finished = static_cast<std::size_t>(std::count(done.begin(), done.end(), true));
    if (progress && finished != last_finished) progress(finished, 0);
    last_finished = finished;
    bool all = true;
    for (const std::size_t i : watched) all = all && done[i];
    if (all) return;
    const int64_t now = transport::monotonic_ns();
    if (now >= next_queue_ns) {
      next_queue_ns = now + int64_t{kQueuePollMs} * 1000000;
      if (active_tasks(job).empty()) {
        // The job is over: a last count, for runs that finished as it ended.
        const std::vector<bool> last = finished_runs(c);
        const std::size_t n = static_cast<std::size_t>(std::count(last.begin(), last.end(), true));
        if (progress && n != finished) progress(n, 0);
        return;
      }
    }
    std::this_thread::sleep_for(
        std::chrono::milliseconds(c.run_count() > kLargeCampaignRuns ? kFilePollLargeMs : kFilePollMs));
  }
}

std::vector<std::size_t> tasks_with_missing_runs(const Campaign& c) {
  std::vector<std::size_t> tasks;
  for (const std::size_t i : missing_runs(c)) {
    const std::size_t t = c.task_of(i);
    if (tasks.empty() || tasks.back() != t) tasks.push_back(t);
  }
  return tasks;
}

std::vector<std::string> describe_missing(const Campaign& c, const std::string& job,
                                          const std::vector<std::size_t>& tasks) {
  const std::vector<bool> done = finished_runs(c);
  const std::map<std::size_t, std::string> outcomes = task_outcomes(job);
  std::vector<std::string> lines;
  for (const std::size_t t : tasks) {
    const std::vector<std::size_t> runs = c.chunk(t);
    std::vector<std::size_t> missing;
    for (const std::size_t i : runs) {
      if (!done[i]) missing.push_back(i);
    }
    if (missing.empty()) continue;
    std::string how;
    const auto it = outcomes.find(t);
    if (it != outcomes.end()) {
      how = it->second;
    } else {
      // Slurm keeps no record of an array task cancelled while it was pending; one that ran
      // wrote its output file (slurmstepd adds "*** ... CANCELLED AT ..." to it when cancelled).
      const std::string output = c.slurm_dir() + "/task-" + job + "_" + std::to_string(t) + ".out";
      if (!fs::exists(output)) {
        how = "never started (CANCELLED while pending: Slurm has no record of it and it wrote no output)";
      } else {
        const std::string said = last_line(output);
        how = said.empty() ? "ended (Slurm no longer reports how)" : "ended; its output's last line: " + said;
      }
    }
    std::string names;
    for (std::size_t k = 0; k < std::min<std::size_t>(missing.size(), 4); ++k) {
      names += (k ? ", " : "") + c.run_name(missing[k]);
    }
    if (missing.size() > 4) names += ", ...";
    lines.push_back("job " + job + " task " + std::to_string(t) + " (" + runs_text(c, runs) + ") " + how + ": " +
                    std::to_string(missing.size()) + " of " + std::to_string(runs.size()) + " runs without a result (" +
                    names + ")");
  }
  return lines;
}

}  // namespace nimble::campaign
