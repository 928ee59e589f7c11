/// `rig discrepancy`: the discrepancy workflow on flight data against a model (discrepancy/discrepancy.h).

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "cmdline/args.h"
#include "effects/registry.h"
#include "cli/commands.h"
#include "core/model.h"
#include "core/vehicle.h"
#include "ident/flight_data.h"
#include "ident/rig_log.h"
#include "ident/closed_loop.h"
#include "discrepancy/closed_loop_compare.h"
#include "discrepancy/discrepancy.h"
#include "ident/model_writer.h"
#include "ident/plots.h"
#include "ident/report.h"
#include "mcap/log_export.h"
#include "cli/log_input.h"
#include "core/config.h"
#include "plots/gnuplot.h"

namespace nimble::cli {

namespace {

/// --test-term EQUATION: EXPRESSION (repeatable): forms tested as given (DiscrepancyOptions::test_terms).
void add_test_terms(cmdline::CommandLine& cl, ident::DiscrepancyOptions& opt) {
  cmdline::each_value(
      cl->add_option("--test-term")
          ->description("a form to test as given, EQUATION: EXPRESSION (e.g. \"L: p^3\"; grammar: "
                        "docs/models.md \"Terms\"), once on the model as given: the test that knows the "
                        "form, beside the search; reported, not an alarm (repeatable)")
          ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll)
          ->type_name("TERM"),
      [&opt](const std::string& v) {
        const auto colon = v.find(':');
        if (colon == std::string::npos) throw std::invalid_argument("'" + v + "' is not EQUATION: EXPRESSION");
        std::string eq = v.substr(0, colon);
        eq.erase(std::remove_if(eq.begin(), eq.end(), [](unsigned char c) { return std::isspace(c); }), eq.end());
        opt.test_terms.push_back(Term{eq, TermExpression::parse(v.substr(colon + 1)), 0.0, "--test-term"});
      });
}

}  // namespace

