#pragma once
/// Sub-commands of the `rig` command-line tool. Each takes the arguments after
/// its name and returns the process exit code: 0 success, 1 the command ran but
/// its check failed, 2 bad usage or bad input (message on stderr).

#include <string>
#include <vector>

#include "cmdline/args.h"  // kExitUsage

namespace nimble::cli {

/// `rig model <model.yaml> [--vehicle <vehicle.yaml>] [--json]`
int run_model_command(const std::vector<std::string>& args);

/// `rig run <scenario.yaml> [--clock realtime|lockstep|inprocess] [--log F] [--json F] [--set k=v] [--seed N]`
int run_run_command(const std::vector<std::string>& args);

/// `rig view [LOG] [--foxglove [HOST:]PORT] [--speed X] [--web [HOST:]PORT] [--web-root DIR] [--exit-when-done]
/// [--salvage]`: a log replayed live on a Foxglove WebSocket server, and the dashboard page (cli/view_command.cc).
int run_view_command(const std::vector<std::string>& args);

/// `rig sweep <scenario.yaml> --seeds A-B [--vary k=v1,v2]... [--jobs N] [--json F] [--csv F]`: a
/// Monte Carlo campaign (launcher/sweep.h).
int run_sweep_command(const std::vector<std::string>& args);

/// `rig params [SECTION]`: parameter tables (key, default, range, unit, meaning).
int run_params_command(const std::vector<std::string>& args);

/// `rig check`: can this host run LCM multicast (directly or in a private namespace)?
int run_check_command(const std::vector<std::string>& args);

/// `rig spy [--pid PID] [--url URL]`: lcm-spy with the rig's types.
int run_spy_command(const std::vector<std::string>& args);

/// `rig identify <data.csv> [--structure lateral3|lateral4] [--method ols|wls] [--vehicle F] [--w0 M_PER_S]
/// [--rate HZ] [--cutoff HZ] [--order N] [--json F] [--model-out F] [--plots DIR] ...`: identification
/// of the lateral model from CSV flight data (cli/identify_command.cc).
int run_identify_command(const std::vector<std::string>& args);

/// `rig discrepancy <data> --model <model.yaml> [--json F] [--model-out F] [--candidates LIST] ...`: the
/// discrepancy workflow (ident/discrepancy.h).
int run_discrepancy_command(const std::vector<std::string>& args);
/// `rig discrepancy --power --scenario S --model M --effect NAME=SIZE[,...] [--lengths S,...] [--flights N]
/// [--verify N] [--json F|-] [--plots DIR] ...`: how long to fly to name an effect (cli/power_command.cc,
/// power/power_campaign.h). run_discrepancy_command hands every command line with --power to it.
int run_discrepancy_power_command(const std::vector<std::string>& args);
/// `rig validate <model.yaml> <data.csv> [--json F] [--plots DIR] ...`: open-loop validation.
int run_validate_command(const std::vector<std::string>& args);

/// `rig export <log.lcmlog> --csv <out.csv> [--rate HZ] [--states auto|estimate|truth]`
int run_export_command(const std::vector<std::string>& args);

/// `rig turbulence <practical.yaml> [--json F|-] [--plots DIR] [--duration S] [--dt S] [--seed N]`: the
/// Ce500 practical, aircraft responses to atmospheric turbulence (cli/turbulence_command.cc).
int run_turbulence_command(const std::vector<std::string>& args);

/// `rig turbulence-response <scenario.yaml> <log.lcmlog> [--set k=v] [--skip S] [--f-max HZ] [--json F|-]
/// [--plots DIR]`: a rig flight in Dryden side gusts against the closed-loop linear model's PSDs and
/// variances (cli/turbulence_response_command.cc, turbulence/hover_gust_response.h).
int run_turbulence_response_command(const std::vector<std::string>& args);

/// `rig reproduce thesis [--clock C] [--seed N] [--json F|-] [--report DIR]`: the thesis's campaign and
/// its tables (reproduce/campaign.h).
int run_reproduce_command(const std::vector<std::string>& args);

/// `rig loop <scenario.yaml> [--model F] [--gains NAME|KP,KD] [--all-sets] [--break actuator|sensor]
/// [--design phase_margin_deg=P,crossover_hz=F] [--gains-out F] [--fly] [--json F|-] [--plots DIR]`: the roll
/// loop's margins, poles and bandwidth, and a PD design (cli/loop_command.cc).
int run_loop_command(const std::vector<std::string>& args);

}  // namespace nimble::cli
