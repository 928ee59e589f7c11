/// `rig validate`: open-loop (and closed-loop) validation of a model on flight data.

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
#include "core/model.h"
#include "core/vehicle.h"
#include "ident/flight_data.h"
#include "ident/rig_log.h"
#include "ident/closed_loop.h"
#include "ident/plots.h"
#include "ident/report.h"
#include "ident/validate.h"
#include "mcap/log_export.h"
#include "cli/log_input.h"
#include "core/config.h"
#include "plots/gnuplot.h"

namespace nimble::cli {

int run_validate_command(const std::vector<std::string>& args) {
  std::string model_file, csv, vehicle_file, json, plots;
  std::string gains, controller_file = ident::default_controller_file();
  bool closed_loop = false;
  ident::ValidationOptions opt;
  ident::LogReadOptions log_options;
  cmdline::CommandLine cl("rig validate",
                          "Open-loop validation: the state derivatives predicted by the model from the measured\n"
                          "states and inputs against the measured ones (thesis Tables 7-8).");
  cl->add_option("model", model_file, "the model file")->required();
  cl->add_option("data", csv, "flight data: identification CSV or a rig log (.lcmlog)")->required();
  add_vehicle(cl, vehicle_file, "the model's");
  add_salvage(cl, log_options);
  std::string sensing_file;
  add_states(cl, log_options, sensing_file);
  add_processing(cl, opt.processing);
  cl->add_option("--lags", opt.whiteness_lags, "whiteness lags")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str()
      ->type_name("N");
  cl.add_json(json, "the report");
  cl.add_plots(plots, "");
  cl->add_flag("--closed-loop", closed_loop,
               "closed-loop validation instead (thesis Tables 9-11): the model flown by a copy of the attitude "
               "controller and the flap actuator on the data's phi_sp and delta_t, from the measured initial "
               "state; simulated p, v, phi, delta_f against the measured ones; --plots draws their time "
               "histories (closed_loop.png)");
  cl->add_option("--gains", gains,
                 "roll gain set of the controller copy (default: the set a rig log's controller flew, "
                 "fast for CSV data)")
      ->type_name("NAME");
  cl->add_option("--controller", controller_file, "controller configuration")->capture_default_str()->type_name("FILE");
  if (const auto done = cl.parse(args)) return *done;
  if (const auto failed = apply_states(cl, log_options, sensing_file, {csv})) return *failed;
  if (!plots.empty()) plots::require_gnuplot();

  const DerivativeModel model = load_model(model_file);
  const Vehicle vehicle = load_vehicle(vehicle_file.empty() ? model.vehicle_file : vehicle_file);
  log_options.refuse_beyond_bounds = vehicle;  // a log with garbage that decoded is refused as it is read
  std::string damage;
  ident::FlightData data;
  mcap::UndecodableCount undecodable;
  count_undecodable(log_options, undecodable);
  if (ident::is_lcm_log(csv)) {
    ident::RigLogData log = ident::read_rig_log(csv, log_options.states, log_options);
    damage = log.damage;
    data = std::move(log.measured);
    if (gains.empty()) gains = log.gain_set;  // the gains the run flew
  } else {
    data = ident::read_flight_data(csv, log_options, &damage);
  }
  if (gains.empty()) gains = "fast";
  warn_damage("rig validate", csv, damage);
  warn_undecodable("rig validate", csv, undecodable);
  if (closed_loop) {
    ident::ClosedLoopOptions cl;
    cl.controller = load_controller_config(controller_file);
    cl.gain_set = gains;
    cl.interpolation = opt.processing.interpolation;
    const ident::ClosedLoopResult r = ident::validate_closed_loop(data, model, vehicle, cl);
    std::vector<std::string> pngs;
    if (!plots.empty()) pngs = ident::plot_closed_loop(r, plots);
    if (json != "-") {
      std::printf("closed-loop validation of %s on %s (gains %s, %lld samples at %.0f Hz)\n", model.name.c_str(),
                  r.source.c_str(), r.gain_set.c_str(), static_cast<long long>(r.t_s.size()), r.rate_hz);
      std::printf("  %-8s %8s %8s %12s %12s %10s\n", "output", "r_xy", "R2", "RMSE", "range", "RMSE[%rng]");
      for (const char* name : {"p", "v", "phi", "delta_f"}) {
        const ident::FitMetrics& f = r.fits.at(name);
        std::printf("  %-8s %8.3f %8.3f %12.4g %12.4g %10.2f\n", name, f.rxy, f.r2, f.rmse, f.range, f.rmse_pct_range);
      }
      for (const auto& p : pngs) std::cout << "plot " << p << "\n";
    }
    if (!json.empty()) cmdline::write_json(json, ident::closed_loop_json(r, pngs));
    return 0;
  }
  const ident::ValidationResult result = ident::validate_open_loop(data, model, vehicle, opt);
  std::vector<std::string> pngs;
  if (!plots.empty()) pngs = ident::plot_validation(result, plots);
  if (json != "-") {
    std::cout << ident::validation_text(result);
    for (const auto& p : pngs) std::cout << "plot " << p << "\n";
  }
  if (!json.empty()) cmdline::write_json(json, ident::validation_json(result, pngs));
  return 0;
}

}  // namespace nimble::cli
