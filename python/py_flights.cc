/// load_scenario, fly and sweep of nimble_rig._rig: a scenario loaded with `rig run`'s checks, one
/// flight in process with the GIL released and its channels as numpy arrays, and `rig sweep`'s
/// campaign engine (its local backend).

#include <pybind11/stl.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <tuple>

#include "campaign/campaign.h"
#include "campaign/sweep.h"
#include "campaign/sweep_report.h"
#include "launcher/inprocess.h"
#include "launcher/run_report.h"
#include "python/py_channels.h"
#include "python/py_module.h"
#include "transport/clock.h"
#include "transport/node.h"

namespace nimble::python {
namespace {

std::shared_ptr<Scenario> load_scenario(const py::object& path, const py::dict& overrides) {
  auto s = std::make_shared<Scenario>();
  s->options.scenario_file = path_text(path);
  s->options.overrides = overrides_of(overrides);
  s->options.progress = false;
  s->options.print_summary = false;
  s->plan = launcher::load_run_plan(s->options);
  return s;
}

/// One flight: the report (`rig run --json`'s content) and every channel's arrays.
struct Flight {
  py::dict report;
  py::dict channels;
};

Flight fly(Scenario& scenario, std::optional<std::uint64_t> seed, const std::string& clock, const py::object& log,
           const py::dict& participants) {
  if (clock != launcher::kClockInprocess) {
    throw py::value_error("clock '" + clock +
                          "': a flight from Python is flown in process (clock='inprocess'); "
                          "the lockstep and real-time clocks run separate processes: use `rig run`");
  }
  // The plan of this flight: the scenario's, flown in process, with `seed` (as `rig run --clock
  // inprocess --seed N` plans it, so the report is the same).
  if (!scenario.flown || scenario.flown_seed != seed) {
    launcher::RunOptions options = scenario.options;
    options.clock = clock;
    options.seed = seed;
    scenario.flown = std::make_shared<const launcher::RunPlan>(launcher::load_run_plan(options));
    scenario.flown_seed = seed;
  }
  const std::shared_ptr<const launcher::RunPlan> held = scenario.flown;  // kept while it flies
  const launcher::RunPlan& plan = *held;
  ChannelCollector collector;
  launcher::InprocessOptions io;
  io.replace = participants_of(plan.scenario, participants);
  io.log_file = log.is_none() ? "" : path_text(log);
  io.on_message = [&collector](const std::string& channel, const void* data, int size) {
    collector.add(channel, data, size);
  };
  launcher::RunReport report;
  {
    // The flight runs without the GIL; SIGINT during it ends it as it ends `rig run` (result
    // interrupted, the log whole up to there).
    py::gil_scoped_release free;
    transport::ProcessNode::clear_stop_request();  // a Ctrl-C of an earlier flight is spent
    report = launcher::fly_inprocess(plan, io);
  }
  Flight f;
  f.report = json_value(launcher::report_json(report));
  f.channels = channels_dict(collector);
  return f;
}

/// A sweep from Python: the campaign engine's local backend on a campaign directory made for it
/// (`dir`, or a temporary one removed afterwards); returns `rig sweep --json`'s content.
/// The envelopes of rig sweep --report, per parameter set, as arrays.
py::list envelopes_of(const campaign::SweepResult& result) {
  py::list sets;
  auto vec = [](const std::vector<double>& v) {
    return array_of(Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size())));
  };
  for (const campaign::SetReport& r : campaign::sweep_report_sets(result)) {
    py::dict set;
    set["label"] = r.label;
    set["runs"] = r.runs;
    set["controlled"] = r.controlled;
    set["traces"] = r.traces;
    set["controlled_rate"] = py::make_tuple(r.rate.p, r.rate.lo, r.rate.hi);  // with its 95 % Wilson interval
    set["t_s"] = vec(r.phi_deg.t_s);
    using Named = std::pair<const char*, const campaign::Envelope*>;
    for (const auto& [name, e] : {Named{"p", &r.p}, Named{"v", &r.v}, Named{"phi_deg", &r.phi_deg}}) {
      py::dict q;
      q["p5"] = vec(e->p5);
      q["p50"] = vec(e->p50);
      q["p95"] = vec(e->p95);
      q["n"] = e->n;
      set[name] = q;
    }
    sets.append(set);
  }
  return sets;
}

