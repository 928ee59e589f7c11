/// bench_inprocess: speed of the in-process executor and of `rig sweep`.
///
///   bench_inprocess [scenario.yaml] [--runs N] [--duration S] [--json F] [--flights-only]
///
/// Prints, for the scenario (default rig_configs/id_doublet_train_fast.yaml, every process:
/// plant, controller, mocap, estimator), flown for S simulated seconds (default 30):
///  - the in-process speed in multiples of real time, median and best of N runs (default 5),
///    with the LCM log written (the target: >= 300x), the same with the real vehicle's flight
///    vibration and its on-board IMU filtering (rig_configs/sensing/nimble_flight_vibration.yaml;
///    the target: within 5 % of the default), without a log, and without the estimator and
///    motion capture (flying on truth), and without the estimator alone (the motion capture
///    flying, the controller on truth): the estimator's path per simulated second;
///  - the machine's floor in the same run: the plant model stepped alone at its rate, nothing
///    else (no sensors, no controller, no messages), as a speed and as the ratio rig / floor;
///  - the time of `rig sweep` over the five published parameter sets x 20 seeds, with one job
///    and with one job per CPU, as runs per second;
///  - the time of `rig reproduce thesis` (12 flights, identification, validation, every table;
///    the target: <= 60 s), and its simulated seconds per wall second against the floor.
/// With --json F the figures go to F under fixed keys:
///   {"inprocess": {"speed_x": x}, "floor": {"speed_x": x},
///    "sweep": {"runs_per_s_1job": x, "runs_per_s_all": x, "jobs_all": n}, ...}
/// Not a test: figures depend on the machine; the ratio to the floor is what travels.

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <thread>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

#include "cmdline/args.h"
#include "launcher/inprocess.h"
#include "launcher/run_plan.h"
#include "plant/plant_node.h"

namespace fs = std::filesystem;
using namespace nimble;

namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : (v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]));
}

struct Speeds {
  double median_x = 0.0, best_x = 0.0;
  std::string verdict;
};

Speeds fly(const launcher::RunOptions& base, const std::vector<Override>& extra, const std::string& log, int runs) {
  launcher::RunOptions o = base;
  o.overrides.insert(o.overrides.end(), extra.begin(), extra.end());
  const launcher::RunPlan plan = launcher::load_run_plan(o);
  std::vector<double> x;
  Speeds s;
  for (int i = 0; i < runs; ++i) {
    launcher::InprocessOptions io;
    io.log_file = log;
    const launcher::RunReport r = launcher::fly_inprocess(plan, io);
    x.push_back(r.speed_x_realtime());
    s.verdict = r.verdict.text;
  }
  s.median_x = median(x);
  s.best_x = *std::max_element(x.begin(), x.end());
  return s;
}

/// The plant model alone, stepped at its rate for `duration_s` with the trim command.
double plant_floor_x(const launcher::RunPlan& plan, double duration_s, int runs) {
  const Scenario& s = plan.scenario;
  ConfigMap section = s.section("plant");
  const plant::PlantConfig config = plant::plant_config_from(section);
  std::vector<double> x;
  for (int i = 0; i < runs; ++i) {
    const std::unique_ptr<plant::PlantModel> model = plant::plant_model_for(s, config);
    const effects::ActuatorInput trim = model->trim_command();
    const long steps = static_cast<long>(duration_s * config.rate_hz);
    const auto t0 = std::chrono::steady_clock::now();
    for (long k = 0; k < steps; ++k) {
      effects::ActuatorInput u = trim;  // a +-2.5 rad/s square wave of delta_f, so the state moves
      const double half_df = (k / 100) % 2 ? 1.25 : -1.25;
      u.flap_freq_left_radps += half_df;
      u.flap_freq_right_radps -= half_df;
      model->step(u);
    }
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    x.push_back(duration_s / wall);
  }
  return median(x);
}

/// Wall seconds of `cmd` through the shell; negative if it failed.
double command_seconds(const std::string& cmd) {
  const auto t0 = std::chrono::steady_clock::now();
  const int status = std::system(cmd.c_str());
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return WIFEXITED(status) && WEXITSTATUS(status) == 0 ? s : -s;
}

/// Runs of the sweep below.
constexpr int kSweepRuns = 100;