int run_discrepancy_command(const std::vector<std::string>& args) {
  if (std::find(args.begin(), args.end(), "--power") != args.end()) return run_discrepancy_power_command(args);
  std::vector<std::string> data_files;
  std::string model_file, vehicle_file, json, model_out, report, gains;
  ident::DiscrepancyOptions opt;
  ident::LogReadOptions log_options;
  cmdline::CommandLine cl("rig discrepancy",
                          "Where the model and the measured data disagree, which physical effect the model is\n"
                          "missing (by name), the model refit with it, and the gap before and after on data the fit\n"
                          "did not see (ident/README.md, \"Discrepancy workflow\").");
  cl->footer(
      "With --power, no data: how long to fly to name an effect, by simulated flights of a scenario\n"
      "(rig discrepancy --power --scenario S --model M --effect NAME=SIZE; 'rig discrepancy --power --help').\n"
      "Exit code: 0 whatever the verdict; 2 bad usage or input (a record refused as not finite or not\n"
      "physical, naming its first bad sample).");
  cl->add_option("data", data_files,
                 "flight data: identification CSV or a rig log (.lcmlog); several flights of the same vehicle are "
                 "pooled (each its own folds and noise level; an effect named only on the pooled evidence, each "
                 "flight's estimate listed with a test that they agree)")
      ->required();
  cl->add_option("--model", model_file, "the model (lateral3) to check")->type_name("FILE")->required();
  add_salvage(cl, log_options);
  std::string sensing_file;
  add_states(cl, log_options, sensing_file);
  add_vehicle(cl, vehicle_file, "the model's");
  cmdline::each_value(cl->add_option("--candidates")
                          ->description("comma-separated candidate effects to try (default: all the data supports): " +
                                        effects::effect_name_list())
                          ->type_name("LIST"),
                      [&opt](const std::string& v) { opt.candidates = split_list(v); });
  add_test_terms(cl, opt);
  cl->add_option("--folds", opt.folds, "held-out cross-validation folds")
      ->check(CLI::Range(4, 100))
      ->capture_default_str()
      ->type_name("K");
  cl->add_option("--partial-f", opt.partial_f, "significance rule (SIDPAC)")
      ->check(cmdline::kFinite & CLI::PositiveNumber)
      ->capture_default_str()
      ->type_name("F");
  cl->add_option("--delay-max", opt.delay_max_s, "actuator_delay scan limit [s], in (0, 1]")
      ->check(cmdline::kFinite & CLI::Range(1e-9, 1.0))
      ->capture_default_str()
      ->type_name("S");
  cl->add_option("--command-latency", opt.command_latency_s,
                 "known latency of the flap command path [s], in [0, 0.1], not named as a delay (default: one "
                 "controller tick of the rig)")
      ->check(cmdline::kFinite & CLI::Range(0.0, 0.1))
      ->type_name("S");
  bool no_compatibility = false;
  cl->add_flag("--no-compatibility", no_compatibility,
               "skip the data-compatibility stage (the gyro's scale, bias and time offset against the attitude, "
               "from the kinematics, corrected before the search)");
  cl->add_option("--offset-max", opt.compatibility.max_offset_s,
                 "time offsets between the gyro and the attitude scanned by the compatibility stage [s], in (0, 2]")
      ->check(cmdline::kFinite & CLI::Range(1e-9, 2.0))
      ->capture_default_str()
      ->type_name("S");
  cl->add_option("--gains", gains,
                 "roll gain set of the closed-loop controller copy (default: the log's CONTROLLER_STATUS gain "
                 "set; fast for CSV data)")
      ->type_name("NAME");
  add_processing(cl, opt.processing);
  cl.add_json(json, "the report");
  cl->add_option("--model-out", model_out, "write the model refit with the named effects (section effects:)")
      ->type_name("FILE");
  cl->add_option("--report", report, "report.md with PNG plots (gnuplot, Debian package gnuplot-nox)")
      ->type_name("DIR");
  if (const auto done = cl.parse(args)) return *done;
  opt.compatibility.enabled = !no_compatibility;
  if (const auto failed = apply_states(cl, log_options, sensing_file, data_files)) return *failed;
  if (!report.empty()) plots::require_gnuplot();  // fail before the work, not after
  const DerivativeModel model = load_model(model_file);
  const std::string vfile = vehicle_file.empty() ? model.vehicle_file : vehicle_file;
  const Vehicle vehicle = load_vehicle(vfile);
  log_options.refuse_beyond_bounds = vehicle;  // a log with garbage that decoded is refused as it is read
  std::vector<ident::FlightData> flights;
  for (const auto& data_file : data_files) {
    if (ident::is_lcm_log(data_file)) {
      mcap::UndecodableCount undecodable;
      count_undecodable(log_options, undecodable);
      ident::RigLogData log = ident::read_rig_log(data_file, log_options.states, log_options);
      log_options.other_event = nullptr;  // it counts into this flight's `undecodable`
      warn_damage("rig discrepancy", data_file, log.damage);
      warn_undecodable("rig discrepancy", data_file, undecodable);
      flights.push_back(std::move(log.measured));
      if (gains.empty()) gains = log.gain_set;  // the gains the (first) run flew
    } else {
      flights.push_back(ident::read_flight_csv(data_file));
    }
  }
  if (gains.empty()) gains = "fast";
  ident::DiscrepancyResult result = ident::find_discrepancy(flights, model, vehicle, opt);
  // Closed loop before and after, as rig validate --closed-loop.
  ident::compare_closed_loop(result, flights, model, vehicle, load_controller_config(ident::default_controller_file()),
                             gains);
  std::string data_file;
  for (const auto& f : data_files) data_file += (data_file.empty() ? "" : ", ") + f;
  if (!model_out.empty()) {
    ident::write_model_yaml(result.augmented_model, model_out,
                            {"Refit by rig discrepancy from " + data_file + " on " + model_file + ".",
                             "Verdict: " + result.verdict + ". " + result.summary,
                             "published.sigma: coloured-residual standard deviations of this refit."});
  }
  std::vector<std::string> report_files;
  if (!report.empty()) report_files = ident::write_discrepancy_report(result, report);
  if (json != "-") std::cout << ident::discrepancy_text(result);
  if (!model_out.empty() && json != "-") std::cout << "\nmodel written to " << model_out << "\n";
  if (!report_files.empty() && json != "-") std::cout << "report written to " << report_files.front() << "\n";
  if (!json.empty()) cmdline::write_json(json, ident::discrepancy_json(result));
  return 0;
}

}  // namespace nimble::cli
