// nimble_rig._rig: the rig's library code for Python (pybind11). The same loading and checks as
// `rig run`, a flight in process with the GIL released, and every channel of it handed over as
// numpy arrays built in C++ (no Python work per message). python/nimble_rig/__init__.py exports
// it; docs/python.md describes it.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <type_traits>
#include <vector>

#include <nimble/rig_message_list.hpp>

#include "campaign/campaign.h"
#include "campaign/sweep.h"
#include "contract/channels.h"
#include "contract/decode.h"
#include "core/config.h"
#include "launcher/inprocess.h"
#include "launcher/run_plan.h"
#include "launcher/run_report.h"
#include "transport/clock.h"
#include "transport/node.h"

namespace py = pybind11;

namespace nimble::python {
namespace {

template <class T>
struct is_vector : std::false_type {};
template <class T, class A>
struct is_vector<std::vector<T, A>> : std::true_type {};

/// One field of a channel over its messages, as read_log lays it out: a number per message, a
/// fixed-size row per message, or a Python object per message (strings, variable-length arrays).
struct Column {
  enum Kind { kFloat, kInt, kObject } kind = kFloat;
  std::size_t width = 1;  ///< values per message of a fixed-size numeric field (1: a scalar)
  bool row = false;       ///< a fixed-size array (even of size 1): a 2-D array
  std::vector<double> f;
  std::vector<std::int64_t> i;
  std::vector<std::vector<double>> fo;        ///< variable-length numeric arrays
  std::vector<std::vector<std::string>> so;  ///< strings and arrays of strings
  bool strings = false;
  bool scalar_string = false;  ///< a string field (not an array of strings)
};

/// Every field of every message of one channel, in .lcm order.
struct ChannelColumns {
  std::vector<std::string> names;
  std::vector<Column> columns;
  std::size_t messages = 0;
};

/// Appends one message's fields to `c` (its columns made at the first message).
template <class M>
void append(M& m, ChannelColumns& c) {
  const bool first = c.messages == 0;
  std::size_t k = 0;
  for_each_field(m, [&](const char* name, auto& field) {
    using T = std::remove_cv_t<std::remove_reference_t<decltype(field)>>;
    if (first) {
      c.names.emplace_back(name);
      c.columns.emplace_back();
    }
    Column& col = c.columns[k++];
    if constexpr (std::is_arithmetic_v<T>) {
      col.kind = std::is_floating_point_v<T> ? Column::kFloat : Column::kInt;
      if constexpr (std::is_floating_point_v<T>) col.f.push_back(field);
      else col.i.push_back(static_cast<std::int64_t>(field));
    } else if constexpr (std::is_array_v<T> && std::is_arithmetic_v<std::remove_extent_t<T>>) {
      using E = std::remove_extent_t<T>;
      col.row = true;
      col.width = std::extent_v<T>;
      col.kind = std::is_floating_point_v<E> ? Column::kFloat : Column::kInt;
      for (std::size_t j = 0; j < std::extent_v<T>; ++j) {
        if constexpr (std::is_floating_point_v<E>) col.f.push_back(field[j]);
        else col.i.push_back(static_cast<std::int64_t>(field[j]));
      }
    } else if constexpr (std::is_same_v<T, std::string>) {
      col.kind = Column::kObject;
      col.strings = true;
      col.scalar_string = true;
      col.so.push_back({field});
    } else if constexpr (is_vector<T>::value) {
      using E = typename T::value_type;
      col.kind = Column::kObject;
      if constexpr (std::is_arithmetic_v<E>) {
        col.fo.emplace_back(field.begin(), field.end());
      } else if constexpr (std::is_same_v<E, std::string>) {
        col.strings = true;
        col.so.push_back(field);
      } else {
        col.fo.emplace_back();  // nested variable-length arrays: not carried
      }
    } else {
      col.kind = Column::kObject;
      col.fo.emplace_back();  // a fixed array of strings or of arrays: not carried
    }
  });
  ++c.messages;
}

/// Every message of a run, by channel, decoded as its channel's type (contract/channels.h).
class ChannelCollector {
 public:
  void add(const std::string& channel, const void* data, int size) {
    const contract::ChannelSpec* spec = contract::find_channel(channel);
    if (spec == nullptr) return;
    with_message_type(spec->type, [&](auto type) {
      using M = typename decltype(type)::type;
      M m{};
      if (contract::decode_exact(data, size, m)) append(m, channels_[channel]);
    });
  }
  const std::map<std::string, ChannelColumns>& channels() const { return channels_; }

