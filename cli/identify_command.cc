/// `rig identify` and `rig validate`: identification of the lateral model from
/// CSV flight data and open-loop validation of a model on CSV flight data.

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "cmdline/args.h"
#include "core/effects.h"
#include "cli/commands.h"
#include "core/model.h"
#include "core/vehicle.h"
#include "estimator/sensing_config.h"
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
#include "mcap/log_export.h"

namespace nimble::cli {
namespace {

ident::TimeRange time_range(const std::string& text) {
  const std::size_t colon = text.find(':');
  double start = NAN, end = NAN;
  if (colon == std::string::npos || !CLI::detail::lexical_cast(text.substr(0, colon), start) ||
      !CLI::detail::lexical_cast(text.substr(colon + 1), end) || !std::isfinite(start) || !std::isfinite(end)) {
    throw std::invalid_argument("'" + text + "' is not START:END in seconds");
  }
  if (!(end > start)) throw std::invalid_argument("'" + text + "': END must be after START");
  return {start, end};
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
  if (out.empty()) throw std::invalid_argument("empty list");
  return out;
}

/// --rate, --cutoff, --order, --interpolation: the processing every analysis command shares.
void add_processing(CommandLine& cl, ident::ProcessingOptions& p) {
  cl->add_option("--rate", p.rate_hz, "resampling rate [Hz]")
      ->check(kFinite & CLI::Range(1e-3, 1e6))
      ->capture_default_str()
      ->type_name("HZ");
  cl->add_option("--cutoff", p.cutoff_hz, "low-pass cut-off [Hz]")
      ->check(kFinite & CLI::PositiveNumber)
      ->capture_default_str()
      ->type_name("HZ");
  cl->add_option("--order", p.filter_order, "Butterworth order, 0 = no low-pass")
      ->check(CLI::Range(0, 40))
      ->capture_default_str()
      ->type_name("N");
  each_value(cl->add_option("--interpolation", "resampling of every channel: cubic (default) or linear")
                 ->type_name("MODE")
                 ->check(CLI::IsMember({"cubic", "linear"})),
             [&p](const std::string& v) { p.interpolation = ident::interpolation_from_string(v); });
}

/// --salvage: read a damaged log up to the damage.
void add_salvage(CommandLine& cl, ident::LogReadOptions& o) {
  cl->add_flag("--salvage", o.salvage, "a damaged rig log: read the events before the damage and say what was left");
}

/// --states SOURCE and --sensing FILE: where a rig log's states come from, and the sensing the
/// smoother's filter is matched to.
void add_states(CommandLine& cl, ident::LogReadOptions& o, std::string& sensing_file) {
  each_value(cl->add_option("--states", "rig log: where the states come from: auto (the estimator's if the log has "
                                        "them, else the truth), estimate, truth, or smoothed (made offline from the "
                                        "log's IMU and motion capture by the fixed-interval smoother, as the thesis's "
                                        "identification data were)")
                 ->type_name("SOURCE")
                 ->check(CLI::IsMember({"auto", "estimate", "truth", "smoothed"})),
             [&o](const std::string& v) {
               o.states = v == "estimate"   ? ident::StateSource::kEstimate
                          : v == "truth"    ? ident::StateSource::kTruth
                          : v == "smoothed" ? ident::StateSource::kSmoothed
                                            : ident::StateSource::kAuto;
             });
  cl->add_option("--sensing", sensing_file,
                 "--states smoothed: the sensing the flight flew with (its IMU, motion capture and EKF; default "
                 "rig_configs/sensing/default_sensing.yaml)")
      ->type_name("FILE");
}

/// The smoother's model from --sensing (or the default sensing file).
void apply_sensing(ident::LogReadOptions& o, const std::string& sensing_file) {
  if (o.states != ident::StateSource::kSmoothed) return;
  const SensingConfig sensing = load_sensing_config(sensing_file.empty() ? NIMBLE_DEFAULT_SENSING : sensing_file);
  o.smoothing.ekf = smoother_ekf_config(sensing);
  o.smoothing.differentiator = sensing.velocity_differentiator;
}

/// --vehicle FILE.
void add_vehicle(CommandLine& cl, std::string& file, const std::string& default_text) {
  cl->add_option("--vehicle", file, "the vehicle (default " + default_text + ")")->type_name("FILE");
}

/// Says on stderr what a salvaged read left out.
void warn_damage(const char* command, const std::string& file, const std::string& damage) {
  if (!damage.empty()) std::cerr << command << ": warning: " << file << ": " << damage << "\n";
}

/// Counts the undecodable messages a log reader passes over (the channels it does not read), as
/// the MCAP export counts what it leaves out: `o.other_event` feeds `count`.
void count_undecodable(ident::LogReadOptions& o, mcap::UndecodableCount& count) {
  o.other_event = [&count](const ident::LogEventRecord& e) { count.add(e); };
}

/// Says on stderr which undecodable messages a read left out, by channel and count.
void warn_undecodable(const char* command, const std::string& file, const mcap::UndecodableCount& count) {
  const std::string text = mcap::undecodable_text(count.by_channel());
  if (!text.empty()) std::cerr << command << ": warning: " << file << ": " << text << "\n";
}

/// The undecodable messages by channel as a --json object.
void undecodable_json(JsonWriter& w, const std::map<std::string, uint64_t>& by_channel) {
  w.key("undecodable_channels").begin_object();
  for (const auto& [name, n] : by_channel) w.key(name).value(static_cast<long long>(n));
  w.end_object();
}

/// The --json report of an MCAP export.
std::string export_json(const mcap::ExportStats& s) {
  auto n = [](uint64_t v) { return static_cast<long long>(v); };
  JsonWriter w;
  w.begin_object();
  w.key("log").value(s.log).key("out").value(s.out).key("format").value("mcap");
  w.key("compression").value(mcap::to_string(s.compression));
  w.key("events").value(n(s.events)).key("messages").value(n(s.messages));
  w.key("mcap_channels").value(n(s.mcap_channels));
  w.key("undecodable").value(n(s.undecodable)).key("unknown_channel_events").value(n(s.unknown_events));
  undecodable_json(w, mcap::undecodable_by_channel(s));
  w.key("start_time_ns").value(n(s.start_time_ns)).key("end_time_ns").value(n(s.end_time_ns));
  w.key("bytes_in").value(n(s.bytes_in)).key("bytes_out").value(n(s.bytes_out));
  w.key("seconds").value(s.seconds).key("damage").value(s.damage);
  w.key("channels").begin_object();
  for (const auto& kv : s.channels) {
    w.key(kv.first).begin_object();
    w.key("type").value(kv.second.type).key("events").value(n(kv.second.events));
    w.key("json").value(n(kv.second.json)).key("undecodable").value(n(kv.second.undecodable));
    w.key("raw").value(n(kv.second.raw));
    w.end_object();
  }
  w.end_object();
  w.key("unknown_channels").begin_array();
  for (const auto& c : s.unknown_channels) w.value(c);
  w.end_array();
  w.end_object();
  return w.str();
}

/// `rig export --format mcap`: the log as MCAP, the one-line summary, the --json report.
int export_mcap(const std::string& log, const std::string& out, const mcap::ExportOptions& options,
                const std::string& json) {
  const mcap::ExportStats stats = mcap::export_log_to_mcap(log, out, options);
  warn_damage("rig export", log, stats.damage);
  (json == "-" ? std::cerr : std::cout) << "rig export: " << mcap::summary_line(stats) << "\n";
  if (!json.empty()) write_json(json, export_json(stats));
  return 0;
}

}  // namespace

int run_identify_command(const std::vector<std::string>& args) {
  std::string csv, vehicle_file, json, model_out, plots;
  ident::IdentOptions opt;
  ident::LogReadOptions log_options;
  CommandLine cl("rig identify",
                 "Identifies the dimensional stability and control derivatives of the lateral model from\n"
                 "flight data, a CSV file or a rig log (read by its content; equation error, thesis\n"
                 "Section IV), prints the parameters with their standard deviations, flagged correlations,\n"
                 "accuracy metrics, residual whiteness, eigenvalues and modes, and state PSDs.");
  cl->add_option("data", csv, "flight data: identification CSV or a rig log (.lcmlog)")->required();
  each_value(cl->add_option("--structure", "model structure: lateral3 (default) or lateral4")
                 ->type_name("NAME")
                 ->check(CLI::IsMember({"lateral3", "lateral4"})),
             [&opt](const std::string& v) { opt.structure = structure_from_string(v); });
  each_value(cl->add_option("--method", "estimator: wls (default) or ols")->type_name("NAME")->check(CLI::IsMember({"ols", "wls"})),
             [&opt](const std::string& v) { opt.method = ident::method_from_string(v); });
  add_vehicle(cl, vehicle_file, "rig_configs/vehicles/nimble_no_wifi.yaml");
  add_salvage(cl, log_options);
  std::string sensing_file;
  add_states(cl, log_options, sensing_file);
  each_value(cl->add_option("--inputs", "comma-separated inputs (default delta_f,delta_t plus delta_d, delta_w "
                                        "when the data has them)")
                 ->type_name("LIST"),
             [&opt](const std::string& v) { opt.inputs = split_list(v); });
  cl->add_option("--w0", opt.trim.w0_mps, "trim vertical velocity of Eq 21 [m/s]")
      ->check(kFinite)
      ->capture_default_str()
      ->type_name("M_PER_S");
  cl->add_option("--u0", opt.trim.u0_mps, "trim forward velocity, lateral4 [m/s]")
      ->check(kFinite)
      ->capture_default_str()
      ->type_name("M_PER_S");
  add_processing(cl, opt.processing);
  cl->add_option("--wls-window", opt.wls_window_s, "WLS residual-covariance window [s]")
      ->check(kFinite & CLI::PositiveNumber)
      ->capture_default_str()
      ->type_name("S");
  cl->add_option("--lags", opt.whiteness_lags, "whiteness lags")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str()
      ->type_name("N");
  each_value(cl->add_option("--hover", "a hover PSD segment [s] (repeatable; default from |phi_sp|)")
                 ->type_name("A:B")
                 ->allow_extra_args(false)
                 ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll),
             [&opt](const std::string& v) { opt.segments.hover.push_back(time_range(v)); });
  each_value(cl->add_option("--manoeuvre", "a manoeuvre PSD segment [s] (repeatable; default from |phi_sp|)")
                 ->type_name("A:B")
                 ->allow_extra_args(false)
                 ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll),
             [&opt](const std::string& v) { opt.segments.manoeuvre.push_back(time_range(v)); });
  std::string terms_file;
  cl->add_option("--terms", terms_file,
                 "fit the generic terms of this model file's terms: section alongside the derivatives (their "
                 "coefficients are regressors, named <equation>:<expression>; docs/models.md, \"Terms\")")
      ->type_name("MODEL");
  cl.add_json(json, "the report");
  cl->add_option("--model-out", model_out, "write the identified model as a model YAML file")->type_name("FILE");
  cl.add_plots(plots, "");
  if (const auto done = cl.parse(args)) return *done;
  if (!terms_file.empty()) opt.terms = load_model(terms_file).terms;
  if (!plots.empty()) ident::require_gnuplot();  // fail before the work, not after

  if (vehicle_file.empty()) vehicle_file = ident::default_vehicle_file();
  const Vehicle vehicle = load_vehicle(vehicle_file);
  if (log_options.states != ident::StateSource::kAuto && !ident::is_lcm_log(csv)) {
    return cl.fail("--states: " + csv + " is not a rig log; a CSV file carries its own states");
  }
  try {
    apply_sensing(log_options, sensing_file);
  } catch (const ConfigError& e) {
    std::cerr << "rig identify: --sensing: " << e.what() << "\n";
    return kExitUsage;
  }
  std::string damage;
  mcap::UndecodableCount undecodable;
  count_undecodable(log_options, undecodable);
  const ident::FlightData data = ident::read_flight_data(csv, log_options, &damage);
  warn_damage("rig identify", csv, damage);
  warn_undecodable("rig identify", csv, undecodable);
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
  if (std::find(args.begin(), args.end(), "--power") != args.end()) return run_discrepancy_power_command(args);
  std::vector<std::string> data_files;
  std::string model_file, vehicle_file, json, model_out, report, gains;
  ident::DiscrepancyOptions opt;
  ident::LogReadOptions log_options;
  CommandLine cl("rig discrepancy",
                 "Where the model and the measured data disagree, which physical effect the model is\n"
                 "missing (by name), the model refit with it, and the gap before and after on data the fit\n"
                 "did not see (ident/README.md, \"Discrepancy workflow\").");
  cl->footer("With --power, no data: how long to fly to name an effect, by simulated flights of a scenario\n"
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
  add_vehicle(cl, vehicle_file, "the model's");
  each_value(cl->add_option("--candidates")
                 ->description("comma-separated candidate effects to try (default: all the data supports): " +
                               effect_name_list())
                 ->type_name("LIST"),
             [&opt](const std::string& v) { opt.candidates = split_list(v); });
  cl->add_option("--folds", opt.folds, "held-out cross-validation folds")
      ->check(CLI::Range(4, 100))
      ->capture_default_str()
      ->type_name("K");
  cl->add_option("--partial-f", opt.partial_f, "significance rule (SIDPAC)")
      ->check(kFinite & CLI::PositiveNumber)
      ->capture_default_str()
      ->type_name("F");
  cl->add_option("--delay-max", opt.delay_max_s, "actuator_delay scan limit [s], in (0, 1]")
      ->check(kFinite & CLI::Range(1e-9, 1.0))
      ->capture_default_str()
      ->type_name("S");
  cl->add_option("--command-latency", opt.command_latency_s,
                 "known latency of the flap command path [s], in [0, 0.1], not named as a delay (default: one "
                 "controller tick of the rig)")
      ->check(kFinite & CLI::Range(0.0, 0.1))
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
  if (!report.empty()) ident::require_gnuplot();  // fail before the work, not after
  const DerivativeModel model = load_model(model_file);
  const std::string vfile = vehicle_file.empty() ? model.vehicle_file : vehicle_file;
  const Vehicle vehicle = load_vehicle(vfile);
  std::vector<ident::FlightData> flights;
  for (const auto& data_file : data_files) {
    if (ident::is_lcm_log(data_file)) {
      mcap::UndecodableCount undecodable;
      count_undecodable(log_options, undecodable);
      ident::RigLogData log = ident::read_rig_log(data_file, ident::StateSource::kAuto, log_options);
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
  const ident::FlightData& data = flights.front();
  // Closed loop before and after, as rig validate --closed-loop.
  if (flights.size() > 1) {
    result.closed_loop_note = "not flown for pooled flights: run rig discrepancy on one flight for it";
  } else if (!data.has("phi_sp")) {
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
  if (!json.empty()) write_json(json, ident::discrepancy_json(result));
  return 0;
}

int run_validate_command(const std::vector<std::string>& args) {
  std::string model_file, csv, vehicle_file, json, plots;
  std::string gains, controller_file = NIMBLE_DEFAULT_CONTROLLER;
  bool closed_loop = false;
  ident::ValidationOptions opt;
  ident::LogReadOptions log_options;
  CommandLine cl("rig validate",
                 "Open-loop validation: the state derivatives predicted by the model from the measured\n"
                 "states and inputs against the measured ones (thesis Tables 7-8).");
  cl->add_option("model", model_file, "the model file")->required();
  cl->add_option("data", csv, "flight data: identification CSV or a rig log (.lcmlog)")->required();
  add_vehicle(cl, vehicle_file, "the model's");
  add_salvage(cl, log_options);
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
  cl->add_option("--controller", controller_file, "controller configuration")
      ->capture_default_str()
      ->type_name("FILE");
  if (const auto done = cl.parse(args)) return *done;
  if (!plots.empty()) ident::require_gnuplot();

  const DerivativeModel model = load_model(model_file);
  const Vehicle vehicle = load_vehicle(vehicle_file.empty() ? model.vehicle_file : vehicle_file);
  std::string damage;
  ident::FlightData data;
  mcap::UndecodableCount undecodable;
  count_undecodable(log_options, undecodable);
  if (ident::is_lcm_log(csv)) {
    ident::RigLogData log = ident::read_rig_log(csv, ident::StateSource::kAuto, log_options);
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

int run_export_command(const std::vector<std::string>& args) {
  std::string log, csv, out_file, format, compression = "zstd", json;
  bool raw = false;
  double rate_hz = 512.0;
  ident::StateSource source = ident::StateSource::kAuto;
  ident::LogReadOptions log_options;
  ident::Interpolation interpolation = ident::Interpolation::kCubic;
  CommandLine cl("rig export",
                 "Writes a rig log as identification CSV (the format rig identify reads), every channel\n"
                 "resampled onto one grid, or as MCAP for Foxglove, Lichtblick and PlotJuggler.\n"
                 "CSV: states come from the estimator (ESTIMATE) when the log has it, else from the plant's\n"
                 "truth; inputs from ACTUATOR_FB; phi_sp from ATTITUDE_SP. MCAP (docs/viewers.md): one\n"
                 "channel per LCM channel, JSON messages with their JSON Schema, log time = rig time.\n"
                 "A damaged log is an error naming the byte offset and the event; a message that is not one of\n"
                 "its channel's type is left out and named, by channel and count (CSV: those of the channels it\n"
                 "does not read; a damaged message on a channel it reads is an error naming the event).");
  cl->add_option("log", log, "the rig log (.lcmlog)")->required();
  cl->add_option("--format", format, "csv or mcap (default: mcap when --out ends in .mcap, else csv)")
      ->check(CLI::IsMember({"csv", "mcap"}))
      ->type_name("FORMAT");
  cl->add_option("--csv", csv, "the CSV file to write (--format csv)")->type_name("FILE");
  cl->add_option("--out", out_file, "the file to write (either format)")->type_name("FILE");
  auto* rate = cl->add_option("--rate", rate_hz, "CSV: the grid's rate [Hz]")
                   ->check(kFinite & CLI::Range(1e-3, 100000.0))
                   ->capture_default_str()
                   ->type_name("HZ");
  auto* interp = each_value(
      cl->add_option("--interpolation", "CSV: cubic (default) or linear")->type_name("MODE")
          ->check(CLI::IsMember({"cubic", "linear"})),
      [&interpolation](const std::string& v) { interpolation = ident::interpolation_from_string(v); });
  auto* states = each_value(cl->add_option("--states", "CSV: where the states come from: auto (default), estimate "
                                                       "or truth")
                                ->type_name("SOURCE")
                                ->check(CLI::IsMember({"auto", "estimate", "truth"})),
                            [&source](const std::string& v) {
                              source = v == "estimate" ? ident::StateSource::kEstimate
                                       : v == "truth"  ? ident::StateSource::kTruth
                                                       : ident::StateSource::kAuto;
                            });
  auto* comp = cl->add_option("--compression", compression, "MCAP: chunk compression, zstd or none")
                   ->check(CLI::IsMember({"zstd", "none"}))
                   ->capture_default_str()
                   ->type_name("C");
  auto* raw_flag = cl->add_flag("--raw", raw, "MCAP: also each channel's LCM bytes as <CHANNEL>/lcm");
  add_salvage(cl, log_options);
  cl.add_json(json,
              "what was exported (CSV: samples, rate, columns, state source; MCAP: messages per channel; both: "
              "undecodable messages by channel, damage)");
  if (const auto done = cl.parse(args)) return *done;
  if (format.empty()) {
    const bool mcap_name = out_file.size() >= 5 && out_file.compare(out_file.size() - 5, 5, ".mcap") == 0;
    format = csv.empty() && mcap_name ? "mcap" : "csv";
  }
  if (format == "mcap") {
    for (const CLI::Option* o : {rate, interp, states}) {
      if (o->count() > 0) return cl.fail(o->get_name() + " is for --format csv");
    }
    if (!csv.empty()) return cl.fail("--csv is for --format csv; the MCAP file is --out");
    if (out_file.empty()) return cl.fail("--format mcap needs --out FILE");
    mcap::ExportOptions options;
    options.compression = mcap::compression_from_string(compression);
    options.raw = raw;
    options.salvage = log_options.salvage;
    return export_mcap(log, out_file, options, json);
  }
  for (const CLI::Option* o : {comp, raw_flag}) {
    if (o->count() > 0) return cl.fail(o->get_name() + " is for --format mcap");
  }
  if (!csv.empty() && !out_file.empty()) return cl.fail("--csv and --out both name the output: give one");
  if (csv.empty()) csv = out_file;
  if (csv.empty()) return cl.fail("--csv FILE (or --out FILE.mcap for MCAP) is required");
  mcap::UndecodableCount undecodable;
  count_undecodable(log_options, undecodable);
  const ident::RigLogData data = ident::read_rig_log(log, source, log_options);
  warn_damage("rig export", log, data.damage);
  warn_undecodable("rig export", log, undecodable);
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
    w.key("undecodable").value(static_cast<long long>(undecodable.total()));
    undecodable_json(w, undecodable.by_channel());
    w.key("columns").begin_array();
    for (const auto& [name, channel] : out.channels) w.value(name);
    w.end_array();
    w.end_object();
    write_json(json, w.str());
  }
  return 0;
}

}  // namespace nimble::cli
