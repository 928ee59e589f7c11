/// `rig sweep`: a Monte Carlo campaign over a scenario (launcher/sweep.h).

#include <fstream>
#include <iostream>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "cmdline/args.h"
#include "cli/commands.h"
#include "launcher/sweep.h"

namespace nimble::cli {
namespace {

constexpr const char* kSweepDescription =
    "Flies the scenario once per seed A..B and per combination of the --vary values (each --vary\n"
    "multiplies the parameter sets), N runs at a time, each in its own child process, in process\n"
    "unless --clock says otherwise. Prints per parameter set the controlled rate and percentiles\n"
    "across runs of the extremes, state ranges and estimator errors, and each run that was not ok.";

constexpr const char* kSweepFooter =
    "Exit code: 0 every run ok, 1 some run not ok, 2 bad input.\n"
    "Example: rig sweep rig_configs/id_doublet_train_fast.yaml --seeds 1-20 \\\n"
    "           --vary model=rig_configs/models/nimble_lateral_set1.yaml,rig_configs/models/nimble_lateral_set2.yaml";

}  // namespace

int run_sweep_command(const std::vector<std::string>& args) {
  launcher::SweepOptions o;
  o.jobs = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  std::string json_file, csv_file;
  CommandLine cl("rig sweep", kSweepDescription);
  cl->footer(kSweepFooter);
  cl->add_option("scenario", o.base.scenario_file, "the scenario file")->required();
  each_value(cl->add_option("--seeds", "the seeds A-B, each flown once per parameter set")->type_name("A-B")->required(),
             [&o](const std::string& v) { std::tie(o.first_seed, o.last_seed) = launcher::parse_seed_range(v); });
  each_value(cl->add_option("--vary", "a parameter and its values (repeatable; the sets are every combination)")
                 ->type_name("KEY=V1,V2,...")
                 ->allow_extra_args(false)
                 ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll),
             [&o](const std::string& v) { o.vary.push_back(launcher::parse_vary(v)); });
  cl->add_option("--jobs", o.jobs, "runs at a time (default: one per CPU)")->check(CLI::Range(1, 256))->type_name("N");
  cl.add_json(json_file, "the sets and a 'runs' list (seed, verdict, figures)");
  cl->add_option("--csv", csv_file, "one row per run")->type_name("FILE");
  cl->add_option("--clock", o.base.clock, "inprocess (default), lockstep or realtime")
      ->check(CLI::IsMember({std::string(launcher::kClockInprocess), std::string(launcher::kClockLockstep),
                              std::string(launcher::kClockRealtime)}));
  each_value(cl->add_option("--set", "override one scenario value in every run, parsed as YAML (repeatable)")
                 ->type_name("KEY.PATH=VALUE")
                 ->allow_extra_args(false)
                 ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll),
             [&o](const std::string& v) { o.base.overrides.push_back(parse_override(v)); });
  cl->add_option("--logs", o.logs_dir, "keep each run's LCM log in DIR")->type_name("DIR");
  cl->add_flag("--no-progress", "no progress line on stderr")->each([&o](const std::string&) { o.progress = false; });
  if (const auto done = cl.parse(args)) return *done;
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
