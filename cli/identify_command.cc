/// `rig identify`: identification of the lateral model from flight data (a CSV file or a rig log).

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "cmdline/args.h"
#include "cli/commands.h"
#include "core/json_line.h"
#include "core/model.h"
#include "core/vehicle.h"
#include "ident/flight_data.h"
#include "ident/rig_log.h"
#include "ident/identify.h"
#include "ident/model_writer.h"
#include "ident/plots.h"
#include "ident/report.h"
#include "mcap/log_export.h"
#include "cli/log_input.h"
#include "plots/gnuplot.h"

namespace nimble::cli {

namespace {

/// OLS beside WLS of the same record (--ols-beside-wls): the text and the JSON value.
struct MethodsComparison {
  std::string text, json;
};

/// `result` is the command's own identification: it serves as the OLS or the WLS one when it is
/// either, so that only the other is run again.
MethodsComparison compare_methods(const ident::FlightData& data, const Vehicle& vehicle,
                                  const std::string& vehicle_file, const ident::IdentResult& result) {
  const auto by = [&](ident::Method method) {
    if (result.options.method == method) return result;
    ident::IdentOptions o = result.options;
    o.method = method;
    return ident::identify(data, vehicle, vehicle_file, o);
  };
  const ident::IdentResult a = by(ident::Method::kOls), b = by(ident::Method::kWls);
  return {ident::methods_comparison_text(a, b), ident::methods_comparison_json(a, b)};
}

/// The report's JSON with the comparison under "ols_beside_wls" (when there is one).
std::string with_comparison(const std::string& report, const MethodsComparison& comparison) {
  if (comparison.json.empty()) return report;
  OrderedJson j = OrderedJson::parse(report);
  j["ols_beside_wls"] = OrderedJson::parse(comparison.json);
  return json_line(j);
}

}  // namespace

int run_identify_command(const std::vector<std::string>& args) {
  std::string csv, vehicle_file, json, model_out, plots;
  ident::IdentOptions opt;
  ident::LogReadOptions log_options;
  cmdline::CommandLine cl("rig identify",
                          "Identifies the dimensional stability and control derivatives of the lateral model from\n"
                          "flight data, a CSV file or a rig log (read by its content; equation error, thesis\n"
                          "Section IV), prints the parameters with their standard deviations, flagged correlations,\n"
                          "accuracy metrics, residual whiteness, eigenvalues and modes, and state PSDs.");
  cl->add_option("data", csv, "flight data: identification CSV or a rig log (.lcmlog)")->required();
  cmdline::each_value(cl->add_option("--structure",
                                     "model structure: lateral3 (default), lateral4, or the black-box "
                                     "blackbox3, blackbox4 (every entry of A and B free)")
                          ->type_name("NAME")
                          ->check(CLI::IsMember({"lateral3", "lateral4", "blackbox3", "blackbox4"})),
                      [&opt](const std::string& v) { opt.structure = structure_from_string(v); });
  cmdline::each_value(cl->add_option("--method",
                                     "estimator: wls (default, equation error), ols, or output-error (the "
                                     "states simulated from the recorded inputs in segments and fitted to "
                                     "the measured ones, from the WLS values; lateral3)")
                          ->type_name("NAME")
                          ->check(CLI::IsMember({"ols", "wls", "output-error"})),
                      [&opt](const std::string& v) { opt.method = ident::method_from_string(v); });
  cl->add_option("--oe-segment", opt.output_error.segment_s,
                 "output error: the length of each simulated segment, whose initial state is fitted from the "
                 "measured one [s]")
      ->type_name("S")
      ->check(CLI::PositiveNumber);
  add_vehicle(cl, vehicle_file, "rig_configs/vehicles/nimble_no_wifi.yaml");
  add_salvage(cl, log_options);
  std::string sensing_file;
  add_states(cl, log_options, sensing_file);
  cmdline::each_value(cl->add_option("--inputs",
                                     "comma-separated inputs (default delta_f,delta_t plus delta_d, delta_w "
                                     "when the data has them)")
                          ->type_name("LIST"),
                      [&opt](const std::string& v) { opt.inputs = split_list(v); });
  cl->add_option("--w0", opt.trim.w0_mps, "trim vertical velocity of Eq 21 [m/s]")
      ->check(cmdline::kFinite)
      ->capture_default_str()
      ->type_name("M_PER_S");
  cl->add_option("--u0", opt.trim.u0_mps, "trim forward velocity, lateral4 [m/s]")
      ->check(cmdline::kFinite)
      ->capture_default_str()
      ->type_name("M_PER_S");
  add_processing(cl, opt.processing);
  cl->add_option("--wls-window", opt.wls_window_s, "WLS residual-covariance window [s]")
      ->check(cmdline::kFinite & CLI::PositiveNumber)
      ->capture_default_str()
      ->type_name("S");
  cl->add_option("--lags", opt.whiteness_lags, "whiteness lags")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str()
      ->type_name("N");
  cmdline::each_value(cl->add_option("--hover", "a hover PSD segment [s] (repeatable; default from |phi_sp|)")
                          ->type_name("A:B")
                          ->allow_extra_args(false)
                          ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll),
                      [&opt](const std::string& v) { opt.segments.hover.push_back(time_range(v)); });
  cmdline::each_value(cl->add_option("--manoeuvre", "a manoeuvre PSD segment [s] (repeatable; default from |phi_sp|)")
                          ->type_name("A:B")
                          ->allow_extra_args(false)
                          ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll),
                      [&opt](const std::string& v) { opt.segments.manoeuvre.push_back(time_range(v)); });
  std::string terms_file;
  cl->add_option("--terms", terms_file,
                 "fit the generic terms of this model file's terms: section alongside the derivatives (their "
                 "coefficients are regressors, named <equation>:<expression>; docs/models.md, \"Terms\")")
      ->type_name("MODEL");
  bool ols_beside_wls = false;
  cl->add_flag("--ols-beside-wls", ols_beside_wls,
               "also identify the record by OLS and by WLS and print them side by side, estimate, |sigma| and "
               "100 |sigma/estimate| (thesis Appendix D); JSON: ols_beside_wls");
  cl.add_json(json, "the report");
  cl->add_option("--model-out", model_out, "write the identified model as a model YAML file")->type_name("FILE");
  cl.add_plots(plots, "");
  if (const auto done = cl.parse(args)) return *done;
  if (!terms_file.empty()) opt.terms = load_model(terms_file).terms;
  if (!plots.empty()) plots::require_gnuplot();  // fail before the work, not after

  if (vehicle_file.empty()) vehicle_file = ident::default_vehicle_file();
  const Vehicle vehicle = load_vehicle(vehicle_file);
  if (const auto failed = apply_states(cl, log_options, sensing_file, {csv})) return *failed;
  std::string damage;
  mcap::UndecodableCount undecodable;
  count_undecodable(log_options, undecodable);
  log_options.refuse_beyond_bounds = vehicle;  // a log with garbage that decoded is refused as it is read
  const ident::FlightData data = ident::read_flight_data(csv, log_options, &damage);
  warn_damage("rig identify", csv, damage);
  warn_undecodable("rig identify", csv, undecodable);
  const ident::IdentResult result = ident::identify(data, vehicle, vehicle_file, opt);
  const MethodsComparison comparison =
      ols_beside_wls ? compare_methods(data, vehicle, vehicle_file, result) : MethodsComparison{};

  if (!model_out.empty()) {
    ident::write_model_yaml(
        result.model, model_out,
        {"Identified by rig identify from " + csv + ".",
         "Structure " + to_string(opt.structure) + ", " + ident::to_string(opt.method) +
             "; published: holds the eigenvalues and the standard deviations of this identification",
         "(white-residual formula)."});
  }
  std::vector<std::string> pngs;
  if (!plots.empty()) pngs = ident::plot_identification(result, plots);

  if (json != "-") std::cout << ident::identification_text(result);
  if (json != "-" && !comparison.text.empty()) std::cout << "\n" << comparison.text;
  if (!model_out.empty() && json != "-") std::cout << "\nmodel written to " << model_out << "\n";
  for (const auto& p : pngs) {
    if (json != "-") std::cout << "plot " << p << "\n";
  }
  if (!json.empty())
    cmdline::write_json(json, with_comparison(ident::identification_json(result, model_out, pngs), comparison));
  return 0;
}

}  // namespace nimble::cli
