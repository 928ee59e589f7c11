/// identify, validate, discrepancy and export_mcap of nimble_rig._rig: the library code of
/// `rig identify`, `rig validate`, `rig discrepancy` and `rig export --format mcap`, on a rig log,
/// a CSV file or a dict of numpy arrays; each returns the command's --json content as a dict, with
/// the signals behind it as arrays.

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "controller/attitude_controller.h"
#include "core/data_bounds.h"
#include "core/json_line.h"
#include "core/model.h"
#include "core/terms.h"
#include "core/vehicle.h"
#include "estimator/sensing_config.h"
#include "ident/closed_loop.h"
#include "discrepancy/closed_loop_compare.h"
#include "discrepancy/discrepancy.h"
#include "ident/flight_sensing.h"
#include "ident/identify.h"
#include "ident/model_writer.h"
#include "ident/report.h"
#include "ident/validate.h"
#include "mcap/log_export.h"
#include "python/py_module.h"

namespace nimble::python {

namespace {

bool is_path(const py::handle& data) { return py::isinstance<py::str>(data) || py::hasattr(data, "__fspath__"); }

/// A dict of arrays on one time base 't' as flight data, checked as ident::flight_data_from_columns
/// checks a user's columns.
ident::FlightData dict_data(const py::dict& d) {
  if (!d.contains("t")) throw std::invalid_argument("data: the dict has no 't' (time [s]) array");
  using Doubles = py::array_t<double, py::array::c_style | py::array::forcecast>;
  const auto column = [](const py::handle& value, const std::string& name) {
    const Doubles a = Doubles::ensure(value);
    if (!a || a.ndim() != 1)
      throw std::invalid_argument("data: '" + name + "' is not a one-dimensional array of numbers");
    return std::vector<double>(a.data(), a.data() + a.size());
  };
  std::map<std::string, std::vector<double>> columns;
  for (const auto& [key, value] : d) {
    const std::string name = key.cast<std::string>();
    if (name != "t") columns[name] = column(value, name);
  }
  return ident::flight_data_from_columns("data (dict of arrays)", column(d["t"], "t"), std::move(columns));
}

/// The processing options given (None: the commands' defaults).
ident::ProcessingOptions processing_of(std::optional<double> rate_hz, std::optional<double> cutoff_hz,
                                       std::optional<int> order, const std::string& interpolation) {
  // The command line's ranges (--rate, --cutoff, --order: cli/log_input.cc add_processing).
  const auto text = [](double v) { return std::isnan(v) ? std::string("nan") : std::to_string(v); };
  if (rate_hz && !(std::isfinite(*rate_hz) && *rate_hz >= 1e-3 && *rate_hz <= 1e6)) {
    throw py::value_error("rate_hz must be finite and in [0.001, 1e6] Hz, not " + text(*rate_hz));
  }
  if (cutoff_hz && !(std::isfinite(*cutoff_hz) && *cutoff_hz > 0.0)) {
    throw py::value_error("cutoff_hz must be finite and > 0 Hz, not " + text(*cutoff_hz));
  }
  if (order && (*order < 0 || *order > 40)) {
    throw py::value_error("order must be in [0, 40] (0: no low-pass), not " + std::to_string(*order));
  }
  ident::ProcessingOptions p;
  if (rate_hz) p.rate_hz = *rate_hz;
  if (cutoff_hz) p.cutoff_hz = *cutoff_hz;
  if (order) p.filter_order = *order;
  p.interpolation = ident::interpolation_from_string(interpolation);
  return p;
}

/// The vehicle of an analysis: `file`, else `fallback`.
Vehicle vehicle_of(const std::optional<std::string>& file, const std::string& fallback) {
  return load_vehicle(file.value_or(fallback));
}

/// Every signal of `u` (with its time base as "t") as arrays.
py::dict signals_of(const ident::UniformData& u) {
  py::dict out;
  out["t"] = array_of(u.t_s);
  for (const auto& [name, v] : u.signals) out[name.c_str()] = array_of(v);
  return out;
}

/// The generic terms of identify(terms=): a model file's terms: section (a path), or a list of
/// "EQUATION: EXPRESSION" texts (as rig discrepancy --test-term).
std::vector<Term> terms_of(const py::object& terms) {
  if (terms.is_none()) return {};
  if (is_path(terms)) return load_model(path_text(terms)).terms;
  std::vector<Term> out;
  for (const auto& item : terms) {
    if (!py::isinstance<py::str>(item)) {
      throw py::value_error("terms: a model file's path or a list of 'EQUATION: EXPRESSION' texts, not " +
                            py::str(py::type::of(item)).cast<std::string>());
    }
    const std::string v = item.cast<std::string>();
    const auto colon = v.find(':');
    if (colon == std::string::npos)
      throw py::value_error("terms: '" + v + "' is not 'EQUATION: EXPRESSION' (e.g. 'Y: v*abs(v)')");
    std::string eq = v.substr(0, colon);
    eq.erase(0, eq.find_first_not_of(' '));
    eq.erase(eq.find_last_not_of(' ') + 1);
    out.push_back(Term{eq, TermExpression::parse(v.substr(colon + 1)), 0.0, "identify(terms=)"});
  }
  return out;
}

/// Time ranges [(start, end), ...] of identify(hover=, manoeuvre=).
std::vector<ident::TimeRange> ranges_of(const std::optional<std::vector<std::pair<double, double>>>& r,
                                        const char* what) {
  std::vector<ident::TimeRange> out;
  if (!r) return out;
  for (const auto& [a, b] : *r) {
    if (!(std::isfinite(a) && std::isfinite(b) && b > a)) {
      throw py::value_error(std::string(what) + ": (" + std::to_string(a) + ", " + std::to_string(b) +
                            ") is not a time range (start < end, finite)");
    }
    out.push_back({a, b});
  }
  return out;
}

/// A finite value of a keyword, or a ValueError naming it.
double finite_arg(double v, const char* name) {
  if (!std::isfinite(v)) throw py::value_error(std::string(name) + " must be finite");
  return v;
}

py::dict identify(const py::object& data, const std::string& structure, const std::string& method,
                  const std::optional<std::vector<std::string>>& inputs, const std::optional<std::string>& vehicle,
                  const std::optional<std::string>& model_out, const std::string& states,
                  const std::optional<std::string>& sensing, bool salvage, std::optional<double> rate_hz,
                  std::optional<double> cutoff_hz, std::optional<int> order, const std::string& interpolation,
                  double w0, double u0, double theta0, double phi0, const py::object& terms,
                  const std::optional<std::vector<std::pair<double, double>>>& hover,
                  const std::optional<std::vector<std::pair<double, double>>>& manoeuvre, double oe_segment_s) {
  ident::IdentOptions o;
  o.structure = structure_from_string(structure);
  o.method = ident::method_from_string(method);
  if (inputs) o.inputs = *inputs;
  o.processing = processing_of(rate_hz, cutoff_hz, order, interpolation);
  // The command line's --w0, --u0 (and the trim attitude the model files carry), --terms,
  // --hover, --manoeuvre and --oe-segment.
  o.trim.w0_mps = finite_arg(w0, "w0");
  o.trim.u0_mps = finite_arg(u0, "u0");
  o.trim.theta0_rad = finite_arg(theta0, "theta0");
  o.trim.phi0_rad = finite_arg(phi0, "phi0");
  o.terms = terms_of(terms);
  o.segments.hover = ranges_of(hover, "hover");
  o.segments.manoeuvre = ranges_of(manoeuvre, "manoeuvre");
  if (!(std::isfinite(oe_segment_s) && oe_segment_s > 0.0)) throw py::value_error("oe_segment_s must be > 0 s");
  o.output_error.segment_s = oe_segment_s;
  const std::string vehicle_file = vehicle.value_or(ident::default_vehicle_file());
  const Vehicle v = load_vehicle(vehicle_file);
  const DataInput in = flight_data_of(data, states, sensing.value_or(""), salvage, &v);
  ident::IdentResult r;
  {
    py::gil_scoped_release free;
    r = ident::identify(in.data, v, vehicle_file, o);
  }
  if (model_out) {
    ident::write_model_yaml(
        r.model, *model_out,
        {"Identified by nimble_rig.identify from " + in.data.source + ".",
         "Structure " + to_string(o.structure) + ", " + ident::to_string(o.method) +
             "; published: holds the eigenvalues and the standard deviations of this identification",
         "(white-residual formula)."});
  }
  py::dict out = json_value(ident::identification_json(r, model_out.value_or(""), {}));
  out["eigenvalues"] = complex_array_of(r.eigenvalues);  // [1/s], as numpy.linalg.eigvals gives them
  out["signals"] = signals_of(r.data.filtered);
  py::list equations;
  for (const ident::EquationResult& e : r.regression.equations) {
    py::dict q;
    q["name"] = e.equation.name;
    q["dependent"] = e.equation.dependent;
    q["scale"] = e.equation.scale;
    q["regressors"] = e.equation.regressors;
    q["parameters"] = e.equation.parameters;
    q["y"] = array_of(e.y);
    q["theta"] = array_of(e.theta);
    equations.append(q);
  }
  out["equations"] = equations;
  return out;
}

py::dict validate(const py::object& model_path, const py::object& data, bool closed_loop,
                  const std::optional<std::string>& gains, const std::optional<std::string>& controller,
                  const std::optional<std::string>& vehicle, const std::string& states,
                  const std::optional<std::string>& sensing, bool salvage, std::optional<double> rate_hz,
                  std::optional<double> cutoff_hz, std::optional<int> order, const std::string& interpolation) {
  const ModelFile file(model_path);
  const DerivativeModel model = load_model(file.path());
  const Vehicle v = vehicle_of(vehicle, model.vehicle_file);
  const DataInput in = flight_data_of(data, states, sensing.value_or(""), salvage, &v);
  const ident::ProcessingOptions processing = processing_of(rate_hz, cutoff_hz, order, interpolation);
  if (closed_loop) {
    ident::ClosedLoopOptions o;
    o.controller = load_controller_config(controller.value_or(ident::default_controller_file()));
    o.gain_set = gains.value_or(in.gain_set.empty() ? "fast" : in.gain_set);
    o.interpolation = processing.interpolation;
    ident::ClosedLoopResult r;
    {
      py::gil_scoped_release free;
      r = ident::validate_closed_loop(in.data, model, v, o);
    }
    py::dict out = json_value(ident::closed_loop_json(r, {}));
    out["t"] = array_of(r.t_s);
    py::dict measured, simulated;
    for (const auto& [name, x] : r.measured) measured[name.c_str()] = array_of(x);
    for (const auto& [name, x] : r.simulated) simulated[name.c_str()] = array_of(x);
    out["measured"] = measured;
    out["simulated"] = simulated;
    out["phi_sp"] = array_of(r.phi_sp);
    out["phi_ref"] = array_of(r.phi_ref);
    return out;
  }
  ident::ValidationOptions o;
  o.processing = processing;
  ident::ValidationResult r;
  {
    py::gil_scoped_release free;
    r = ident::validate_open_loop(in.data, model, v, o);
  }
  py::dict out = json_value(ident::validation_json(r, {}));
  out["t"] = array_of(r.data.t_s);
  py::dict measured, predicted;
  for (const ident::OutputFit& f : r.fits) {
    measured[f.output.c_str()] = array_of(f.measured);
    predicted[f.output.c_str()] = array_of(f.estimated);
  }
  out["measured"] = measured;
  out["predicted"] = predicted;
  return out;
}

py::dict discrepancy(const py::object& data, const py::object& model_path,
                     const std::optional<std::vector<std::string>>& candidates, std::optional<std::size_t> folds,
                     std::optional<double> partial_f, std::optional<double> delay_max_s,
                     std::optional<double> command_latency_s, const std::optional<std::string>& gains,
                     const std::optional<std::string>& vehicle, const std::optional<std::string>& model_out,
                     const std::string& states, const std::optional<std::string>& sensing, bool salvage) {
  const ModelFile file(model_path);
  const std::string& model_file = file.path();
  ident::DiscrepancyOptions o;
  if (candidates) o.candidates = *candidates;
  if (folds) o.folds = *folds;
  if (partial_f) o.partial_f = *partial_f;
  if (delay_max_s) o.delay_max_s = *delay_max_s;
  if (command_latency_s) o.command_latency_s = *command_latency_s;
  const DerivativeModel model = load_model(model_file);
  const Vehicle v = vehicle_of(vehicle, model.vehicle_file);
  // One flight, or several of the same vehicle pooled (a list).
  std::vector<ident::FlightData> flights;
  std::string gain_set = gains.value_or("");
  const bool pooled = py::isinstance<py::list>(data) || py::isinstance<py::tuple>(data);
  for (const py::handle item : pooled ? py::iterable(data) : py::iterable(py::make_tuple(data))) {
    DataInput in = flight_data_of(py::reinterpret_borrow<py::object>(item), states, sensing.value_or(""), salvage, &v);
    if (gain_set.empty()) gain_set = in.gain_set;
    flights.push_back(std::move(in.data));
  }
  if (flights.empty()) throw std::invalid_argument("data: an empty list of flights");
  if (gain_set.empty()) gain_set = "fast";
  const ControllerConfig controller = load_controller_config(ident::default_controller_file());
  ident::DiscrepancyResult r;
  {
    py::gil_scoped_release free;
    r = ident::find_discrepancy(flights, model, v, o);
    ident::compare_closed_loop(r, flights, model, v, controller, gain_set);
  }
  if (model_out) {
    ident::write_model_yaml(
        r.augmented_model, *model_out,
        {"Refit by nimble_rig.discrepancy from " + flights.front().source + " on " + model_file + ".",
         "Verdict: " + r.verdict + ". " + r.summary,
         "published.sigma: coloured-residual standard deviations of this refit."});
  }
  return json_value(ident::discrepancy_json(r));
}

/// A Python warning naming what a reader left out beyond the bounds (nothing if none).
void warn_beyond(const std::string& log, const BoundsTally& beyond) {
  if (beyond.empty()) return;
  const std::string text = log + ": left out: " + beyond.text();
  if (PyErr_WarnEx(PyExc_UserWarning, text.c_str(), 1) != 0) throw py::error_already_set();
}

py::dict export_mcap(const py::object& log, const py::object& out, bool raw, const std::string& compression,
                     bool salvage, const std::optional<std::string>& vehicle, bool strict) {
  mcap::ExportOptions o;
  o.raw = raw;
  o.salvage = salvage;
  o.compression = mcap::compression_from_string(compression);
  o.vehicle = load_vehicle(vehicle.value_or(ident::default_vehicle_file()));
  o.strict = strict;
  const std::string log_path = path_text(log), out_path = path_text(out);
  mcap::ExportStats stats;
  {
    py::gil_scoped_release free;
    stats = mcap::export_log_to_mcap(log_path, out_path, o);
  }
  if (stats.beyond) warn_beyond(log_path, *stats.beyond);
  return json_value(mcap::export_json(stats));
}

/// The messages of a log beyond the vehicle's bounds, for read_log: their byte offsets and the tally.
py::dict log_bounds(const py::object& log, const std::optional<std::string>& vehicle, bool salvage) {
  const Vehicle v = load_vehicle(vehicle.value_or(ident::default_vehicle_file()));
  const std::string path = path_text(log);
  std::optional<mcap::LogBounds> found;
  {
    py::gil_scoped_release free;
    found.emplace(mcap::check_log_bounds(path, v, salvage));
  }
  OrderedJson j;
  j["beyond_bounds"] = found->tally.json();
  j["text"] = found->tally.empty() ? std::string() : found->tally.text();
  py::dict out = json_value(json_line(j));
  out["offsets"] = found->offsets;
  return out;
}

}  // namespace

DataInput flight_data_of(const py::object& data, const std::string& states, const std::string& sensing, bool salvage,
                         const Vehicle* vehicle) {
  ident::LogReadOptions o;
  o.salvage = salvage;
  if (vehicle != nullptr) o.refuse_beyond_bounds = *vehicle;
  o.states = ident::state_source_from_name(states);
  DataInput in;
  if (py::hasattr(data, "report") && py::hasattr(data, "channels")) {
    // A Flight: its log, if it was flown with one.
    const py::dict report = data.attr("report").cast<py::dict>();
    const std::string log = report.contains("log") ? report["log"].cast<std::string>() : std::string();
    if (log.empty()) {
      throw std::invalid_argument(
          "data: this Flight was flown without a log; fly(scenario, log='flight.lcmlog') "
          "keeps the record the analyses read");
    }
    return flight_data_of(py::str(log), states, sensing, salvage, vehicle);
  }
  if (py::isinstance<py::dict>(data)) {
    if (o.states != ident::StateSource::kAuto) {
      throw std::invalid_argument("states='" + states +
                                  "': the data is a dict of arrays, which carries its own states");
    }
    in.data = dict_data(data.cast<py::dict>());
    return in;
  }
  if (!is_path(data))
    throw std::invalid_argument("data: a path (rig log or CSV file), a Flight or a dict of arrays, not " +
                                py::str(py::type::of(data)).cast<std::string>());
  const std::string file = path_text(data);
  if (!ident::is_lcm_log(file)) {
    if (o.states != ident::StateSource::kAuto && std::filesystem::exists(file)) {
      throw std::invalid_argument("states='" + states + "': " + file +
                                  " is not a rig log; a CSV file carries its own states");
    }
    in.data = ident::read_flight_data(file, o);
    return in;
  }
  if (o.states == ident::StateSource::kSmoothed) {
    if (sensing.empty()) throw std::invalid_argument("states='smoothed' needs sensing= (the flight's sensing file)");
    o.smoothing = ident::smoothing_options(load_sensing_config(sensing));
  } else if (o.states == ident::StateSource::kSensors && !sensing.empty()) {
    // The flight's velocity differentiator and IMU filtering (without sensing=, the default ones).
    o.smoothing = ident::smoothing_options(load_sensing_config(sensing));
  }
  ident::RigLogData log;
  {
    py::gil_scoped_release free;
    log = ident::read_rig_log(file, o.states, o);
  }
  in.data = std::move(log.measured);
  in.gain_set = log.gain_set;
  return in;
}

void add_analysis(py::module_& m) {
  m.def("identify", &identify, py::arg("data"), py::kw_only(), py::arg("structure") = "lateral3",
        py::arg("method") = "wls", py::arg("inputs") = py::none(), py::arg("vehicle") = py::none(),
        py::arg("model_out") = py::none(), py::arg("states") = "auto", py::arg("sensing") = py::none(),
        py::arg("salvage") = false, py::arg("rate_hz") = py::none(), py::arg("cutoff_hz") = py::none(),
        py::arg("order") = py::none(), py::arg("interpolation") = "cubic", py::arg("w0") = 0.0, py::arg("u0") = 0.0,
        py::arg("theta0") = 0.0, py::arg("phi0") = 0.0, py::arg("terms") = py::none(), py::arg("hover") = py::none(),
        py::arg("manoeuvre") = py::none(), py::arg("oe_segment_s") = 2.0,
        "Identifies the lateral model's dimensional derivatives from flight data, as `rig identify`: "
        "method 'wls' (default) or 'ols' (equation error) or 'output-error'. data: a rig log or CSV path, a "
        "Flight flown with log= (its log is read), or a dict of numpy arrays {'t', 'p', 'v', 'phi', "
        "'delta_f', 'delta_t', ...}. w0, u0 [m/s], theta0, phi0 [rad]: the trim of Eq 21 (--w0, --u0); terms: a "
        "model file whose terms: are fitted alongside, or a list of 'EQUATION: EXPRESSION' texts; hover, "
        "manoeuvre: lists of (start, end) [s] for the PSDs; oe_segment_s: output error's segment [s]. Returns `rig "
        "identify --json`'s content as a dict (parameters in SI units per unit of state or input, metrics, "
        "'eigenvalues' a complex array [1/s], ...) plus 'signals' (the resampled, filtered signals the regression "
        "used, 't' first) and "
        "'equations' (per equation its regressors, parameters, y = scale * dependent, theta). model_out: write "
        "the identified model file there. Raises DataError for bad data, ValueError for a bad option.");
  m.def("validate", &validate, py::arg("model"), py::arg("data"), py::kw_only(), py::arg("closed_loop") = false,
        py::arg("gains") = py::none(), py::arg("controller") = py::none(), py::arg("vehicle") = py::none(),
        py::arg("states") = "auto", py::arg("sensing") = py::none(), py::arg("salvage") = false,
        py::arg("rate_hz") = py::none(), py::arg("cutoff_hz") = py::none(), py::arg("order") = py::none(),
        py::arg("interpolation") = "cubic",
        "Validates a model (a model file's path, or a dict with its content) on flight data, as `rig "
        "validate`: open loop (the state derivatives predicted "
        "from the measured states; 't', 'measured', 'predicted' arrays beside the --json content) or, "
        "closed_loop=True, the model flown by the controller copy on the data's phi_sp (gains: the log's set, "
        "'fast' for other data; 't' [s], 'measured', 'simulated' {p [rad/s], v [m/s], phi [rad], delta_f "
        "[rad/s]}, 'phi_sp', 'phi_ref' [rad]). rate_hz, cutoff_hz [Hz], order: the resampling and low-pass.");
  m.def("discrepancy", &discrepancy, py::arg("data"), py::kw_only(), py::arg("model"),
        py::arg("candidates") = py::none(), py::arg("folds") = py::none(), py::arg("partial_f") = py::none(),
        py::arg("delay_max_s") = py::none(), py::arg("command_latency_s") = py::none(), py::arg("gains") = py::none(),
        py::arg("vehicle") = py::none(), py::arg("model_out") = py::none(), py::arg("states") = "auto",
        py::arg("sensing") = py::none(), py::arg("salvage") = false,
        "The discrepancy workflow, as `rig discrepancy`: where the model and the data disagree, the effect the "
        "model misses (by name, or unexplained / ambiguous), the refit and the gap before and after on held-out "
        "data. data: one flight (path or dict of arrays) or a list of flights pooled; model: a model file's path "
        "or a dict with its content. folds: held-out cross-validation folds; partial_f: the partial F a term must "
        "reach (SIDPAC's rule, 20) [-]; "
        "delay_max_s: the actuator_delay scan's limit [s]; command_latency_s: the flap command path's known latency "
        "[s]. Returns `rig "
        "discrepancy --json`'s content as a dict; model_out: write the refit model there.");
  m.def("export_mcap", &export_mcap, py::arg("log"), py::arg("out"), py::kw_only(), py::arg("raw") = false,
        py::arg("compression") = "zstd", py::arg("salvage") = false, py::arg("vehicle") = py::none(),
        py::arg("strict") = false,
        "Writes a rig log as MCAP (Foxglove, Lichtblick, PlotJuggler), as `rig export --format mcap`, and "
        "returns its --json content (messages per channel, what was left out). A damaged log raises DataError "
        "naming the byte offset unless salvage=True. A message with a value beyond the physical bounds of "
        "vehicle (default the rig's) is left out with a UserWarning naming its channel, field, time and count "
        "('beyond_bounds' in the result); strict=True raises DataError instead. Each MCAP message's log time is its "
        "rig time "
        "[ns from the run's start] (docs/viewers.md); its fields keep the units their names say.");
  m.def("log_bounds", &log_bounds, py::arg("log"), py::kw_only(), py::arg("vehicle") = py::none(),
        py::arg("salvage") = false,
        "The messages of a rig log with a value beyond the physical bounds of vehicle (default the rig's): "
        "'beyond_bounds' (count, and per channel and field its count, bound and value in the field's unit, "
        "first time [s of simulated time]), 'text' "
        "(the same for people, '' if none) and 'offsets' (each such message's byte offset in the log). "
        "read_log uses it to leave them out.");
}

}  // namespace nimble::python
