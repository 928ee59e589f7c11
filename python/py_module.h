#pragma once
/// What the files of nimble_rig._rig share: the loaded scenario, how Python values become the
/// rig's (overrides, flight data), and the functions each file adds to the module.
/// python/rig_module.cc makes the module; docs/python.md describes it.

#include <pybind11/pybind11.h>

#include <complex>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "core/config.h"
#include "ident/flight_data.h"
#include "ident/rig_log.h"
#include "launcher/inprocess.h"
#include "launcher/run_plan.h"

namespace nimble::python {

namespace py = pybind11;

/// A scenario loaded as `rig run` loads it: the run plan, checked.
struct Scenario {
  launcher::RunOptions options;
  launcher::RunPlan plan;
  /// The plan of its last flight from Python (in process, with that flight's seed), reused by the
  /// next flight with the same seed: planned once, flown many times.
  std::shared_ptr<const launcher::RunPlan> flown;
  std::optional<std::uint64_t> flown_seed;  ///< (none: the scenario's own)
};

/// The overrides of a dict ({'plant.effects.lateral_gust.enabled': True}): each value as YAML
/// text (a str as it is, anything else as JSON, which is YAML).
std::vector<Override> overrides_of(const py::dict& overrides);

/// A value of a dict or list as the text `--set` would give it.
std::string value_text(const py::handle& value);

/// Flight data given to an analysis: a rig log, a CSV file, or a dict of numpy arrays.
struct DataInput {
  ident::FlightData data;
  std::string gain_set;  ///< the gain set a rig log's controller flew ("" otherwise)
};

/// `data` as flight data: a path (str or os.PathLike) of a rig log or an identification CSV
/// (read by content, as the commands read it), or a dict {'t': array, 'p': array, ...} of the
/// channels of ident/flight_data.h on one time base ('t' [s], strictly increasing). `states`
/// (auto, estimate, truth, smoothed, sensors) says where a log's states come from; `sensing` is the
/// sensing file of the smoother (states='smoothed') or of the differentiator (states='sensors'). With `vehicle`, a log with a message beyond
/// its physical bounds is refused as it is read (ident::LogReadOptions::refuse_beyond_bounds).
/// @throws ident::DataError naming the channel and sample; std::invalid_argument for an unknown
///         channel, a length that differs from t's, or states given for data that is not a log.
DataInput flight_data_of(const py::object& data, const std::string& states, const std::string& sensing, bool salvage,
                         const Vehicle* vehicle = nullptr);

/// A numpy array of an Eigen vector (one copy, no Python work per sample).
py::object array_of(const Eigen::VectorXd& v);
/// A complex numpy array of complex numbers (eigenvalues, poles, frequency responses).
py::object complex_array_of(const std::vector<std::complex<double>>& v);

/// A path given as str or os.PathLike (pathlib.Path) as text. @throws TypeError for anything else.
std::string path_text(const py::handle& path);

/// A model given to an analysis: a path (str or os.PathLike) of a model file, or a dict with a model
/// file's content (name, structure, vehicle, inputs, trim, derivatives, ...; a relative vehicle path
/// taken from the current directory), written to a temporary file that goes with this.
class ModelFile {
 public:
  /// @throws TypeError for anything else; OSError if the temporary file cannot be written.
  explicit ModelFile(const py::handle& model);
  ~ModelFile();
  ModelFile(const ModelFile&) = delete;
  ModelFile& operator=(const ModelFile&) = delete;
  /// The model file (the path given, or the temporary file of the dict).
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::string temporary_dir_;  ///< "" for a path
};

/// The regex (Bus::subscribe_raw) that matches exactly the channels named, each taken literally;
/// "" for none.
std::string channels_pattern(const std::vector<std::string>& channels);

/// A JSON text as Python objects (json.loads).
py::object json_value(const std::string& text);

/// The participants of a flight (nimble_rig.fly(participants=)): each value of `participants` a
/// Python object (nimble_rig/participant.py) flying in place of the scenario's process its key
/// names, and the scenario's own (section `participants`) where `participants` names none in
/// their place, each checked here; `scenario` must outlive the flight.
/// @throws TypeError or ValueError from the check, naming the process and what is wrong.
std::map<std::string, launcher::ParticipantFactory> participants_of(const nimble::Scenario& scenario,
                                                                    const py::dict& participants);

/// A Python participant as a rig process of its own over LCM (`python -m nimble_rig.node --name
/// controller --scenario FILE --lcm-url URL`, the flags of every rig process): the participant the
/// scenario's section `participants` names in place of that process, flown until the run ends.
/// Returns the process's exit code (transport/process_options.h).
int run_node(const std::vector<std::string>& args);

/// Adds load_scenario, fly, sweep and their classes (python/py_flights.cc).
void add_flights(py::module_& m);
/// Adds identify, validate, discrepancy, export_mcap (python/py_analysis.cc).
void add_analysis(py::module_& m);
/// Adds loop (python/py_loop.cc).
void add_loop(py::module_& m);
/// Adds the live run's subscription (python/py_subscribe.cc).
void add_subscribe(py::module_& m);

}  // namespace nimble::python