py::dict sweep(const Scenario& scenario, const std::string& seeds, const py::dict& vary, int jobs,
               const std::optional<std::string>& dir, bool envelopes, const std::optional<std::string>& report) {
  campaign::CampaignRequest req;
  campaign::SweepOptions& o = req.sweep;
  o.base = scenario.options;
  o.base.clock = std::string(launcher::kClockInprocess);
  try {
    std::tie(o.first_seed, o.last_seed) = campaign::parse_seed_range(seeds);
  } catch (const std::invalid_argument& e) {
    throw py::value_error("seeds '" + seeds + "': " + e.what());
  }
  for (const auto& [key, values] : vary) {
    campaign::Vary v;
    v.key = key.cast<std::string>();
    for (const auto& value : values) {
      v.values.push_back(value_text(value));
    }
    o.vary.push_back(v);
  }
  if (jobs < 1 || jobs > 256) {  // rig sweep --jobs's range
    throw py::value_error("jobs must be in [1, 256] (runs at a time), not " + std::to_string(jobs));
  }
  o.jobs = jobs;
  o.progress = false;
  req.report = envelopes || report.has_value();
  std::optional<campaign::TemporaryCampaignDir> temporary;  // removed on return, whatever happened
  req.dir = dir ? *dir : temporary.emplace().path();
  campaign::Campaign c = campaign::create_campaign(req);
  campaign::SweepResult result;
  const std::int64_t start = transport::monotonic_ns();
  {
    py::gil_scoped_release free;
    transport::ProcessNode::clear_stop_request();  // a Ctrl-C of an earlier flight is spent
    campaign::fly_campaign_runs(c, campaign::missing_runs(c), o.jobs, "", nullptr);
  }
  result = campaign::merge_campaign(c);
  result.jobs = o.jobs;
  result.wall_time_s = static_cast<double>(transport::monotonic_ns() - start) / 1e9;
  py::dict out = json_value(campaign::sweep_json(result));
  if (req.report) out["envelopes"] = envelopes_of(result);
  if (report) campaign::write_sweep_report(result, *report);
  return out;
}

}  // namespace

void add_flights(py::module_& m) {
  py::class_<Scenario, std::shared_ptr<Scenario>>(m, "Scenario", "A scenario loaded and checked as `rig run` loads it.")
      .def_property_readonly(
          "file", [](const Scenario& s) { return s.options.scenario_file; }, "the scenario file")
      .def_property_readonly(
          "name", [](const Scenario& s) { return s.plan.scenario.name; }, "its name")
      .def_property_readonly(
          "seed", [](const Scenario& s) { return s.plan.scenario.seed; },
          "its seed (fly() flies it unless given another)")
      .def_property_readonly(
          "duration_s", [](const Scenario& s) { return s.plan.scenario.duration_s; },
          "its duration [s] of simulated time")
      .def("__repr__", [](const Scenario& s) {
        return "<nimble_rig.Scenario '" + s.plan.scenario.name + "' from " + s.options.scenario_file + ">";
      });

  py::class_<Flight>(m, "Flight", "One flight: .report (the `rig run --json` content) and .channels.")
      .def_readonly("report", &Flight::report, "the run's report: `rig run --json`'s content as a dict")
      .def_readonly("channels", &Flight::channels,
                    "channel -> field -> numpy array, one row per message (read_log's layout)");

  m.def("load_scenario", &load_scenario, py::arg("path"), py::arg("overrides") = py::dict(),
        "Loads a scenario with the same checks as `rig run`; overrides are --set values "
        "({'plant.effects.lateral_gust.enabled': True}). Raises ConfigError naming the file, line and key.");
  m.def("fly", &fly, py::arg("scenario"), py::arg("seed") = py::none(), py::arg("clock") = "inprocess",
        py::arg("log") = py::none(), py::kw_only(), py::arg("participants") = py::dict(),
        "Flies the scenario in process (the GIL released) and returns a Flight; log: also write the LCM log "
        "there. The TRUTH is byte for byte that of `rig run --clock inprocess` with the same seed. SIGINT "
        "during the flight ends it with result interrupted. participants: {process: object} flies each "
        "object in place of the scenario's process of that name (not the plant): an object with inputs, "
        "outputs, rate_hz [Hz] and step(t_s, inputs) -> {channel: message} (nimble_rig.Participant), called "
        "at its rate with the GIL taken for the call alone; an exception it raises ends the flight with "
        "result failed, naming the process, the exception and the simulated time, the log kept.");
  m.def("sweep", &sweep, py::arg("scenario"), py::arg("seeds") = "1-10", py::arg("vary") = py::dict(),
        py::arg("jobs") = 1, py::arg("dir") = py::none(), py::arg("envelopes") = false, py::arg("report") = py::none(),
        "Flies the scenario over seeds ('1-100') and parameter sets (vary={'key.path': [v1, v2]}) in process, "
        "`jobs` runs at a time, with the campaign engine of `rig sweep` (its local backend), and returns "
        "`rig sweep --json`'s content as a dict. dir: keep the campaign directory there, taken as rig sweep "
        "--dir takes it (one writer: RuntimeError naming the holder's pid if another process holds it; a "
        "directory that is not empty and holds no campaign is refused untouched; this same campaign there is "
        "finished, not flown again). envelopes: also "
        "'envelopes', per parameter set the 5/50/95 % percentiles of p [rad/s], v [m/s] and phi_deg [deg] "
        "across seeds against t_s [s of simulated time] (rig sweep --report's figures, as arrays), with "
        "'controlled_rate' (fraction, 95 % Wilson interval); vary's values are in the unit the key's name or "
        "its configuration says (docs/configuration.md); report: write rig sweep --report's files into that "
        "directory. Raises ConfigError for a bad value in any set.");
}

}  // namespace nimble::python
