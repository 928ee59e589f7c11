/// `rig identify` and `rig validate`: identification of the lateral model from
/// CSV flight data and open-loop validation of a model on CSV flight data.

#include <cstdlib>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli/args.h"
#include "cli/commands.h"
#include "core/model.h"
#include "core/vehicle.h"
#include "ident/flight_data.h"
#include "ident/rig_log.h"
#include "ident/closed_loop.h"
#include "ident/discrepancy.h"
#include "core/json_writer.h"
#include "ident/signal.h"
#include "ident/identify.h"
#include "ident/model_writer.h"
#include "ident/plots.h"
#include "ident/report.h"
#include "ident/validate.h"

namespace nimble::cli {
namespace {

constexpr const char* kIdentifyUsage =
    "usage: rig identify <data.csv|log.lcmlog> [options]\n"
    "  Identifies the dimensional stability and control derivatives of the lateral\n"
    "  model from flight data, a CSV file or a rig log (read by its content; equation\n"
    "  error, thesis Section IV), prints the\n"
    "  parameters with their standard deviations, flagged correlations, accuracy\n"
    "  metrics, residual whiteness, eigenvalues and modes, and state PSDs.\n"
    "  --structure lateral3|lateral4  model structure (default lateral3)\n"
    "  --salvage                      a damaged rig log: read the events before the damage\n"
    "  --method ols|wls               estimator (default wls)\n"
    "  --vehicle FILE                 vehicle (default rig_configs/vehicles/nimble_no_wifi.yaml)\n"
    "  --inputs LIST                  comma-separated inputs (default delta_f,delta_t plus\n"
    "                                 delta_d, delta_w when the data has them)\n"
    "  --w0 M_PER_S                   trim vertical velocity of Eq 21 (default 0)\n"
    "  --u0 M_PER_S                   trim forward velocity, lateral4 (default 0)\n"
    "  --rate HZ                      resampling rate (default 512)\n"
    "  --interpolation cubic|linear   resampling of every channel (default cubic)\n"
    "  --cutoff HZ                    low-pass cut-off (default 9)\n"
    "  --order N                      Butterworth order, 0 = no low-pass (default 10)\n"
    "  --wls-window S                 WLS residual-covariance window (default 2 s)\n"
    "  --lags N                       whiteness lags (default 50)\n"
    "  --hover A:B, --manoeuvre A:B   PSD segments in s (repeatable; default from |phi_sp|)\n"
    "  --json FILE                    write the JSON report to FILE ('-' for stdout)\n"
    "  --model-out FILE               write the identified model as a model YAML file\n"
    "  --plots DIR                    PNG plots via gnuplot (Debian package gnuplot-nox)\n";

constexpr const char* kValidateUsage =
    "usage: rig validate <model.yaml> <data.csv|log.lcmlog> [options]\n"
    "  Open-loop validation: the state derivatives predicted by the model from the\n"
    "  measured states and inputs against the measured ones (thesis Tables 7-8).\n"
    "  --vehicle FILE   use this vehicle instead of the model's\n"
    "  --salvage        a damaged rig log: read the events before the damage\n"
    "  --rate HZ, --cutoff HZ, --order N   processing (defaults 512, 9, 10)\n"
    "  --interpolation cubic|linear        resampling (default cubic)\n"
    "  --lags N         whiteness lags (default 50)\n"
    "  --json FILE      write the JSON report to FILE ('-' for stdout)\n"
    "  --plots DIR      PNG plots via gnuplot (Debian package gnuplot-nox)\n"
    "  --closed-loop    closed-loop validation instead (thesis Tables 9-11): the model flown by a copy\n"
    "                   of the attitude controller and the flap actuator on the data's phi_sp and\n"
    "                   delta_t, from the measured initial state; simulated p, v, phi, delta_f\n"
    "                   against the measured ones; --plots draws their time histories (closed_loop.png)\n"
    "  --gains NAME     roll gain set of the controller copy (default fast)\n"
    "  --controller FILE  controller configuration (default rig_configs/controller/nimble_attitude.yaml)\n";

constexpr const char* kDiscrepancyUsage =
    "usage: rig discrepancy <data.csv|log.lcmlog> --model <model.yaml> [options]\n"
    "  Where the model and the measured data disagree, which physical effect the model is\n"
    "  missing (by name), the model refit with it, and the gap before and after on data the\n"
    "  fit did not see (ident/README.md, \"Discrepancy workflow\"). Exit 0 whatever the verdict.\n"
    "  --model FILE        the model (lateral3) to check\n"
    "  --salvage           a damaged rig log: read the events before the damage\n"
    "  --vehicle FILE      use this vehicle instead of the model's\n"
    "  --candidates LIST   comma-separated candidate effects to try (default: all the data supports):\n"
    "                      kinematic_coupling, gravity_nonlinearity, lateral_inflow,\n"
    "                      forward_speed_coupling, actuator_delay, sensor_bias, dihedral_coupling,\n"
    "                      yaw_coupling, flapping_forcing, lateral_gust\n"
    "  --folds K           held-out cross-validation folds (default 10)\n"
    "  --partial-f F       significance rule (default 20, SIDPAC)\n"
    "  --delay-max S       actuator_delay scan limit (default 0.06 s)\n"
    "  --command-latency S known latency of the flap command path, not named as a delay\n"
    "                      (default 1/512 s: one controller tick of the rig)\n"
    "  --gains NAME        roll gain set of the closed-loop controller copy (default: the log's\n"
    "                      CONTROLLER_STATUS gain set; fast for CSV data)\n"
    "  --rate HZ, --cutoff HZ, --order N, --interpolation cubic|linear   processing (512, 9, 10, cubic)\n"
    "  --json FILE         write the JSON report to FILE ('-' for stdout)\n"
    "  --model-out FILE    write the model refit with the named effects (section effects:)\n"
    "  --report DIR        report.md with PNG plots (gnuplot, Debian package gnuplot-nox)\n";

ident::TimeRange time_range(const std::string& option, const std::string& text) {
  const std::size_t colon = text.find(':');
  if (colon == std::string::npos) throw UsageError(option + ": '" + text + "' is not START:END in seconds");
  ident::TimeRange r{number(option, text.substr(0, colon)), number(option, text.substr(colon + 1))};
  if (!(r.end_s > r.start_s)) throw UsageError(option + ": '" + text + "': END must be after START");
  return r;
}

std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t comma = text.find(',', start);
    const std::string item = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    if (!item.empty()) out.push_back(item);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

/// Processing options shared by both commands; returns false if `a` is not one.
bool processing_option(Args& it, ident::ProcessingOptions& p) {
  const std::string& a = it.arg();
  if (a == "--rate") {
    p.rate_hz = number(a, it.value());
    if (!(p.rate_hz > 0.0)) throw UsageError("--rate must be > 0 Hz");
  } else if (a == "--cutoff") {
    p.cutoff_hz = number(a, it.value());
  } else if (a == "--order") {
    p.filter_order = integer(a, it.value(), 0, 40);
  } else if (a == "--interpolation") {
    const std::string m = it.value();
    if (m != "linear" && m != "cubic") throw UsageError("--interpolation: '" + m + "' is not cubic or linear");
    p.interpolation = ident::interpolation_from_string(m);
  } else {
    return false;
  }
  return true;
}

/// `--salvage`: read a damaged log up to the damage; returns false if `it` is not that option.
bool log_option(Args& it, ident::LogReadOptions& o) {
  if (it.arg() != "--salvage") return false;
  o.salvage = true;
  return true;
}

/// Says on stderr what a salvaged read left out.
void warn_damage(const char* command, const std::string& file, const std::string& damage) {
  if (!damage.empty()) std::cerr << command << ": warning: " << file << ": " << damage << "\n";
}

}  // namespace

int run_identify_command(const std::vector<std::string>& args) {
  if (wants_help(args)) {
    std::cout << kIdentifyUsage;
    return 0;
  }
  std::string csv, vehicle_file, json, model_out, plots;
  ident::IdentOptions opt;
  ident::LogReadOptions log_options;
  try {
    Args it(args);
    while (it.next()) {
      const std::string& a = it.arg();
      if (processing_option(it, opt.processing) || log_option(it, log_options)) continue;
      if (a == "--structure") {
        const std::string s = it.value();
        if (s != "lateral3" && s != "lateral4") throw UsageError("--structure: '" + s + "' is not lateral3 or lateral4");
        opt.structure = structure_from_string(s);
      } else if (a == "--method") {
        const std::string m = it.value();
        if (m != "ols" && m != "wls") throw UsageError("--method: '" + m + "' is not ols or wls");
        opt.method = ident::method_from_string(m);
      } else if (a == "--vehicle") {
        vehicle_file = it.value();
      } else if (a == "--inputs") {
        opt.inputs = split_list(it.value());
        if (opt.inputs.empty()) throw UsageError("--inputs: empty list");
      } else if (a == "--w0") {
        opt.trim.w0_mps = number(a, it.value());
      } else if (a == "--u0") {
        opt.trim.u0_mps = number(a, it.value());
      } else if (a == "--wls-window") {
        opt.wls_window_s = number(a, it.value());
        if (!(opt.wls_window_s > 0.0)) throw UsageError("--wls-window must be > 0 s");
      } else if (a == "--lags") {
        opt.whiteness_lags = static_cast<std::size_t>(integer(a, it.value(), 1, 100000));
      } else if (a == "--hover") {
        opt.segments.hover.push_back(time_range(a, it.value()));
      } else if (a == "--manoeuvre") {
        opt.segments.manoeuvre.push_back(time_range(a, it.value()));
      } else if (a == "--json") {
        json = it.value();
      } else if (a == "--model-out") {
        model_out = it.value();
      } else if (a == "--plots") {
        plots = it.value();
      } else if (!a.empty() && a[0] == '-') {
        throw UsageError("unknown option '" + a + "'");
      } else if (csv.empty()) {
        csv = a;
      } else {
        throw UsageError("unexpected argument '" + a + "'");
      }
    }
    if (csv.empty()) throw UsageError("missing <data.csv>");
  } catch (const UsageError& e) {
    std::cerr << "rig identify: " << e.what() << "\n" << kIdentifyUsage;
    return kExitUsage;
  }
  if (!plots.empty()) ident::require_gnuplot();  // fail before the work, not after

  if (vehicle_file.empty()) vehicle_file = ident::default_vehicle_file();
  const Vehicle vehicle = load_vehicle(vehicle_file);
  std::string damage;
  const ident::FlightData data = ident::read_flight_data(csv, log_options, &damage);
  warn_damage("rig identify", csv, damage);
  const ident::IdentResult result = ident::identify(data, vehicle, vehicle_file, opt);

  if (!model_out.empty()) {
    ident::write_model_yaml(result.model, model_out,
                            {"Identified by rig identify from " + csv + ".",
                             "Structure " + to_string(opt.structure) + ", " + ident::to_string(opt.method) +
                                 "; published: holds the eigenvalues and the standard deviations of this identification",
                             "(white-residual formula)."});
  }
  std::vector<std::string> pngs;
  if (!plots.empty()) pngs = ident::plot_identification(result, plots);

  if (json != "-") std::cout << ident::identification_text(result);
  if (!model_out.empty() && json != "-") std::cout << "\nmodel written to " << model_out << "\n";
  for (const auto& p : pngs) {
    if (json != "-") std::cout << "plot " << p << "\n";
  }
  if (!json.empty()) write_json(json, ident::identification_json(result, model_out, pngs));
  return 0;
}

int run_discrepancy_command(const std::vector<std::string>& args) {
  if (wants_help(args)) {
    std::cout << kDiscrepancyUsage;
    return 0;
  }
  std::string data_file, model_file, vehicle_file, json, model_out, report, gains;
  ident::DiscrepancyOptions opt;
  ident::LogReadOptions log_options;
  try {
    Args it(args);
    while (it.next()) {
      const std::string& a = it.arg();
      if (processing_option(it, opt.processing) || log_option(it, log_options)) continue;
      if (a == "--model") {
        model_file = it.value();
      } else if (a == "--vehicle") {
        vehicle_file = it.value();
      } else if (a == "--candidates") {
        opt.candidates = split_list(it.value());
        if (opt.candidates.empty()) throw UsageError("--candidates: empty list");
      } else if (a == "--folds") {
        opt.folds = static_cast<std::size_t>(integer(a, it.value(), 4, 100));
      } else if (a == "--partial-f") {
        opt.partial_f = number(a, it.value());
        if (!(opt.partial_f > 0.0)) throw UsageError("--partial-f must be > 0");
      } else if (a == "--delay-max") {
        opt.delay_max_s = number(a, it.value());
        if (!(opt.delay_max_s > 0.0 && opt.delay_max_s <= 1.0)) throw UsageError("--delay-max must be in (0, 1] s");
      } else if (a == "--command-latency") {
        opt.command_latency_s = number(a, it.value());
        if (!(opt.command_latency_s >= 0.0 && opt.command_latency_s <= 0.1)) {
          throw UsageError("--command-latency must be in [0, 0.1] s");
        }
      } else if (a == "--gains") {
        gains = it.value();
      } else if (a == "--json") {
        json = it.value();
      } else if (a == "--model-out") {
        model_out = it.value();
      } else if (a == "--report") {
        report = it.value();
      } else if (!a.empty() && a[0] == '-') {
        throw UsageError("unknown option '" + a + "'");
      } else if (data_file.empty()) {
        data_file = a;
      } else {
        throw UsageError("unexpected argument '" + a + "'");
      }
    }
    if (data_file.empty()) throw UsageError("missing <data.csv|log.lcmlog>");
    if (model_file.empty()) throw UsageError("missing --model <model.yaml>");
  } catch (const UsageError& e) {
    std::cerr << "rig discrepancy: " << e.what() << "\n" << kDiscrepancyUsage;
    return kExitUsage;
  }
  if (!report.empty()) ident::require_gnuplot();  // fail before the work, not after
  const DerivativeModel model = load_model(model_file);
  const std::string vfile = vehicle_file.empty() ? model.vehicle_file : vehicle_file;
  const Vehicle vehicle = load_vehicle(vfile);
  ident::FlightData data;
  if (ident::is_lcm_log(data_file)) {
    ident::RigLogData log = ident::read_rig_log(data_file, ident::StateSource::kAuto, log_options);
    warn_damage("rig discrepancy", data_file, log.damage);
    data = std::move(log.measured);
    if (gains.empty()) gains = log.gain_set;  // the gains the run flew
  } else {
    data = ident::read_flight_csv(data_file);
  }
  if (gains.empty()) gains = "fast";
  ident::DiscrepancyResult result = ident::find_discrepancy(data, model, vehicle, opt);
  // Closed loop before and after, as rig validate --closed-loop.
  if (!data.has("phi_sp")) {
    result.closed_loop_note = "the data has no phi_sp";
  } else {
    try {
      ident::ClosedLoopOptions cl;
      cl.controller = load_controller_config(NIMBLE_DEFAULT_CONTROLLER);
      cl.gain_set = gains;
      const ident::ClosedLoopResult before = ident::validate_closed_loop(data, model, vehicle, cl);
      const ident::ClosedLoopResult after = ident::validate_closed_loop(data, result.augmented_model, vehicle, cl);
      for (const char* s : {"p", "v", "phi", "delta_f"}) {
        result.closed_loop.push_back({s, before.fits.at(s).r2, after.fits.at(s).r2, before.fits.at(s).rmse,
                                      after.fits.at(s).rmse});
      }
      result.closed_loop_note = "gains " + gains;
    } catch (const std::exception& e) {
      result.closed_loop_note = std::string("not flown: ") + e.what();
    }
  }
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
  if (!json.empty()) write_json(json, ident::discrepancy_json(result));
  return 0;
}

int run_validate_command(const std::vector<std::string>& args) {
  if (wants_help(args)) {
    std::cout << kValidateUsage;
    return 0;
  }
  std::string model_file, csv, vehicle_file, json, plots;
  std::string gains = "fast", controller_file = NIMBLE_DEFAULT_CONTROLLER;
  bool closed_loop = false;
  ident::ValidationOptions opt;
  ident::LogReadOptions log_options;
  try {
    Args it(args);
    while (it.next()) {
      const std::string& a = it.arg();
      if (processing_option(it, opt.processing) || log_option(it, log_options)) continue;
      if (a == "--closed-loop") {
        closed_loop = true;
      } else if (a == "--gains") {
        gains = it.value();
      } else if (a == "--controller") {
        controller_file = it.value();
      } else if (a == "--vehicle") {
        vehicle_file = it.value();
      } else if (a == "--lags") {
        opt.whiteness_lags = static_cast<std::size_t>(integer(a, it.value(), 1, 100000));
      } else if (a == "--json") {
        json = it.value();
      } else if (a == "--plots") {
        plots = it.value();
      } else if (!a.empty() && a[0] == '-') {
        throw UsageError("unknown option '" + a + "'");
      } else if (model_file.empty()) {
        model_file = a;
      } else if (csv.empty()) {
        csv = a;
      } else {
        throw UsageError("unexpected argument '" + a + "'");
      }
    }
    if (model_file.empty()) throw UsageError("missing <model.yaml>");
    if (csv.empty()) throw UsageError("missing <data.csv>");
  } catch (const UsageError& e) {
    std::cerr << "rig validate: " << e.what() << "\n" << kValidateUsage;
    return kExitUsage;
  }
  if (!plots.empty()) ident::require_gnuplot();

  const DerivativeModel model = load_model(model_file);
  const Vehicle vehicle = load_vehicle(vehicle_file.empty() ? model.vehicle_file : vehicle_file);
  std::string damage;
  const ident::FlightData data = ident::read_flight_data(csv, log_options, &damage);
  warn_damage("rig validate", csv, damage);
  if (closed_loop) {
    ident::ClosedLoopOptions cl;
    cl.controller = load_controller_config(controller_file);
    cl.gain_set = gains;
    cl.interpolation = opt.processing.interpolation;
    const ident::ClosedLoopResult r = ident::validate_closed_loop(data, model, vehicle, cl);
    std::vector<std::string> pngs;
    if (!plots.empty()) pngs = ident::plot_closed_loop(r, plots);
    JsonWriter w;
    w.begin_object();
    w.key("source").value(r.source).key("model").value(model.name).key("gain_set").value(r.gain_set);
    w.key("rate_hz").value(r.rate_hz).key("samples").value(static_cast<long long>(r.t_s.size()));
    w.key("closed_loop").begin_object();
    if (json != "-") {
      std::printf("closed-loop validation of %s on %s (gains %s, %lld samples at %.0f Hz)\n", model.name.c_str(),
                  r.source.c_str(), r.gain_set.c_str(), static_cast<long long>(r.t_s.size()), r.rate_hz);
      std::printf("  %-8s %8s %8s %12s %12s %10s\n", "output", "r_xy", "R2", "RMSE", "range", "RMSE[%rng]");
    }
    for (const char* name : {"p", "v", "phi", "delta_f"}) {
      const ident::FitMetrics& f = r.fits.at(name);
      if (json != "-") {
        std::printf("  %-8s %8.3f %8.3f %12.4g %12.4g %10.2f\n", name, f.rxy, f.r2, f.rmse, f.range, f.rmse_pct_range);
      }
      w.key(name).begin_object();
      w.key("rxy").value(f.rxy).key("r2").value(f.r2).key("rmse").value(f.rmse);
      w.key("range").value(f.range).key("rmse_pct_range").value(f.rmse_pct_range);
      w.end_object();
    }
    w.end_object();
    if (!pngs.empty()) w.key("plots").array(pngs);
    w.end_object();
    if (json != "-") {
      for (const auto& p : pngs) std::cout << "plot " << p << "\n";
    }
    if (!json.empty()) write_json(json, w.str());
    return 0;
  }
  const ident::ValidationResult result = ident::validate_open_loop(data, model, vehicle, opt);
  std::vector<std::string> pngs;
  if (!plots.empty()) pngs = ident::plot_validation(result, plots);
  if (json != "-") {
    std::cout << ident::validation_text(result);
    for (const auto& p : pngs) std::cout << "plot " << p << "\n";
  }
  if (!json.empty()) write_json(json, ident::validation_json(result, pngs));
  return 0;
}

namespace {

constexpr const char* kExportUsage =
    "usage: rig export <log.lcmlog> --csv <out.csv> [--rate HZ] [--interpolation cubic|linear]\n"
    "                  [--states auto|estimate|truth] [--salvage] [--json FILE|-]\n"
    "  Writes a rig log as identification CSV (the format rig identify reads), every channel\n"
    "  resampled onto one grid (default 512 Hz, cubic interpolation). States come from the estimator\n"
    "  (ESTIMATE) when the log has it, else from the plant's truth; inputs from ACTUATOR_FB;\n"
    "  phi_sp from ATTITUDE_SP. A damaged log is an error naming the byte offset and the event;\n"
    "  --salvage reads the events before the damage and says how much was left.\n"
    "  --json writes what was exported (samples, rate, columns, state source, damage) as JSON;\n"
    "  '-' writes it to stdout.\n";

}  // namespace

int run_export_command(const std::vector<std::string>& args) {
  std::string log, csv;
  double rate_hz = 512.0;
  ident::StateSource source = ident::StateSource::kAuto;
  ident::LogReadOptions log_options;
  ident::Interpolation interpolation = ident::Interpolation::kCubic;
  std::string json;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    const bool has_value = i + 1 < args.size();
    if (a == "--help" || a == "-h") {
      std::cout << kExportUsage;
      return 0;
    } else if (a == "--json" && has_value) {
      json = args[++i];
    } else if (a == "--interpolation" && has_value) {
      const std::string v = args[++i];
      if (v != "cubic" && v != "linear") {
        std::cerr << "rig export: --interpolation must be cubic or linear, got '" << v << "'\n";
        return kExitUsage;
      }
      interpolation = ident::interpolation_from_string(v);
    } else if (a == "--csv" && has_value) {
      csv = args[++i];
    } else if (a == "--rate" && has_value) {
      const std::string v = args[++i];
      char* end = nullptr;
      rate_hz = std::strtod(v.c_str(), &end);
      if (end == v.c_str() || *end != '\0' || !(rate_hz > 0.0) || rate_hz > 100000.0) {
        std::cerr << "rig export: --rate needs a positive number of Hz, got '" << v << "'\n";
        return kExitUsage;
      }
    } else if (a == "--states" && has_value) {
      const std::string v = args[++i];
      if (v == "auto") source = ident::StateSource::kAuto;
      else if (v == "estimate") source = ident::StateSource::kEstimate;
      else if (v == "truth") source = ident::StateSource::kTruth;
      else {
        std::cerr << "rig export: --states must be auto, estimate or truth, got '" << v << "'\n";
        return kExitUsage;
      }
    } else if (a == "--salvage") {
      log_options.salvage = true;
    } else if (!a.empty() && a[0] != '-' && log.empty()) {
      log = a;
    } else {
      std::cerr << "rig export: unexpected argument '" << a << "'\n" << kExportUsage;
      return kExitUsage;
    }
  }
  if (log.empty() || csv.empty()) {
    std::cerr << "rig export: needs <log.lcmlog> and --csv <out.csv>\n" << kExportUsage;
    return kExitUsage;
  }
  const ident::RigLogData data = ident::read_rig_log(log, source, log_options);
  warn_damage("rig export", log, data.damage);
  const ident::UniformData grid = ident::resample_uniform(data.measured, rate_hz, interpolation);
  ident::FlightData out;
  out.source = log;
  const std::vector<double> t(grid.t_s.data(), grid.t_s.data() + grid.t_s.size());
  for (const auto& [name, values] : grid.signals) {
    if (!ident::is_known_channel(name)) continue;
    out.channels[name] = ident::Channel{t, std::vector<double>(values.data(), values.data() + values.size())};
  }
  ident::write_flight_csv(out, csv);
  (json == "-" ? std::cerr : std::cout) << "rig export: " << grid.size() << " samples at " << rate_hz
                                        << " Hz (states from " << data.state_source << ") -> " << csv << "\n";
  if (!json.empty()) {
    JsonWriter w;
    w.begin_object();
    w.key("log").value(log).key("csv").value(csv).key("samples").value(static_cast<long long>(grid.size()));
    w.key("rate_hz").value(rate_hz).key("interpolation").value(ident::to_string(interpolation));
    w.key("state_source").value(data.state_source).key("damage").value(data.damage);
    w.key("columns").begin_array();
    for (const auto& [name, channel] : out.channels) w.value(name);
    w.end_array();
    w.end_object();
    write_json(json, w.str());
  }
  return 0;
}

}  // namespace nimble::cli