 private:
  std::map<std::string, ChannelColumns> channels_;
};

template <class T>
py::array_t<T> array_of(const std::vector<T>& values, std::size_t n, std::size_t width, bool row) {
  std::vector<py::ssize_t> shape{static_cast<py::ssize_t>(n)};
  if (row) shape.push_back(static_cast<py::ssize_t>(width));
  py::array_t<T> a(shape);
  if (!values.empty()) std::memcpy(a.mutable_data(), values.data(), values.size() * sizeof(T));
  return a;
}

/// channel -> field -> numpy array (read_log's layout), built under the GIL after the flight.
py::dict channels_dict(const ChannelCollector& collector) {
  py::dict out;
  py::module_ np = py::module_::import("numpy");
  for (const auto& [channel, c] : collector.channels()) {
    py::dict fields;
    for (std::size_t k = 0; k < c.names.size(); ++k) {
      const Column& col = c.columns[k];
      if (col.kind == Column::kFloat) {
        fields[c.names[k].c_str()] = array_of(col.f, c.messages, col.width, col.row);
      } else if (col.kind == Column::kInt) {
        fields[c.names[k].c_str()] = array_of(col.i, c.messages, col.width, col.row);
      } else {
        py::list items;
        if (col.strings) {
          for (const auto& s : col.so) items.append(col.scalar_string ? py::cast(s.front()) : py::cast(s));
        } else {
          for (const auto& v : col.fo) items.append(array_of(v, v.size(), 1, false));
        }
        fields[c.names[k].c_str()] = np.attr("array")(items, py::arg("dtype") = "object");
      }
    }
    out[channel.c_str()] = fields;
  }
  return out;
}

/// nimble_rig.ConfigError, carrying the rig's message and where the problem is (made once, kept
/// for the interpreter's life).
PyObject* g_config_error = nullptr;

[[noreturn]] void raise_config_error(const ConfigError& e) {
  py::object error = py::reinterpret_borrow<py::object>(g_config_error)(e.what());
  error.attr("file") = e.file();
  error.attr("line") = e.line();
  error.attr("key") = e.key();
  error.attr("value") = e.value();
  error.attr("problem") = e.problem();
  PyErr_SetObject(g_config_error, error.ptr());
  throw py::error_already_set();
}

/// A scenario loaded as `rig run` loads it: the run plan, checked.
struct Scenario {
  launcher::RunOptions options;
  launcher::RunPlan plan;
};

/// The overrides of a dict: each value as YAML text (JSON is YAML).
std::vector<Override> overrides_of(const py::dict& overrides) {
  py::module_ json = py::module_::import("json");
  std::vector<Override> out;
  for (const auto& [key, value] : overrides) {
    const std::string text =
        py::isinstance<py::str>(value) ? value.cast<std::string>() : json.attr("dumps")(value).cast<std::string>();
    out.push_back({key.cast<std::string>(), text});
  }
  return out;
}

std::shared_ptr<Scenario> load_scenario(const std::string& path, const py::dict& overrides) {
  auto s = std::make_shared<Scenario>();
  s->options.scenario_file = path;
  s->options.overrides = overrides_of(overrides);
  s->options.progress = false;
  s->options.print_summary = false;
  try {
    s->plan = launcher::load_run_plan(s->options);
  } catch (const ConfigError& e) {
    raise_config_error(e);
  }
  return s;
}

/// One flight: the report (`rig run --json`'s content) and every channel's arrays.
struct Flight {
  py::dict report;
  py::dict channels;
};

Flight fly(const Scenario& scenario, std::optional<std::uint64_t> seed, const std::string& clock,
           const std::optional<std::string>& log) {
  if (clock != launcher::kClockInprocess) {
    throw py::value_error("clock '" + clock + "': a flight from Python is flown in process (clock='inprocess'); "
                          "the lockstep and real-time clocks run separate processes: use `rig run`");
  }
  // The plan of this flight: the scenario's, flown in process, with `seed` (as `rig run --clock
  // inprocess --seed N` plans it, so the report is the same).
  launcher::RunOptions options = scenario.options;
  options.clock = clock;
  if (seed) options.seed = *seed;
  launcher::RunPlan plan;
  try {
    plan = launcher::load_run_plan(options);
  } catch (const ConfigError& e) {
    raise_config_error(e);
  }
  ChannelCollector collector;
  launcher::InprocessOptions io;
  io.log_file = log.value_or("");
  io.on_message = [&collector](const std::string& channel, const void* data, int size) {
    collector.add(channel, data, size);
  };
  launcher::RunReport report;
  {
    // The flight runs without the GIL; SIGINT during it ends it as it ends `rig run` (result
    // interrupted, the log whole up to there).
    py::gil_scoped_release free;
    transport::ProcessNode::clear_stop_request();  // a Ctrl-C of an earlier flight is spent
    try {
      report = launcher::fly_inprocess(plan, io);
    } catch (const ConfigError& e) {
      py::gil_scoped_acquire held;
      raise_config_error(e);
    }
  }
  Flight f;
  f.report = py::module_::import("json").attr("loads")(launcher::report_json(report));
  f.channels = channels_dict(collector);
  return f;
}

/// A sweep from Python: the campaign engine's local backend on a campaign directory made for it
/// (`dir`, or a temporary one removed afterwards); returns `rig sweep --json`'s content.
py::dict sweep(const Scenario& scenario, const std::string& seeds, const py::dict& vary, int jobs,
               const std::optional<std::string>& dir) {
  campaign::CampaignRequest req;
  campaign::SweepOptions& o = req.sweep;
  o.base = scenario.options;
  o.base.clock = std::string(launcher::kClockInprocess);
  try {
    std::tie(o.first_seed, o.last_seed) = campaign::parse_seed_range(seeds);
  } catch (const std::invalid_argument& e) {
    throw py::value_error("seeds '" + seeds + "': " + e.what());
  }
  py::module_ json = py::module_::import("json");
  for (const auto& [key, values] : vary) {
    campaign::Vary v;
    v.key = key.cast<std::string>();
    for (const auto& value : values) {
      v.values.push_back(py::isinstance<py::str>(value) ? value.cast<std::string>()
                                                         : json.attr("dumps")(value).cast<std::string>());
    }
    o.vary.push_back(v);
  }
  o.jobs = std::max(1, jobs);
  o.progress = false;
  const bool keep = dir.has_value();
  req.dir = keep ? *dir
                 : (std::filesystem::temp_directory_path() / ("rig_py_sweep_" + std::to_string(::getpid()))).string();
  if (!keep) std::filesystem::remove_all(req.dir);
  campaign::Campaign c;
  try {
    c = campaign::create_campaign(req);
  } catch (const ConfigError& e) {
    raise_config_error(e);
  }
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
  if (!keep) {
    std::error_code ec;
    std::filesystem::remove_all(c.dir, ec);
  }
  return json.attr("loads")(campaign::sweep_json(result));
}

}  // namespace
}  // namespace nimble::python

