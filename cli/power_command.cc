/// `rig discrepancy --power`: how long to fly to name an effect (detection_power/power_campaign.h).

#include <algorithm>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

#include "cli/commands.h"
#include "cmdline/args.h"
#include "effects/registry.h"
#include "ident/plots.h"
#include "detection_power/effect_size.h"
#include "detection_power/power_campaign.h"
#include "detection_power/power_report.h"
#include "plots/gnuplot.h"

namespace nimble::cli {
namespace {

constexpr const char* kPowerDescription =
    "How long to fly: the probability that rig discrepancy names a plant effect of a given size with\n"
    "the scenario as it is, and the record length it needs for the target probability (90 %). Each\n"
    "(size, length) is flown --flights times in process, by the rig's own plant, sensors, controller\n"
    "and estimator, the effect set to SIZE, the scenario's manoeuvre repeated for the length; the\n"
    "workflow runs on each flight's data as it would on its log. Prints per cell the probability of\n"
    "naming the effect, of naming another, of any alarm (95 % Wilson intervals), the recommended\n"
    "length per size and the smallest size per length (docs/discrepancy.md \"How long to fly\").";

std::string power_footer() {
  std::string out = "SIZE sets one plant parameter (plant.effects.<effect>.<parameter>):\n";
  for (const auto& e : detection_power::sized_effects()) {
    out += "  " + e.effect + "=" + e.parameter + " [" + e.unit + "], " + e.range.describe() + "; " + e.scales +
           "; named " + e.named_as + "\n";
  }
  out +=
      "SIZE 0 switches the effect off: its naming rate is then the false-naming rate.\n"
      "Flight i of every cell has the seed hash(--seed, i); --verify flies fresh seeds.\n"
      "Exit code: 0 whatever the probabilities; 2 bad usage or input.\n"
      "Example: rig discrepancy --power --scenario rig_configs/cl_doublet_train_slow.yaml \\\n"
      "           --model rig_configs/models/nimble_lateral_set1_kinematic.yaml --effect actuator_delay=0.004,0.008 "
      "\\\n"
      "           --lengths 9,18,36 --flights 100 --plots power/";
  return out;
}

}  // namespace

int run_discrepancy_power_command(const std::vector<std::string>& args_in) {
  std::vector<std::string> args;
  for (const auto& a : args_in) {
    if (a != "--power") args.push_back(a);
  }
  detection_power::PowerOptions o;
  o.jobs = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  std::string json, plots;
  cmdline::CommandLine cl("rig discrepancy --power", kPowerDescription);
  cl->footer(power_footer());
  cl->add_option("--scenario", o.scenario_file, "the scenario to fly")->type_name("FILE")->required();
  cl->add_option("--model", o.model_file, "the model (lateral3) the workflow checks")->type_name("FILE")->required();
  cmdline::each_value(cl->add_option("--effect")
                          ->description("the plant effect and its sizes, a list A,B or a grid FROM:TO:STEP: " +
                                        detection_power::sized_effect_list())
                          ->type_name("NAME=SIZE")
                          ->required(),
                      [&o](const std::string& v) {
                        const detection_power::EffectSizes e = detection_power::parse_effect_sizes(v);
                        o.effect = e.effect;
                        o.sizes = e.sizes;
                      });
  cmdline::each_value(cl->add_option("--lengths",
                                     "record lengths [s], a list or FROM:TO:STEP (default: the scenario's block "
                                     "times 1, 2, 4, 8)")
                          ->type_name("S"),
                      [&o](const std::string& v) {
                        o.lengths_s = cmdline::number_grid(v);
                        for (const double l : o.lengths_s) {
                          if (!(l > 0.0)) throw std::invalid_argument("a record length must be > 0 s, got " + v);
                        }
                      });
  cl->add_option("--flights", o.flights, "flights per (size, length)")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str()
      ->type_name("N");
  cl->add_option("--seed", o.seed, "the campaign's seed")
      ->check(cmdline::kWholeNumber)
      ->capture_default_str()
      ->type_name("N");
  cl->add_option("--jobs", o.jobs, "flights at a time (default: one per CPU)")
      ->check(CLI::Range(1, 256))
      ->type_name("N");
  cl->add_option("--target", o.target, "the naming probability a recommended length reaches")
      ->check(cmdline::kFinite & CLI::Range(0.01, 0.999))
      ->capture_default_str()
      ->type_name("P");
  cl->add_option("--refine", o.refine,
                 "rounds of refinement of each recommended length (a cell at the interpolated "
                 "length)")
      ->check(CLI::Range(0, 20))
      ->capture_default_str()
      ->type_name("N");
  cl->add_option("--verify", o.verify, "fly N fresh seeds at each recommended length and report the rate there")
      ->check(CLI::Range(0, 100000))
      ->type_name("N");
  cmdline::each_value(
      cl->add_option("--set", "override one scenario value in every flight, parsed as YAML (repeatable)")
          ->type_name("KEY.PATH=VALUE")
          ->allow_extra_args(false)
          ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll),
      [&o](const std::string& v) { o.overrides.push_back(parse_override(v)); });
  cl->add_option("--vehicle", o.vehicle_file, "the vehicle of the workflow (default: the model's)")->type_name("FILE");
  cmdline::each_value(cl->add_option("--candidates")
                          ->description("comma-separated candidate effects the workflow tries (default: all the data "
                                        "supports): " +
                                        effects::effect_name_list())
                          ->type_name("LIST"),
                      [&o](const std::string& v) {
                        o.discrepancy.candidates.clear();
                        std::size_t start = 0;
                        while (start <= v.size()) {
                          const std::size_t comma = std::min(v.find(',', start), v.size());
                          if (comma > start) o.discrepancy.candidates.push_back(v.substr(start, comma - start));
                          start = comma + 1;
                        }
                      });
  cl.add_json(json, "the cells, recommendations, verification and timing");
  cl.add_plots(plots, "power_length.png, power_size.png");
  cl->add_option("--dir", o.result_dir,
                 "keep each flight's outcome in this campaign directory as it finishes (DIR/campaign.json, "
                 "DIR/runs/); started again with the same scenario, effect, model and candidates, the command flies "
                 "only the flights DIR lacks, and a DIR of another campaign is refused, naming what differs")
      ->type_name("DIR");
  cl->add_flag("--no-progress", "no progress line on stderr")->each([&o](const std::string&) { o.progress = false; });
  if (const auto done = cl.parse(args)) return *done;
  if (!plots.empty()) plots::require_gnuplot();  // fail before the flights, not after

  detection_power::PowerResult result;
  try {
    result = detection_power::run_power(o);
  } catch (const ConfigError& e) {
    std::cerr << "rig discrepancy --power: config error: " << e.what() << "\n";
    return cmdline::kExitUsage;
  }
  std::vector<std::string> pngs;
  if (!plots.empty()) pngs = detection_power::write_power_plots(result, plots);
  std::ostream& text = json == "-" ? std::cerr : std::cout;
  text << detection_power::power_text(result);
  for (const auto& p : pngs) text << "plot " << p << "\n";
  if (!json.empty()) cmdline::write_json(json, detection_power::power_json(result, pngs));
  return 0;
}

}  // namespace nimble::cli
