/// `rig`: the rig's command-line tool. Dispatches to one sub-command.

#include <csignal>
#include <cstdio>
#include <exception>
#include <iostream>
#include <string>
#include <vector>

#include "cli/commands.h"

namespace {

struct Command {
  const char* name;
  const char* synopsis;
  int (*run)(const std::vector<std::string>&);
};

const Command kCommands[] = {
    {"model", "model <model.yaml> [--vehicle <vehicle.yaml>] [--json]   A, B, eigenvalues, modes, eigenvectors",
     nimble::cli::run_model_command},
    {"run",
     "run <scenario.yaml> [--clock realtime|lockstep|inprocess] [--log F] [--mcap F] [--json F|-] [--set k=v] "
     "[--vibration] [--seed N] [--foxglove [HOST:]PORT]   fly a scenario",
     nimble::cli::run_run_command},
    {"view",
     "view [LOG] [--foxglove [HOST:]PORT] [--speed X] [--web [HOST:]PORT] [--hold|--loop|--exit-when-done]   replay a "
     "log live to Foxglove/Lichtblick",
     nimble::cli::run_view_command},
    {"sweep",
     "sweep <scenario.yaml> --seeds A-B [--vary k=v1,v2]... [--jobs N] [--json F|-] [--csv F]   Monte Carlo campaign",
     nimble::cli::run_sweep_command},
    {"params", "params [SECTION]                                   parameters: default, range, unit, meaning",
     nimble::cli::run_params_command},
    {"check", "check [--json F|-]                                 can this host run LCM multicast?",
     nimble::cli::run_check_command},
    {"spy", "spy [--pid PID] [--url URL]                        lcm-spy with the rig's message types",
     nimble::cli::run_spy_command},
    {"identify",
     "identify <data.csv|log.lcmlog> [--structure lateral3|lateral4] [--method ols|wls] [--states "
     "auto|estimate|truth|smoothed|sensors] [--json F] [--model-out F] [--plots DIR] ...   identify the lateral model",
     nimble::cli::run_identify_command},
    {"validate",
     "validate <model.yaml> <data.csv|log.lcmlog> [--json F] [--plots DIR] ...   open-loop validation of a model on "
     "flight data",
     nimble::cli::run_validate_command},
    {"discrepancy",
     "discrepancy <data> --model <model.yaml> [--json F] [--model-out F] ...   name the effect the model misses",
     nimble::cli::run_discrepancy_command},
    {"export",
     "export <log.lcmlog> (--csv <out.csv> [--rate HZ] [--interpolation cubic|linear] [--states "
     "auto|estimate|truth|smoothed|sensors] | --format mcap --out <out.mcap> [--compression zstd|none] [--raw]) "
     "[--salvage] [--json F|-]   a rig log as identification CSV, or as MCAP for Foxglove, Lichtblick, PlotJuggler",
     nimble::cli::run_export_command},
    {"turbulence",
     "turbulence <practical.yaml> [--json F|-] [--plots DIR] [--duration S] [--dt S] [--seed N]   the Ce500 turbulence "
     "practical",
     nimble::cli::run_turbulence_command},
    {"turbulence-response",
     "turbulence-response <scenario.yaml> <log.lcmlog> [--set k=v] [--f-max HZ] [--json F|-] [--plots DIR]   a flight "
     "in Dryden gusts against the closed-loop model",
     nimble::cli::run_turbulence_response_command},
    {"loop",
     "loop <scenario.yaml> [--all-sets] [--gains NAME|KP,KD] [--break actuator|sensor] [--design ...] [--json F|-] "
     "[--plots DIR]   the roll loop's margins, poles, bandwidth; PD design",
     nimble::cli::run_loop_command},
    {"reproduce",
     "reproduce thesis [--seeds LIST] [--states smoothed|estimate|truth] [--clock C] [--set k=v] [--vibration] "
     "[--beside] [--json F|-] [--report DIR]   the thesis's campaign beside its published tables",
     nimble::cli::run_reproduce_command},
};

void print_usage(std::ostream& out) {
  out << "usage: rig <command> [args]   (rig --version: the version)\n\ncommands:\n";
  for (const auto& c : kCommands) out << "  " << c.synopsis << "\n";
  out << "\n'rig <command> --help' describes one command.\n";
}

}  // namespace

int main(int argc, char** argv) {
  // A file over the size limit (RLIMIT_FSIZE) is a write that fails with EFBIG, named by the
  // writer, not a signal that kills the rig with its outputs half written.
  std::signal(SIGXFSZ, SIG_IGN);
  if (argc < 2) {
    print_usage(std::cerr);
    return nimble::cmdline::kExitUsage;
  }
  const std::string name = argv[1];
  if (name == "help" || name == "--help" || name == "-h") {
    print_usage(std::cout);
    return 0;
  }
  if (name == "--version" || name == "version") {
    std::cout << "rig " << NIMBLE_RIG_VERSION << " (Delfly Nimble lateral-dynamics rig)\n";
    return 0;
  }
  const std::vector<std::string> args(argv + 2, argv + argc);
  for (const auto& c : kCommands) {
    if (name == c.name) {
      try {
        return c.run(args);
      } catch (const std::exception& e) {
        std::cerr << "rig " << name << ": error: " << e.what() << "\n";
        return nimble::cmdline::kExitUsage;
      }
    }
  }
  std::cerr << "rig: unknown command '" << name << "'\n";
  print_usage(std::cerr);
  return nimble::cmdline::kExitUsage;
}
