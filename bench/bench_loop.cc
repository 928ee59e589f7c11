/// bench_loop: time of `rig loop --all-sets` (model sets 1-5 x both gain sets, the robustness
/// lines over the sets and the 64 corners and 12 faces of a +-2 sigma box, per gain set) as a
/// user runs it, a whole process, median over repetitions; and in this process, the analysis
/// of one loop (margins, poles, bandwidth). As the machine's floor, measured in the same run:
/// one frequency response of the loop (its 600 points, the grid the margins search), and the
/// ratio of each figure to it.

#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "cmdline/args.h"
#include "controller/loop_margins.h"
#include "controller/roll_loop.h"
#include "core/bench_timing.h"
#include "core/json_line.h"
#include "core/model.h"
#include "core/vehicle.h"
#include "core/constants.h"

namespace {

namespace fs = std::filesystem;
using namespace nimble;

/// The loop of hover: set 1, fast gains, on the estimate (latency 2 control periods).
struct Loop {
  StateSpace lateral;
  RollLoopConfig config;
};

Loop hover_loop() {
  const DerivativeModel m = load_model(std::string(RIG_SOURCE_DIR) + "/rig_configs/models/nimble_lateral_set1.yaml");
  const ControllerConfig c =
      load_controller_config(std::string(RIG_SOURCE_DIR) + "/rig_configs/controller/nimble_attitude.yaml");
  Loop l{build_state_space(m, load_vehicle(m.vehicle_file)), roll_loop_config(c, roll_gain_set(c, "fast"))};
  l.config.latency_s = 2.0 / c.rate_hz;
  return l;
}

/// CPU ms of one frequency response: the loop assembled, reduced, and evaluated at 600 points.
double frequency_response_ms(const Loop& l, double& checksum) {
  const double t0 = thread_cpu_ms();
  const LoopResponse r(roll_broken_loop(l.lateral, l.config, LoopBreak::kActuator));
  const double w_min = 2 * kPi * 0.01, w_max = r.nyquist_radps();
  for (int i = 0; i < 600; ++i) checksum += std::abs(r.ratio(w_min * std::pow(w_max / w_min, i / 599.0)));
  return thread_cpu_ms() - t0;
}

double analysis_ms(const Loop& l, double& checksum) {
  const double t0 = thread_cpu_ms();
  const RollLoopAnalysis a = analyse_roll_loop(l.lateral, l.config);
  checksum += a.margins.phase_margin_deg;
  return thread_cpu_ms() - t0;
}

/// Wall ms of `cmd`; negative if it failed.
double command_ms(const std::string& cmd) {
  const auto t0 = std::chrono::steady_clock::now();
  const int status = std::system(cmd.c_str());
  const double ms = elapsed_ms(t0, std::chrono::steady_clock::now());
  return WIFEXITED(status) && WEXITSTATUS(status) == 0 ? ms : -ms;
}

}  // namespace

int main(int argc, char** argv) {
  int reps = 15;
  std::string json;
  std::string scenario = std::string(RIG_SOURCE_DIR) + "/rig_configs/hover.yaml";
  cmdline::CommandLine cl("bench_loop",
                          "Times rig loop --all-sets (a whole process) and one loop's analysis against the machine's\n"
                          "floor measured in the same run: one frequency response of the roll loop (600 points).");
  cl->footer(
      "Not a test: the figures depend on the machine; the ratios to the floor travel. Target: rig loop "
      "--all-sets <= 100 ms.");
  cl->add_option("scenario", scenario, "the scenario (default rig_configs/hover.yaml)")->type_name("SCENARIO.YAML");
  cl->add_option("--runs", reps, "repetitions of each figure (the median is reported)")
      ->check(CLI::Range(3, 10000))
      ->capture_default_str();
  cl.add_json(json, "the figures");
  if (const auto done = cl.parse(argc, argv)) return *done;

  const Loop l = hover_loop();
  double checksum = 0.0;
  std::vector<double> floor_ms, one_ms, all_ms;
  for (int i = 0; i < 10 * reps; ++i) floor_ms.push_back(frequency_response_ms(l, checksum));
  for (int i = 0; i < reps; ++i) one_ms.push_back(analysis_ms(l, checksum));
  const std::string rig = (fs::path(argv[0]).parent_path() / "rig").string();
  const std::string out = (fs::temp_directory_path() / ("bench_loop_" + std::to_string(::getpid()) + ".json")).string();
  const std::string cmd = "'" + rig + "' loop '" + scenario + "' --all-sets --json '" + out + "' > /dev/null 2>&1";
  for (int i = 0; i < reps; ++i) {
    const double ms = command_ms(cmd);
    if (ms < 0.0) {
      std::fprintf(stderr, "bench_loop: '%s' failed\n", cmd.c_str());
      return 1;
    }
    all_ms.push_back(ms);
  }
  fs::remove(out);
  const double floor = median(floor_ms), one = median(one_ms), all = median(all_ms);
  const double version_ms = command_ms("'" + rig + "' --version > /dev/null");
  if (json != "-") {
    std::printf("bench_loop (%d repetitions, medians; checksum %.6g)\n", reps, checksum);
    std::printf("  floor: one frequency response of the roll loop, 600 points   %8.3f ms CPU\n", floor);
    std::printf("  one loop analysed (margins, poles, bandwidth)               %8.3f ms CPU   %6.1f x floor\n", one,
                one / floor);
    std::printf(
        "  rig loop --all-sets, whole process                          %8.3f ms wall  %6.1f x floor"
        "   (target <= 100 ms)\n",
        all, all / floor);
    std::printf("  (a bare 'rig --version' process: %.1f ms wall)\n", version_ms);
  }
  if (!json.empty()) {
    OrderedJson j;
    j["floor"] = {{"frequency_response_ms", floor}};
    j["one_loop_ms"] = one;
    j["one_loop_per_floor"] = one / floor;
    j["all_sets_ms"] = all;
    j["all_sets_per_floor"] = all / floor;
    j["process_start_ms"] = version_ms;
    j["target_ms"] = 100.0;
    cmdline::write_json(json, json_line(j));
  }
  return 0;
}
