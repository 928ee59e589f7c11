/// bench_campaign: what one run of a campaign costs, by clock, and what running a campaign on
/// Slurm adds to running it here.
///
///   bench_campaign [scenario.yaml] [--duration S] [--campaign-runs N] [--slurm] [--repeats K] [--json F]
///
/// 1. Per run, for each clock (inprocess, lockstep, realtime), one `rig run` of the scenario
///    (default rig_configs/id_doublet_train_fast.yaml, every process) for S simulated seconds
///    (default 30): CPU seconds (user + system of the rig and every process it waited for), wall
///    seconds, the largest resident set of any of its processes, and LCM log bytes per simulated
///    second; from them runs per core-hour (3600 / CPU seconds; a real-time run is bound by the
///    wall clock instead: 3600 / wall seconds per run at a time).
/// 2. The machine's own scaling: the plant model alone (no rig code but the model) in one
///    process, then in one process per CPU at once: the most that one job per CPU can gain here.
///    `rig sweep` in process with one job and with one per CPU, as runs per second, against it.
/// 3. With --slurm (root; Debian's slurm-wlm and munge): a one-node cluster brought up by
///    tests/cluster/slurm_cluster.sh, and a campaign of N runs (default 200: the five published
///    parameter sets x N/5 seeds) flown with --backend local (one job per CPU) and --backend slurm
///    (one task per CPU, all runs in one wave; and chunks of 25 runs), each K times (median),
///    from the command to its merged result: Slurm's overhead over local (target <= 20 %).
/// Not a test: figures depend on the machine; the ratios are what travel.

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

#include "cmdline/args.h"
#include "core/bench_timing.h"
#include "launcher/run_plan.h"
#include "plant/plant_node.h"

namespace fs = std::filesystem;
using namespace nimble;

namespace {

struct Spawned {
  int exit_code = -1;
  double wall_s = 0.0, cpu_s = 0.0;
  double max_rss_mb = 0.0;
};

/// Runs argv to completion; its wall time and the resources of it and its waited-for children.
Spawned spawn(const std::vector<std::string>& argv, const std::string& out_file) {
  std::fflush(stdout);  // the child must not print this process's buffered lines again
  std::fflush(stderr);
  const auto t0 = std::chrono::steady_clock::now();
  const pid_t pid = ::fork();
  if (pid == 0) {
    std::freopen(out_file.c_str(), "w", stdout);
    std::freopen(out_file.c_str(), "a", stderr);
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    ::execvp(args[0], args.data());
    ::_exit(127);
  }
  int status = 0;
  rusage ru{};
  ::wait4(pid, &status, 0, &ru);
  Spawned s;
  s.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  s.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  const auto sec = [](const timeval& t) {
    return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec);
  };
  // wait4 gives the child's own usage; its descendants that it waited for are in RUSAGE_CHILDREN
  // of the child, which the kernel folds into the child's figures when it is reaped.
  s.cpu_s = sec(ru.ru_utime) + sec(ru.ru_stime);
  s.max_rss_mb = static_cast<double>(ru.ru_maxrss) / 1024.0;
  return s;
}

double seconds_of(const std::string& cmd) {
  const auto t0 = std::chrono::steady_clock::now();
  const int status = std::system(cmd.c_str());
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return WIFEXITED(status) && WEXITSTATUS(status) == 0 ? s : -s;
}

