/// `rig reproduce thesis`: the thesis's campaign flown, identified, validated and set beside the
/// published tables (reproduce/campaign.h).

#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "cmdline/args.h"
#include "cli/commands.h"
#include "core/config.h"
#include "core/output_file.h"
#include "launcher/launcher.h"
#include "launcher/run_plan.h"
#include "reproduce/campaign.h"

namespace nimble::cli {

int run_reproduce_command(const std::vector<std::string>& args) {
  namespace fs = std::filesystem;
  reproduce::CampaignOptions o;
  o.campaign_file = NIMBLE_DEFAULT_CAMPAIGN;
  o.controller_file = NIMBLE_DEFAULT_CONTROLLER;
  o.work_dir = "rig_logs/reproduce";
  o.progress = true;
  std::string what, json_file;
  CommandLine cl("rig reproduce",
                 "Flies the thesis's campaign (identification train on every identification set's model;\n"
                 "open-loop 6 Hz doublet and 1-1-2; closed-loop slow train and 1-1-2s; coupled doublet; 20 and\n"
                 "30 deg nonlinear doublets), identifies set 1's model from its identification flight as the\n"
                 "thesis did, validates it on the others, and prints every table it reproduces beside the\n"
                 "published one (Tables 9.4, 9.5, 9.6, 4, 7, 8, 9, 10, 11, 15, 16, 8.8), each cell with its\n"
                 "verdict: match (within the table's tolerance), explained (a reason in the campaign file) or\n"
                 "differs.");
  cl->footer("Exit code: 0 no cell differs, 1 some cell differs, 2 bad input or a flight that could not fly.\n"
             "Example: rig reproduce thesis --json tables.json --report report/");
  cl->add_option("what", what, "the campaign to reproduce")->required()->check(CLI::IsMember({"thesis"}));
  cl->add_option("--campaign", o.campaign_file, "the campaign file (default rig_configs/reproduce/thesis.yaml)")
      ->type_name("FILE");
  cl->add_option("--clock", o.clock, "inprocess (default), lockstep or realtime")
      ->check(CLI::IsMember({std::string(launcher::kClockInprocess), std::string(launcher::kClockLockstep),
                              std::string(launcher::kClockRealtime)}))
      ->capture_default_str();
  cl->add_option("--seed", o.seed, "the seed of every flight")->capture_default_str();
  cl->add_option("--states", o.states,
                 "states for identification and validation: estimate (the EKF's, as the thesis's) or truth")
      ->check(CLI::IsMember({"estimate", "truth"}))
      ->capture_default_str();
  cl->add_option("--logs", o.work_dir, "where the flights' logs go")->capture_default_str()->type_name("DIR");
  cl->add_option("--controller", o.controller_file, "the controller copy of the closed-loop validation")
      ->type_name("FILE");
  cl.add_json(json_file, "the tables: {\"tables\": [{\"id\", \"title\", \"cells\": [{\"row\", \"column\", "
                         "\"published\", \"rig\", \"verdict\", \"reason\"}]}], \"counts\", \"flights\"}");
  cl->add_option("--report", o.report_dir,
                 "figures in DIR: Fig 9.1 (every set's eigenvalues), the identification, the open-loop "
                 "validations with residual autocorrelation, the closed-loop traces (phi_sp, phi, delta_f)")
      ->type_name("DIR");
  cl->add_flag("--no-progress", "no line per flight on stderr")->each([&o](const std::string&) { o.progress = false; });
  if (const auto done = cl.parse(args)) return *done;
  if (!json_file.empty() && json_file != "-") {
    if (const std::string problem = launcher::writable_problem(json_file); !problem.empty()) {
      std::cerr << "rig reproduce: --json " << json_file << ": " << problem << "\n";
      return kExitUsage;
    }
  }
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  o.rig_exe = ec ? "rig" : exe.string();
  reproduce::CampaignResult result;
  try {
    result = reproduce::run_campaign(o);
  } catch (const ConfigError& e) {
    std::cerr << "rig reproduce: config error: " << e.what() << "\n";
    return kExitUsage;
  } catch (const std::exception& e) {
    std::cerr << "rig reproduce: " << e.what() << "\n";
    return kExitUsage;
  }
  (json_file == "-" ? std::cerr : std::cout) << reproduce::campaign_text(result);
  if (!json_file.empty()) {
    const std::string text = reproduce::campaign_json(result) + "\n";
    if (json_file == "-") {
      std::cout << text;
    } else {
      try {
        write_file(json_file, text);
      } catch (const OutputError& e) {
        std::cerr << "rig reproduce: " << e.what() << "\n";
        return kExitUsage;
      }
    }
  }
  return result.counts().at("differs") > 0 ? 1 : 0;
}

}  // namespace nimble::cli