PYBIND11_MODULE(_rig, m) {
  using namespace nimble::python;
  m.doc() = "The rig's library code: scenarios loaded and checked as `rig run` does, flights in process.";
  g_config_error = PyErr_NewExceptionWithDoc("nimble_rig.ConfigError",
                                             "A bad scenario or configuration value: .file, .line, .key, .value and "
                                             ".problem say where and what (str(e) is the rig's message).",
                                             PyExc_ValueError, nullptr);
  m.attr("ConfigError") = py::reinterpret_borrow<py::object>(g_config_error);

  py::class_<Scenario, std::shared_ptr<Scenario>>(m, "Scenario",
                                                  "A scenario loaded and checked as `rig run` loads it.")
      .def_property_readonly("file", [](const Scenario& s) { return s.options.scenario_file; },
                             "the scenario file")
      .def_property_readonly("name", [](const Scenario& s) { return s.plan.scenario.name; }, "its name")
      .def_property_readonly("seed", [](const Scenario& s) { return s.plan.scenario.seed; },
                             "its seed (fly() flies it unless given another)")
      .def_property_readonly("duration_s", [](const Scenario& s) { return s.plan.scenario.duration_s; },
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
        py::arg("log") = py::none(),
        "Flies the scenario in process (the GIL released) and returns a Flight; log: also write the LCM log "
        "there. The TRUTH is byte for byte that of `rig run --clock inprocess` with the same seed. SIGINT "
        "during the flight ends it with result interrupted.");
  m.def("sweep", &sweep, py::arg("scenario"), py::arg("seeds") = "1-10", py::arg("vary") = py::dict(),
        py::arg("jobs") = 1, py::arg("dir") = py::none(),
        "Flies the scenario over seeds ('1-100') and parameter sets (vary={'key.path': [v1, v2]}) in process, "
        "`jobs` runs at a time, with the campaign engine of `rig sweep` (its local backend), and returns "
        "`rig sweep --json`'s content as a dict. dir: keep the campaign directory there. Raises ConfigError "
        "for a bad value in any set.");
}