double sweep_seconds(const std::string& rig, const std::string& scenario, int jobs) {
  std::string vary = "model=";
  for (int k = 1; k <= 5; ++k) {
    vary += std::string(k > 1 ? "," : "") + RIG_SOURCE_DIR + "/rig_configs/models/nimble_lateral_set" +
            std::to_string(k) + ".yaml";
  }
  return command_seconds(rig + " sweep " + scenario + " --seeds 1-20 --vary " + vary + " --jobs " +
                         std::to_string(jobs) + " --no-progress > /dev/null");
}

}  // namespace

int main(int argc, char** argv) {
  std::string scenario = std::string(RIG_SOURCE_DIR) + "/rig_configs/id_doublet_train_fast.yaml";
  int runs = 5;
  double duration_s = 30.0;
  std::string json_file;
  cmdline::CommandLine cl("bench_inprocess",
                          "Times the in-process executor on a flight against the machine's floor (the plant model\n"
                          "alone) measured in the same run, and rig sweep.");
  cl->footer("Not a test: the figures depend on the machine; the ratio to the floor travels.");
  cl->add_option("scenario", scenario, "the scenario (default rig_configs/id_doublet_train_fast.yaml)")
      ->type_name("SCENARIO.YAML");
  cl->add_option("--runs", runs, "runs of each figure (median and best are reported)")
      ->check(CLI::Range(1, 1000))
      ->type_name("N")
      ->capture_default_str();
  cl->add_option("--duration", duration_s, "simulated seconds of each flight")
      ->check(cmdline::kFinite & CLI::Range(0.001, 1e6))
      ->type_name("S")
      ->capture_default_str();
  cl->add_option("--json", json_file, "the figures as JSON to FILE, under fixed keys")->type_name("FILE");
  bool flights_only = false;
  cl->add_flag("--flights-only", flights_only, "the flights and the floor only: no rig sweep, no rig reproduce thesis");
  if (const auto done = cl.parse(argc, argv)) return *done;
  const std::string dir = (fs::temp_directory_path() / ("bench_inprocess_" + std::to_string(::getpid()))).string();
  fs::create_directories(dir);
  try {
    launcher::RunOptions base;
    base.scenario_file = scenario;
    base.clock = launcher::kClockInprocess;
    base.overrides.push_back({"duration_s", std::to_string(duration_s)});
    const launcher::RunPlan plan = launcher::load_run_plan(base);
    std::printf("bench_inprocess: %s, %.0f s simulated, %d runs each, %u CPUs\n", plan.scenario.name.c_str(),
                duration_s, runs, std::max(1u, std::thread::hardware_concurrency()));
    const Speeds full = fly(base, {}, dir + "/bench.lcmlog", runs);
    const double log_mb = static_cast<double>(fs::file_size(dir + "/bench.lcmlog")) / 1e6;
    // The real vehicle's flight vibration with its on-board filtering (the target: within 5 % of
    // the default's speed).
    const std::string vibration_file =
        std::string(RIG_SOURCE_DIR) + "/rig_configs/sensing/nimble_flight_vibration.yaml";
    const Speeds vibration = fly(base, {{"sensing.base", vibration_file}}, dir + "/bench_vibration.lcmlog", runs);
    const Speeds no_log = fly(base, {}, "", runs);
    const Speeds truth = fly(base, {{"run.controller_input", "truth"}, {"processes", "[plant,controller]"}}, "", runs);
    // Without the estimator (the motion capture still flies): what the estimator's path costs.
    const Speeds no_estimator =
        fly(base, {{"run.controller_input", "truth"}, {"processes", "[plant,controller,mocap]"}}, "", runs);
    const double estimator_path_us_per_s = 1e6 * (1.0 / no_log.median_x - 1.0 / no_estimator.median_x);
    const double floor_x = plant_floor_x(plan, duration_s, runs);
    std::printf("  %-58s median %7.1fx  best %7.1fx   (%s; log %.1f MB)\n",
                "in process, every process, log written (target >= 300x)", full.median_x, full.best_x,
                full.verdict.c_str(), log_mb);
    std::printf("  %-58s median %7.1fx  best %7.1fx   (%s; %.3f of the default, target >= 0.95)\n",
                "the same with the flight vibration and its IMU filtering", vibration.median_x, vibration.best_x,
                vibration.verdict.c_str(), vibration.median_x / full.median_x);
    std::printf("  %-58s median %7.1fx  best %7.1fx\n", "in process, every process, no log", no_log.median_x,
                no_log.best_x);
    std::printf("  %-58s median %7.1fx  best %7.1fx\n", "in process, plant and controller on truth, no log",
                truth.median_x, truth.best_x);
    std::printf("  %-58s median %7.1fx  best %7.1fx\n", "in process, no estimator (controller on truth), no log",
                no_estimator.median_x, no_estimator.best_x);
    std::printf("  %-58s %7.0f us per simulated s\n", "the estimator's path (every process minus no estimator)",
                estimator_path_us_per_s);
    std::printf("  %-58s median %7.1fx\n", "floor: the plant model alone at its rate", floor_x);
    std::printf("  ratio rig (every process, log) / floor: %.3f\n", full.median_x / floor_x);
    nlohmann::json j{
        {"scenario", plan.scenario.name},
        {"duration_s", duration_s},
        {"runs", runs},
        {"inprocess",
         {{"speed_x", full.median_x},
          {"best_x", full.best_x},
          {"no_log_speed_x", no_log.median_x},
          {"truth_only_speed_x", truth.median_x},
          {"no_estimator_speed_x", no_estimator.median_x},
          {"estimator_path_us_per_s", estimator_path_us_per_s},
          {"log_mb", log_mb}}},
        {"floor", {{"speed_x", floor_x}, {"what", "the plant model alone at its rate"}}},
        {"ratio_to_floor", full.median_x / floor_x},
        {"vibration", {{"speed_x", vibration.median_x}, {"ratio_to_default", vibration.median_x / full.median_x}}}};
    if (flights_only) {
      if (!json_file.empty()) cmdline::write_json(json_file, j.dump(2));
      fs::remove_all(dir);
      return 0;
    }
    const std::string rig = (fs::path(argv[0]).parent_path() / "rig").string();
    const int jobs_all = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    const double sweep_1_s = sweep_seconds(rig, scenario, 1);
    const double sweep_all_s = sweep_seconds(rig, scenario, jobs_all);
    const double runs_per_s_1 = kSweepRuns / std::abs(sweep_1_s);
    const double runs_per_s_all = kSweepRuns / std::abs(sweep_all_s);
    std::printf("  %-58s %7.2f s%s  %.1f runs/s\n", "rig sweep, 5 published sets x 20 seeds, 1 job",
                std::abs(sweep_1_s), sweep_1_s < 0 ? "  (some run not ok)" : "", runs_per_s_1);
    std::printf("  %-58s %7.2f s%s  %.1f runs/s (%.2fx one job; target >= 1.8x on 2 cores)\n",
                ("rig sweep, the same, " + std::to_string(jobs_all) + " jobs").c_str(), std::abs(sweep_all_s),
                sweep_all_s < 0 ? "  (some run not ok)" : "", runs_per_s_all, runs_per_s_all / runs_per_s_1);
    const double reproduce_s = command_seconds(rig + " reproduce thesis --no-progress --logs " + dir +
                                               "/reproduce --json " + dir + "/reproduce.json > /dev/null");
    double campaign_sim_s = 0.0;  // simulated seconds of every flight of the campaign
    for (const auto& f : YAML::LoadFile(dir + "/reproduce.json")["flights"]) campaign_sim_s += f["sim_s"].as<double>();
    std::printf("  %-58s %7.2f s%s (target <= 60 s; %.0fx real time, %.3f of the floor)\n",
                "rig reproduce thesis, in process", std::abs(reproduce_s), reproduce_s < 0 ? "  (a cell differs)" : "",
                campaign_sim_s / std::abs(reproduce_s), campaign_sim_s / std::abs(reproduce_s) / floor_x);
    if (!json_file.empty()) {
      j["sweep"] = {{"runs", kSweepRuns},
                    {"runs_per_s_1job", runs_per_s_1},
                    {"runs_per_s_all", runs_per_s_all},
                    {"jobs_all", jobs_all},
                    {"all_ok", sweep_1_s > 0 && sweep_all_s > 0}};
      j["reproduce"] = {{"seconds", std::abs(reproduce_s)}, {"all_cells_match", reproduce_s > 0}};
      cmdline::write_json(json_file, j.dump(2));
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_inprocess: %s\n", e.what());
    fs::remove_all(dir);
    return 2;
  }
  fs::remove_all(dir);
  return 0;
}
