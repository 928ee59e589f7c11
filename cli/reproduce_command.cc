/// `rig reproduce thesis`: the thesis's campaign flown, identified, validated and set beside the
/// published tables (reproduce/thesis_campaign.h).

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <fstream>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

#include "cmdline/args.h"
#include "cli/commands.h"
#include "ident/closed_loop.h"
#include "core/config.h"
#include "core/output_file.h"
#include "launcher/launcher.h"
#include "launcher/run_plan.h"
#include "campaign/sweep.h"
#include "reproduce/beside.h"
#include "reproduce/thesis_campaign.h"
#include "scenario/scenario.h"

namespace nimble::cli {
namespace {

/// "1-5", "1,3,7" or "1-3,8": each item A or A-B (campaign::parse_seed_range); at most 1000 seeds, none twice.
std::vector<std::uint64_t> parse_seed_list(const std::string& text) {
  std::vector<std::uint64_t> seeds;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t comma = text.find(',', start);
    const auto [a, b] =
        campaign::parse_seed_range(text.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    if (b - a >= 1000 || seeds.size() + (b - a + 1) > 1000) throw std::invalid_argument("at most 1000 seeds");
    for (std::uint64_t s = a; s <= b; ++s) {
      if (std::find(seeds.begin(), seeds.end(), s) != seeds.end()) {
        throw std::invalid_argument("seed " + std::to_string(s) + " is named twice");
      }
      seeds.push_back(s);
    }
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return seeds;
}

/// Flies the campaign (with `beside`, twice: reproduce/beside.h), prints its tables and writes its
/// JSON to `json_file` ("-": stdout, the text then on stderr); the command's exit code.
int fly_and_print(const reproduce::CampaignOptions& o, bool beside, const std::string& json_file) {
  reproduce::CampaignResult result;
  reproduce::BesideResult both;
  try {
    if (beside) {
      both = reproduce::run_beside(o);
    } else {
      result = reproduce::run_campaign(o);
    }
  } catch (const ConfigError& e) {
    std::cerr << "rig reproduce: config error: " << e.what() << "\n";
    return cmdline::kExitUsage;
  } catch (const std::exception& e) {
    std::cerr << "rig reproduce: " << e.what() << "\n";
    return cmdline::kExitUsage;
  }
  (json_file == "-" ? std::cerr : std::cout)
      << (beside ? reproduce::beside_text(both) : reproduce::campaign_text(result));
  if (!json_file.empty()) {
    const std::string text = (beside ? reproduce::beside_json(both) : reproduce::campaign_json(result)) + "\n";
    if (json_file == "-") {
      std::cout << text;
    } else {
      try {
        write_file(json_file, text);
      } catch (const OutputError& e) {
        std::cerr << "rig reproduce: " << e.what() << "\n";
        return cmdline::kExitUsage;
      }
    }
  }
  if (beside) return both.without.differing() > 0 || both.with.differing() > 0 ? 1 : 0;
  return result.differing() > 0 ? 1 : 0;
}

}  // namespace

int run_reproduce_command(const std::vector<std::string>& args) {
  namespace fs = std::filesystem;
  reproduce::CampaignOptions o;
  o.campaign_file = NIMBLE_DEFAULT_CAMPAIGN;
  o.controller_file = ident::default_controller_file();
  o.work_dir = "rig_logs/reproduce";
  o.progress = true;
  std::string what, json_file;
  cmdline::CommandLine cl(
      "rig reproduce",
      "Flies the thesis's campaign (identification train on every identification set's model;\n"
      "open-loop 6 Hz doublet and 1-1-2; closed-loop slow train and 1-1-2s; coupled doublet; 20 and\n"
      "30 deg nonlinear doublets; the train on the four-state model and on Appendix E's input\n"
      "variants), identifies set 1's model from its identification flight as the thesis did,\n"
      "validates it on the others, identifies the thesis's other model structures (four- and\n"
      "three-state grey- and black-box, OLS and WLS, delta_f only and with delta_d), and prints every\n"
      "table it reproduces beside the published one (Tables 9.4, 9.5, 9.6, 4, 7-16, 8.2-8.15, D.1,\n"
      "D.2, E.2, E.3, H.1-H.5), each cell with its category, decided by\n"
      "what it is computed from, and its verdict (reproduce/cell_verdict.h): ranges and fit metrics\n"
      "of the rig's flights are match (the mean's 95 % interval inside the tolerance), explained (a\n"
      "reason whose check holds in the same run), differs (wholly outside) or inconclusive (across\n"
      "an edge); calibrated cells match or differ; model cells check the transcribed model files\n"
      "against the thesis and the rig's re-identification of its own plant against the plant file.");
  cl->footer(
      "Exit code: 0 no cell differs, 1 some cell differs (with --beside: in either run), 2 bad input or a\n"
      "flight that could not fly.\n"
      "Examples: rig reproduce thesis --json tables.json --report report/\n"
      "          rig reproduce thesis --vibration --beside --json beside.json");
  cl->add_option("what", what, "the campaign to reproduce")->required()->check(CLI::IsMember({"thesis"}));
  cl->add_option("--campaign", o.campaign_file, "the campaign file (default rig_configs/reproduce/thesis.yaml)")
      ->type_name("FILE");
  cl->add_option("--clock", o.clock, "inprocess (default), lockstep or realtime")
      ->check(CLI::IsMember({std::string(launcher::kClockInprocess), std::string(launcher::kClockLockstep),
                             std::string(launcher::kClockRealtime)}))
      ->capture_default_str();
  std::string seeds = "1-5";
  cl->add_option("--seeds", seeds,
                 "the seeds every flight is flown with, a list or ranges (e.g. 1-10 or 1,3,7); each cell is judged "
                 "on the mean over them, with its interval")
      ->capture_default_str()
      ->type_name("LIST");
  cl->add_option("--states", o.states,
                 "states for identification and validation: smoothed (made offline from the recorded IMU and motion "
                 "capture, as the thesis's were), estimate (the on-board EKF's) or truth")
      ->check(CLI::IsMember({"smoothed", "estimate", "truth"}))
      ->capture_default_str();
  o.jobs = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  cl->add_option("--jobs", o.jobs,
                 "seeds flown at a time, each in a worker process (default: this machine's CPUs); the tables are "
                 "the same for any number")
      ->check(CLI::Range(1, 1024))
      ->capture_default_str();
  cl->add_option("--logs", o.work_dir, "where the flights' logs go")->capture_default_str()->type_name("DIR");
  cl->add_option("--dir", o.result_dir,
                 "keep each seed's values in this campaign directory as it finishes (DIR/campaign.json, "
                 "DIR/runs/seed-N.json); started again with the same campaign, the command flies only the seeds "
                 "DIR lacks, and a DIR of another campaign is refused, naming what differs")
      ->type_name("DIR");
  cl->add_option("--controller", o.controller_file, "the controller copy of the closed-loop validation")
      ->type_name("FILE");
  cmdline::each_value(cl->add_option("--set",
                                     "override one scenario value in every flight of the campaign, parsed as "
                                     "YAML (repeatable; as for rig run, SECTION.base=FILE included); printed "
                                     "in the report, and part of what identifies a --dir")
                          ->type_name("KEY.PATH=VALUE")
                          ->allow_extra_args(false)
                          ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll),
                      [&o](const std::string& v) { o.overrides.push_back(parse_override(v)); });
  bool vibration = false, beside = false;
  cl->add_flag("--vibration", vibration,
               "the real vehicle's flight vibration on every flight: --set sensing.base=<the source tree's "
               "rig_configs/sensing/nimble_flight_vibration.yaml> (before any --set)");
  cl->add_flag("--beside", beside,
               "fly the campaign twice, without and with the overrides (--set, --vibration; their logs, figures and "
               "campaign directory in without/ and with/ of --logs, --report and --dir), and print per cell the "
               "published value, the rig's without and with, each judged on its own run, and whether the cell moved "
               "toward the published value or away (same: the change of |rig - published| within the cell's "
               "tolerance or the two means' 95 % interval), with the counts and the verdicts that changed");
  cl.add_json(json_file,
              "the tables: {\"tables\": [{\"id\", \"title\", \"cells\": [{\"row\", \"column\", "
              "\"published\", \"rig\", \"verdict\", \"reason\"}]}], \"counts\", \"flights\", "
              "\"overrides\"}; with --beside, per cell \"rig_without\", \"rig_with\", \"verdict_without\", "
              "\"verdict_with\", \"moved\" and both runs' cells, and each run's whole JSON in \"without\" "
              "and \"with\",");
  cl->add_option("--report", o.report_dir,
                 "figures in DIR: Fig 9.1 (every set's eigenvalues), the identification, the open-loop "
                 "validations with residual autocorrelation, the closed-loop traces (phi_sp, phi, delta_f)")
      ->type_name("DIR");
  cl->add_flag("--no-progress", "no line per flight on stderr")->each([&o](const std::string&) { o.progress = false; });
  if (const auto done = cl.parse(args)) return *done;
  if (vibration) o.overrides.insert(o.overrides.begin(), Override{"sensing.base", NIMBLE_DEFAULT_VIBRATION});
  if (beside && o.overrides.empty())
    return cl.fail("--beside needs overrides to fly beside: --set KEY=VALUE or --vibration");
  try {
    o.seeds = parse_seed_list(seeds);
  } catch (const std::invalid_argument& e) {
    return cl.fail("--seeds " + seeds + ": " + e.what());
  }
  if (!json_file.empty() && json_file != "-") {
    if (const std::string problem = launcher::writable_problem(json_file); !problem.empty()) {
      std::cerr << "rig reproduce: --json " << json_file << ": " << problem << "\n";
      return cmdline::kExitUsage;
    }
  }
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  o.rig_exe = ec ? "rig" : exe.string();
  return fly_and_print(o, beside, json_file);
}

}  // namespace nimble::cli
