// nimble_rig._rig: the rig's library code for Python (pybind11). Scenarios loaded with `rig run`'s
// checks, flights and sweeps in process (python/py_flights.cc), identification, validation, the
// discrepancy workflow and the MCAP export on a log, a CSV file or numpy arrays
// (python/py_analysis.cc), the roll loop's analysis (python/py_loop.cc). The rig's errors become
// Python exceptions here. python/nimble_rig/__init__.py exports it; docs/python.md describes it.

#include <pybind11/complex.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstring>
#include <filesystem>
#include <regex>
#include <string>
#include <vector>

#include "core/config.h"
#include "ident/flight_data.h"
#include "python/py_module.h"

namespace nimble::python {

std::string value_text(const py::handle& value) {
  if (py::isinstance<py::str>(value)) return value.cast<std::string>();
  return py::module_::import("json").attr("dumps")(value).cast<std::string>();
}

std::vector<Override> overrides_of(const py::dict& overrides) {
  std::vector<Override> out;
  for (const auto& [key, value] : overrides) out.push_back({key.cast<std::string>(), value_text(value)});
  return out;
}

py::object array_of(const Eigen::VectorXd& v) {
  py::array_t<double> a(static_cast<py::ssize_t>(v.size()));
  if (v.size() > 0) std::memcpy(a.mutable_data(), v.data(), static_cast<std::size_t>(v.size()) * sizeof(double));
  return std::move(a);
}

py::object complex_array_of(const std::vector<std::complex<double>>& v) {
  py::array_t<std::complex<double>> a(static_cast<py::ssize_t>(v.size()));
  if (!v.empty()) std::memcpy(a.mutable_data(), v.data(), v.size() * sizeof(std::complex<double>));
  return std::move(a);
}

std::string path_text(const py::handle& path) {
  return py::module_::import("os").attr("fspath")(path).cast<std::string>();
}

ModelFile::ModelFile(const py::handle& model) {
  if (!py::isinstance<py::dict>(model)) {
    path_ = path_text(model);
    return;
  }
  py::dict content = py::module_::import("copy").attr("deepcopy")(model);
  const py::object os_path = py::module_::import("os.path");
  if (content.contains("vehicle") && py::isinstance<py::str>(content["vehicle"]) &&
      !os_path.attr("isabs")(content["vehicle"]).cast<bool>()) {
    content["vehicle"] = os_path.attr("abspath")(content["vehicle"]);
  }
  const py::object tempfile = py::module_::import("tempfile");
  temporary_dir_ = tempfile.attr("mkdtemp")(py::arg("prefix") = "nimble_rig_model_").cast<std::string>();
  path_ = temporary_dir_ + "/model.yaml";
  // JSON is YAML: the loader reads the dict as it reads a model file, with the same checks.
  const std::string text = py::module_::import("json").attr("dumps")(content).cast<std::string>();
  py::module_::import("pathlib").attr("Path")(path_).attr("write_text")(text);
}

ModelFile::~ModelFile() {
  if (temporary_dir_.empty()) return;
  std::error_code ec;
  std::filesystem::remove_all(temporary_dir_, ec);
}

std::string channels_pattern(const std::vector<std::string>& channels) {
  static const std::regex special(R"([.^$|()\[\]{}*+?\\])");
  std::string pattern;
  for (const std::string& c : channels)
    pattern += (pattern.empty() ? "" : "|") + std::regex_replace(c, special, R"(\$&)");
  return pattern.empty() ? pattern : "(" + pattern + ")";
}

py::object json_value(const std::string& text) { return py::module_::import("json").attr("loads")(text); }

namespace {

/// nimble_rig.ConfigError and nimble_rig.DataError (made once, kept for the interpreter's life).
PyObject* g_config_error = nullptr;
PyObject* g_data_error = nullptr;

/// Raises `type` with the rig's message and `attributes` set on the exception.
void raise_with(PyObject* type, const char* message, const py::dict& attributes) {
  py::object error = py::reinterpret_borrow<py::object>(type)(message);
  for (const auto& [key, value] : attributes) error.attr(key) = value;
  PyErr_SetObject(type, error.ptr());
}

/// Where the rig's errors say an override (`--set`) is from.
const std::string kOverrideSource = "--set";

/// A line number for Python: None where the rig has none (-1, or 0).
py::object line_of(int line) { return line > 0 ? py::object(py::int_(line)) : py::object(py::none()); }

/// The rig's errors as Python exceptions: a bad configuration value and bad flight data carry
/// where they are; the rest become ValueError or RuntimeError (pybind11's own translation).
void translate(std::exception_ptr p) {
  try {
    if (p) std::rethrow_exception(p);
  } catch (const ConfigError& e) {
    // An override (the command line's --set) came from Python's overrides dict: named so, no line.
    const bool override = e.file() == kOverrideSource;
    std::string message = e.what();
    if (override && message.rfind(kOverrideSource, 0) == 0)
      message = "overrides" + message.substr(kOverrideSource.size());
    py::dict a;
    a["file"] = override ? py::object(py::none()) : py::str(e.file());
    a["line"] = line_of(e.line());
    a["key"] = e.key();
    a["value"] = e.value();
    a["problem"] = e.problem();
    a["override"] = override;
    raise_with(g_config_error, message.c_str(), a);
  } catch (const ident::DataError& e) {
    py::dict a;
    a["source"] = e.source();
    a["line"] = line_of(e.line());
    a["row"] = e.row();
    a["column"] = e.column();
    a["problem"] = e.problem();
    raise_with(g_data_error, e.what(), a);
  }
}

}  // namespace
}  // namespace nimble::python

PYBIND11_MODULE(_rig, m) {
  using namespace nimble::python;
  m.doc() =
      "The rig's library code: scenarios loaded and checked as `rig run` does, flights and sweeps in "
      "process, identification, validation, the discrepancy workflow, the roll loop's analysis and the "
      "MCAP export.";
  g_config_error = PyErr_NewExceptionWithDoc("nimble_rig.ConfigError",
                                             "A bad scenario or configuration value: .file, .line, .key, .value and "
                                             ".problem say where and what (str(e) is the rig's message); a value "
                                             "of the overrides dict has .override True, .file and .line None.",
                                             PyExc_ValueError, nullptr);
  g_data_error = PyErr_NewExceptionWithDoc("nimble_rig.DataError",
                                           "Bad flight data: .source, .line (None: no line), .row (1-based sample), "
                                           ".column and .problem say where and what (str(e) is the rig's message).",
                                           PyExc_ValueError, nullptr);
  m.attr("ConfigError") = py::reinterpret_borrow<py::object>(g_config_error);
  m.attr("DataError") = py::reinterpret_borrow<py::object>(g_data_error);
  py::register_exception_translator(&translate);
  add_flights(m);
  add_analysis(m);
  add_loop(m);
  add_subscribe(m);
  m.def("_run_node", &run_node, py::arg("args"),
        "Runs the scenario's Python participant as a rig process over LCM (python -m nimble_rig.node; "
        "args: the flags of every rig process, --name, --scenario, --lcm-url); returns its exit code.");
}
