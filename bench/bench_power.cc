/// bench_power: the time of `rig discrepancy --power` for one effect size and one record length.
///
///   bench_power [--scenario F] [--model F] [--effect NAME=SIZE] [--length S] [--flights N] [--jobs N]
///
/// Flies N flights (default 200) of the scenario (default rig_configs/cl_doublet_train_slow.yaml,
/// 9 s, every process: plant, controller, mocap, estimator) with the effect at one size (default
/// actuator_delay=0.004) for one length (default the scenario's own), the workflow on each
/// (model set 1 with the exact kinematics), as the command does, and prints:
///  - the wall time (the target: <= 30 s for 200 flights on this 2-core machine);
///  - per flight, where the time goes: flying (wall and CPU, of which building the processes)
///    and the workflow (wall and CPU); CPU time is what a flight costs a core whatever else runs;
///  - what the wall time would be on `jobs` idle cores (flights x CPU per flight / jobs), and the
///    load average before and after, since other work on the machine stretches the wall time;
///  - the naming probability of the cell, so that the figure says what was measured.
/// Not a test: figures depend on the machine.

#include <cstdio>
#include <fstream>
#include <string>
#include <thread>

#include "cmdline/args.h"
#include "launcher/run_plan.h"
#include "detection_power/effect_size.h"
#include "detection_power/power_campaign.h"

namespace {

std::string load_average() {
  std::ifstream in("/proc/loadavg");
  std::string one, five, fifteen;
  in >> one >> five >> fifteen;
  return one + " " + five + " " + fifteen;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace nimble;
  const std::string configs = std::string(RIG_SOURCE_DIR) + "/rig_configs/";
  detection_power::PowerOptions o;
  o.scenario_file = configs + "cl_doublet_train_slow.yaml";
  o.model_file = configs + "models/nimble_lateral_set1_kinematic.yaml";
  o.flights = 200;
  o.refine = 0;
  o.jobs = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  std::string effect = "actuator_delay=0.004";
  double length_s = 0.0;
  cmdline::CommandLine cl("bench_power",
                          "The time of rig discrepancy --power for one effect size and one record length: N flights\n"
                          "of the in-process rig, the discrepancy workflow on each; wall time and where it goes.");
  cl->add_option("--scenario", o.scenario_file, "the scenario")->capture_default_str()->type_name("FILE");
  cl->add_option("--model", o.model_file, "the model the workflow checks")->capture_default_str()->type_name("FILE");
  cl->add_option("--effect", effect, "the effect and its one size")->capture_default_str()->type_name("NAME=SIZE");
  cl->add_option("--length", length_s, "record length [s] (default: the scenario's)")
      ->check(cmdline::kFinite & CLI::PositiveNumber)
      ->type_name("S");
  cl->add_option("--flights", o.flights, "flights")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str()
      ->type_name("N");
  cl->add_option("--jobs", o.jobs, "flights at a time (default: one per CPU)")
      ->check(CLI::Range(1, 256))
      ->type_name("N");
  if (const auto done = cl.parse(argc, argv)) return *done;
  try {
    const detection_power::EffectSizes e = detection_power::parse_effect_sizes(effect);
    if (e.sizes.size() != 1) return cl.fail("--effect: one size");
    o.effect = e.effect;
    o.sizes = e.sizes;
    if (length_s > 0.0) o.lengths_s = {length_s};
    o.progress = false;
    const std::string load_before = load_average();
    if (o.lengths_s.empty()) {  // the scenario's own length: one grid length, no longer records
      launcher::RunOptions ro;
      ro.scenario_file = o.scenario_file;
      o.lengths_s = {launcher::load_run_plan(ro).scenario.duration_s};
    }
    const detection_power::PowerResult r = detection_power::run_power(o);
    const detection_power::PowerCell& c = r.cells.front();
    const double n = static_cast<double>(c.flights.size());
    std::printf("bench_power: %s, %s = %g %s, %.4g s records, %zu flights, %d jobs\n", r.scenario.c_str(),
                r.parameter.c_str(), c.size, r.unit.c_str(), c.length_s, c.flights.size(), r.jobs);
    std::printf("  wall             %7.2f s   (target <= 30 s for 200 flights; plans %.3f s before)\n", r.wall_s,
                r.setup_s);
    std::printf("  per flight       flying %.3f s wall, %.3f s CPU (building the processes %.3f s wall)\n",
                c.flight_s / n, c.flight_cpu_s / n, c.build_s / n);
    std::printf("                   workflow %.3f s wall, %.3f s CPU\n", c.workflow_s / n, c.workflow_cpu_s / n);
    std::printf("  on %d idle cores %7.2f s   (flights x CPU per flight / jobs)\n", r.jobs,
                (c.flight_cpu_s + c.workflow_cpu_s) / r.jobs);
    std::printf("  load average     %s before, %s after\n", load_before.c_str(), load_average().c_str());
    std::printf("  named            %d/%d (%.1f %% [%.1f, %.1f]), another name %.1f %%, any alarm %.1f %%\n",
                c.named.count, c.named.n, 100 * c.named.p, 100 * c.named.lo, 100 * c.named.hi, 100 * c.other.p,
                100 * c.alarm.p);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_power: %s\n", e.what());
    return cmdline::kExitUsage;
  }
  return 0;
}
