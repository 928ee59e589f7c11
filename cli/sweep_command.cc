/// `rig sweep`: a Monte Carlo campaign over a scenario (launcher/sweep.h).

#include <fstream>
#include <iostream>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "cli/args.h"
#include "cli/commands.h"
#include "launcher/sweep.h"

namespace nimble::cli {
namespace {

constexpr const char* kSweepUsage =
    "usage: rig sweep <scenario.yaml> --seeds A-B [--vary key=v1,v2,...]... [--jobs N] [--json FILE|-]\n"
    "                 [--csv FILE] [--clock inprocess|lockstep|realtime] [--set key.path=value]...\n"
    "                 [--logs DIR] [--no-progress]\n"
    "  Flies the scenario once per seed A..B and per combination of the --vary values (each\n"
    "  --vary multiplies the parameter sets), N runs at a time (default: one per CPU), each in\n"
    "  its own child process, in process unless --clock says otherwise. Prints per parameter\n"
    "  set the controlled rate and percentiles across runs of the extremes, state ranges and\n"
    "  estimator errors, and each run that was not ok. --json writes the sets and a 'runs' list\n"
    "  (seed, verdict, figures; '-': to stdout, the text then to stderr), --csv one row per run,\n"
    "  --logs DIR keeps each run's LCM log.\n"
    "  Exit code: 0 every run ok, 1 some run not ok, 2 bad input.\n"
    "  Example: rig sweep rig_configs/id_doublet_train_fast.yaml --seeds 1-20 \\\n"
    "             --vary model=rig_configs/models/nimble_lateral_set1.yaml,rig_configs/models/nimble_lateral_set2.yaml\n";

}  // namespace

int run_sweep_command(const std::vector<std::string>& args) {
  launcher::SweepOptions o;
  o.jobs = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  std::string json_file, csv_file;
  bool have_seeds = false;
  if (wants_help(args)) {
    std::cout << kSweepUsage;
    return 0;
  }
  try {
    for (Args arg(args); arg.next();) {
      const std::string& a = arg.arg();
      if (a == "--seeds") {
        std::tie(o.first_seed, o.last_seed) = launcher::parse_seed_range(arg.value());
        have_seeds = true;
      } else if (a == "--vary") {
        o.vary.push_back(launcher::parse_vary(arg.value()));
      } else if (a == "--jobs") {
        o.jobs = integer("--jobs", arg.value(), 1, 256);
      } else if (a == "--json") {
        json_file = arg.value();
      } else if (a == "--csv") {
        csv_file = arg.value();
      } else if (a == "--clock") {
        o.base.clock = arg.value();
      } else if (a == "--set") {
        o.base.overrides.push_back(parse_override(arg.value()));
      } else if (a == "--logs") {
        o.logs_dir = arg.value();
      } else if (a == "--no-progress") {
        o.progress = false;
      } else if (!a.empty() && a[0] == '-') {
        throw UsageError("unknown option '" + a + "'");
      } else if (o.base.scenario_file.empty()) {
        o.base.scenario_file = a;
      } else {
        throw UsageError("unexpected argument '" + a + "'");
      }
    }
  } catch (const UsageError& e) {
    std::cerr << "rig sweep: " << e.what() << "\n" << kSweepUsage;
    return kExitUsage;
  } catch (const std::invalid_argument& e) {  // a malformed --seeds or --vary
    std::cerr << "rig sweep: " << e.what() << "\n" << kSweepUsage;
    return kExitUsage;
  }
  if (o.base.scenario_file.empty() || !have_seeds) {
    std::cerr << "rig sweep: " << (o.base.scenario_file.empty() ? "missing <scenario.yaml>" : "missing --seeds A-B")
              << "\n" << kSweepUsage;
    return kExitUsage;
  }
  launcher::SweepResult result;
  try {
    result = launcher::run_sweep(o);
  } catch (const ConfigError& e) {
    std::cerr << "rig sweep: config error: " << e.what() << "\n";
    return kExitUsage;
  } catch (const std::exception& e) {
    std::cerr << "rig sweep: " << e.what() << "\n";
    return kExitUsage;
  }
  // --json -: stdout carries the JSON alone, the text goes to stderr.
  launcher::write_sweep_text(json_file == "-" ? std::cerr : std::cout, result);
  const auto write = [](const std::string& file, const std::string& text) {
    if (file.empty()) return true;
    if (file == "-") {
      std::cout << text;
      return true;
    }
    std::ofstream out(file);
    out << text;
    if (!out) std::cerr << "rig sweep: cannot write " << file << "\n";
    return static_cast<bool>(out);
  };
  bool written = write(json_file, launcher::sweep_json(result) + "\n");
  written = write(csv_file, launcher::sweep_csv(result)) && written;
  if (!written) return kExitUsage;
  for (const auto& run : result.runs) {
    if (run.exit_code != launcher::kRunOk) return 1;
  }
  return 0;
}

}  // namespace nimble::cli