/// Wall seconds of `procs` processes each stepping the plant model alone for `sim_s` at once.
double plant_alone_s(const launcher::RunPlan& plan, double sim_s, int procs) {
  std::fflush(stdout);
  std::fflush(stderr);
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<pid_t> pids;
  for (int k = 0; k < procs; ++k) {
    const pid_t pid = ::fork();
    if (pid == 0) {
      // As bench_inprocess's floor: the model stepped at its rate with a square wave of delta_f.
      ConfigMap section = plan.scenario.section("plant");
      const plant::PlantConfig config = plant::plant_config_from(section);
      const std::unique_ptr<plant::PlantModel> model = plant::plant_model_for(plan.scenario, config);
      const effects::ActuatorInput trim = model->trim_command();
      const long steps = static_cast<long>(sim_s * config.rate_hz);
      for (long i = 0; i < steps; ++i) {
        effects::ActuatorInput u = trim;
        const double half_df = (i / 100) % 2 ? 1.25 : -1.25;
        u.flap_freq_left_radps += half_df;
        u.flap_freq_right_radps -= half_df;
        model->step(u);
      }
      ::_exit(0);
    }
    pids.push_back(pid);
  }
  for (const pid_t p : pids) ::waitpid(p, nullptr, 0);
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::string five_sets() {
  std::string vary = "model=";
  for (int k = 1; k <= 5; ++k) {
    vary += std::string(k > 1 ? "," : "") + RIG_SOURCE_DIR + "/rig_configs/models/nimble_lateral_set" +
            std::to_string(k) + ".yaml";
  }
  return vary;
}

/// 1. One run by clock: its CPU and wall seconds, largest RSS, log bytes and runs per hour.
void per_run_figures(const std::string& rig, const std::string& scenario, double duration_s, const std::string& dir,
                     nlohmann::json& j) {
  std::printf("\n  %-10s %9s %9s %12s %14s %16s\n", "clock", "CPU s", "wall s", "largest RSS", "log per sim s",
              "runs per hour");
  for (const char* clock : {"inprocess", "lockstep", "realtime"}) {
    const std::string log = dir + "/" + clock + ".lcmlog", json = dir + "/" + clock + ".json";
    const Spawned s = spawn({rig, "run", scenario, "--clock", clock, "--seed", "1", "--set",
                             "duration_s=" + std::to_string(duration_s), "--log", log, "--json", json, "--no-progress"},
                            dir + "/" + clock + ".out");
    if (s.exit_code != 0 || !fs::exists(json)) {
      std::printf("  %-10s failed (exit %d; %s)\n", clock, s.exit_code, (dir + "/" + clock + ".out").c_str());
      j["per_run"][clock] = {{"failed", true}};
      continue;
    }
    const double sim_s = YAML::LoadFile(json)["sim_time_s"].as<double>();
    const double log_kb_per_s = static_cast<double>(fs::file_size(log)) / 1024.0 / sim_s;
    const bool realtime = std::string(clock) == "realtime";
    // In process and lockstep a run is bound by CPU: runs per core-hour. In real time it is
    // bound by the clock: runs per hour for each run flown at a time.
    const double per_hour = realtime ? 3600.0 / s.wall_s : 3600.0 / s.cpu_s;
    std::printf("  %-10s %9.2f %9.2f %9.0f MB %11.0f kB %10.0f %s\n", clock, s.cpu_s, s.wall_s, s.max_rss_mb,
                log_kb_per_s, per_hour, realtime ? "per slot" : "per core");
    j["per_run"][clock] = {{"cpu_s", s.cpu_s},
                           {"wall_s", s.wall_s},
                           {"max_rss_mb", s.max_rss_mb},
                           {"log_bytes_per_sim_s", log_kb_per_s * 1024.0},
                           {"sim_s", sim_s},
                           {realtime ? "runs_per_hour_per_slot" : "runs_per_core_hour", per_hour}};
    fs::remove(log);
  }
}

/// 2. Scaling: the machine's (the plant model alone) against the sweep's.
void scaling_figures(const std::string& rig, const std::string& scenario, int cpus, int repeats, nlohmann::json& j) {
  launcher::RunOptions base;
  base.scenario_file = scenario;
  base.clock = launcher::kClockInprocess;
  const launcher::RunPlan plan = launcher::load_run_plan(base);
  std::vector<double> one, all;
  for (int k = 0; k < 3; ++k) {
    one.push_back(plant_alone_s(plan, 60.0, 1));
    all.push_back(plant_alone_s(plan, 60.0, cpus));
  }
  const double machine_scaling = cpus * median(one) / median(all);
  const std::string sweep =
      rig + " sweep " + scenario + " --seeds 1-20 --vary " + five_sets() + " --no-progress >/dev/null";
  std::vector<double> s1, sn;
  for (int k = 0; k < repeats; ++k) {
    s1.push_back(std::abs(seconds_of(sweep + " --jobs 1")));
    sn.push_back(std::abs(seconds_of(sweep + " --jobs " + std::to_string(cpus))));
  }
  const double sweep_scaling = median(s1) / median(sn);
  std::printf("\n  the plant model alone, %d processes at once against one: %.2fx (the machine's floor)\n", cpus,
              machine_scaling);
  std::printf("  rig sweep, 5 sets x 20 seeds, %d jobs against one: %.2fx (%.1f and %.1f runs/s), %.2f of the floor\n",
              cpus, sweep_scaling, 100.0 / median(s1), 100.0 / median(sn), sweep_scaling / machine_scaling);
  j["scaling"] = {{"machine_x", machine_scaling},
                  {"sweep_x", sweep_scaling},
                  {"sweep_runs_per_s_1job", 100.0 / median(s1)},
                  {"sweep_runs_per_s_all", 100.0 / median(sn)},
                  {"ratio_to_machine", sweep_scaling / machine_scaling}};
}

/// 3. Slurm against local, on a one-node cluster; false if the cluster did not start.
bool slurm_figures(const std::string& rig, const std::string& scenario, const std::string& dir, int cpus,
                   int campaign_runs, int repeats, nlohmann::json& j) {
  const std::string cluster = dir + "/cluster";
  const std::string start = std::string(RIG_SOURCE_DIR) + "/tests/cluster/slurm_cluster.sh start " + cluster + " >" +
                            dir + "/cluster.txt 2>&1";
  if (std::system(start.c_str()) != 0) {
    std::fprintf(stderr, "bench_campaign: the cluster did not start (%s/cluster.txt)\n", dir.c_str());
    return false;
  }
  ::setenv("SLURM_CONF", (cluster + "/slurm.conf").c_str(), 1);
  const int seeds = campaign_runs / 5;
  const std::string campaign =
      rig + " sweep " + scenario + " --seeds 1-" + std::to_string(seeds) + " --vary " + five_sets() + " --no-progress";
  std::vector<double> local, one_wave, chunks;
  for (int k = 0; k < repeats; ++k) {
    const std::string tag = std::to_string(k);
    local.push_back(seconds_of(campaign + " --jobs " + std::to_string(cpus) + " --dir " + dir + "/local" + tag +
                               " >/dev/null 2>&1"));
    one_wave.push_back(seconds_of(campaign + " --backend slurm --chunk " +
                                  std::to_string((5 * seeds + cpus - 1) / cpus) + " --dir " + dir + "/wave" + tag +
                                  " >/dev/null 2>&1"));
    chunks.push_back(
        seconds_of(campaign + " --backend slurm --chunk 25 --dir " + dir + "/chunks" + tag + " >/dev/null 2>&1"));
  }
  std::system(
      (std::string(RIG_SOURCE_DIR) + "/tests/cluster/slurm_cluster.sh stop " + cluster + " >/dev/null 2>&1").c_str());
  const double l = median(local), w = median(one_wave), c = median(chunks);
  std::printf("\n  a campaign of %d runs (5 sets x %d seeds), median of %d, command to merged result:\n", 5 * seeds,
              seeds, repeats);
  std::printf("    local, %d jobs:                          %7.2f s%s\n", cpus, std::abs(l), l < 0 ? " (failed)" : "");
  std::printf("    slurm, %d tasks of %d runs (one wave):   %7.2f s%s  overhead %+.1f %% (target <= 20 %%)\n", cpus,
              (5 * seeds + cpus - 1) / cpus, std::abs(w), w < 0 ? " (failed)" : "",
              100.0 * (std::abs(w) / std::abs(l) - 1));
  std::printf("    slurm, chunks of 25 runs (%2d tasks):     %7.2f s%s  overhead %+.1f %%\n", (5 * seeds + 24) / 25,
              std::abs(c), c < 0 ? " (failed)" : "", 100.0 * (std::abs(c) / std::abs(l) - 1));
  j["slurm"] = {{"runs", 5 * seeds},
                {"local_s", std::abs(l)},
                {"slurm_one_wave_s", std::abs(w)},
                {"slurm_chunks_of_25_s", std::abs(c)},
                {"overhead_one_wave", std::abs(w) / std::abs(l) - 1},
                {"overhead_chunks_of_25", std::abs(c) / std::abs(l) - 1},
                {"all_ok", l > 0 && w > 0 && c > 0}};
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  std::string scenario = std::string(RIG_SOURCE_DIR) + "/rig_configs/id_doublet_train_fast.yaml";
  double duration_s = 30.0;
  int campaign_runs = 200, repeats = 3;
  bool slurm = false;
  std::string json_file;
  cmdline::CommandLine cl("bench_campaign",
                          "What one run of a campaign costs by clock, the sweep's scaling against the "
                          "machine's own, and Slurm's overhead over local (--slurm).");
  cl->footer("Not a test: the figures depend on the machine; the ratios travel.");
  cl->add_option("scenario", scenario, "the scenario (default rig_configs/id_doublet_train_fast.yaml)");
  cl->add_option("--duration", duration_s, "simulated seconds of each run")
      ->check(cmdline::kFinite & CLI::Range(1.0, 3600.0))
      ->capture_default_str();
  cl->add_option("--campaign-runs", campaign_runs, "runs of the Slurm comparison (a multiple of 5)")
      ->check(CLI::Range(5, 100000))
      ->capture_default_str();
  cl->add_option("--repeats", repeats, "times each campaign is flown (median)")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  cl->add_flag("--slurm", slurm, "bring up a one-node Slurm cluster (root) and compare the backends");
  cl->add_option("--json", json_file, "the figures as JSON to FILE")->type_name("FILE");
  if (const auto done = cl.parse(argc, argv)) return *done;

  const std::string rig = (fs::path(argv[0]).parent_path() / "rig").string();
  const std::string dir = (fs::temp_directory_path() / ("bench_campaign_" + std::to_string(::getpid()))).string();
  fs::remove_all(dir);
  fs::create_directories(dir);
  const int cpus = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  nlohmann::json j{{"scenario", scenario}, {"duration_s", duration_s}, {"cpus", cpus}};
  std::printf("bench_campaign: %s, %.0f s simulated per run, %d CPUs\n", fs::path(scenario).filename().c_str(),
              duration_s, cpus);

  per_run_figures(rig, scenario, duration_s, dir, j);
  scaling_figures(rig, scenario, cpus, repeats, j);
  if (slurm && !slurm_figures(rig, scenario, dir, cpus, campaign_runs, repeats, j)) return 1;
  if (!json_file.empty()) cmdline::write_json(json_file, j.dump(2));
  fs::remove_all(dir);
  return 0;
}
