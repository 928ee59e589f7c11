/// Participants written in Python: a Python object in place of one of the scenario's processes
/// (nimble_rig/participant.py says what it is), with the process's own frame (heartbeat, health,
/// faults), its step() called by its task at its rate with the GIL taken for the call alone.
/// In process (nimble_rig.fly()) it is on the run's hub; in lockstep and real time it is a process
/// of its own over LCM (`python -m nimble_rig.node`, which the launcher starts for the scenario's
/// `participants` section).

#include <cstdio>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <pybind11/stl.h>
#include <yaml-cpp/yaml.h>

#include <nimble/actuator_command_t.hpp>
#include <nimble/actuator_feedback_t.hpp>
#include <nimble/attitude_setpoint_t.hpp>
#include <nimble/can_health_t.hpp>
#include <nimble/controller_status_t.hpp>
#include <nimble/estimator_state_t.hpp>
#include <nimble/fault_event_t.hpp>
#include <nimble/mocap_pose_t.hpp>

#include "contract/channels.h"
#include "contract/decode.h"
#include "launcher/inprocess.h"
#include "python/py_module.h"
#include "transport/process_main.h"

namespace nimble::python {
namespace {

/// Publishes a participant's encoded message as the rig's own process publishes its own: decoded
/// into its type and sent through the bus's fault injector, so that the scenario's faults on the
/// channel apply. @throws std::runtime_error if the bytes are not one message of the type.
template <typename T>
void publish_typed(transport::Bus& bus, const std::string& channel, const std::string& bytes) {
  T msg{};
  std::string error;
  if (!contract::decode_as(bytes.data(), static_cast<int>(bytes.size()), msg, false, &error)) {
    throw std::runtime_error("its message on " + channel + " does not decode: " + error);
  }
  bus.publish(channel, msg);
}

using TypedPublish = void (*)(transport::Bus&, const std::string&, const std::string&);

/// How each message type a replaceable process publishes (controller, mocap, estimator, the CAN
/// bridge's sides; contract/channels.cc) goes out; participant.py holds outputs to those channels.
TypedPublish typed_publish(const std::string& type) {
  static const std::map<std::string, TypedPublish> table = {
      {"actuator_command_t", &publish_typed<actuator_command_t>},
      {"actuator_feedback_t", &publish_typed<actuator_feedback_t>},
      {"attitude_setpoint_t", &publish_typed<attitude_setpoint_t>},
      {"can_health_t", &publish_typed<can_health_t>},
      {"controller_status_t", &publish_typed<controller_status_t>},
      {"estimator_state_t", &publish_typed<estimator_state_t>},
      {"mocap_pose_t", &publish_typed<mocap_pose_t>},
  };
  const auto it = table.find(type);
  if (it == table.end()) {
    throw std::logic_error("a participant's output of type " + type + ": no replaceable process publishes it");
  }
  return it->second;
}

/// A participant's declaration, checked (nimble_rig/participant.py stepper()).
struct Declared {
  /// The callable that steps it. Held, not copied: it is a Python object, and the participant may
  /// be built and destroyed without the GIL; released with the GIL taken, wherever the last
  /// holder lets go of it.
  std::shared_ptr<py::object> stepper;
  std::vector<std::string> inputs;
  std::map<std::string, TypedPublish> outputs;  ///< channel -> how its messages go out (by their type)
  double rate_hz = 0.0;
  std::string label;  ///< "controller (Python MyController)"
};

/// Checks `participant` in place of `process` against the contract's channels. GIL held.
/// @throws TypeError or ValueError naming the process and what is wrong.
Declared declare(const std::string& process, const py::handle& participant) {
  py::dict channels;  // the contract's: each one's type and publishers, which the check holds it to
  for (const contract::ChannelSpec& c : contract::channel_table())
    channels[py::str(c.name)] = py::make_tuple(c.type, c.publishers);
  const py::tuple made = py::module_::import("nimble_rig.participant").attr("stepper")(process, participant, channels);
  Declared d;
  d.stepper = std::shared_ptr<py::object>(new py::object(made[0]), [](py::object* o) {
    py::gil_scoped_acquire gil;
    delete o;
  });
  d.inputs = made[1].cast<std::vector<std::string>>();
  d.rate_hz = made[2].cast<double>();
  d.label = made[3].cast<std::string>();
  for (const auto& [channel, type] : made[4].cast<std::map<std::string, std::string>>())
    d.outputs[channel] = typed_publish(type);
  return d;
}

/// A YAML value (a participant's `arguments`) as Python: a plain scalar as the number or boolean
/// it reads as, else text; a quoted scalar as text; sequences as lists, mappings as dicts.
py::object python_of(const YAML::Node& node) {
  if (!node || node.IsNull()) return py::none();
  if (node.IsSequence()) {
    py::list out;
    for (const auto& item : node) out.append(python_of(item));
    return out;
  }
  if (node.IsMap()) {
    py::dict out;
    for (const auto& entry : node) out[py::str(entry.first.Scalar())] = python_of(entry.second);
    return out;
  }
  if (node.Tag() != "!") {  // not quoted
    long long i = 0;
    double x = 0.0;
    bool b = false;
    if (YAML::convert<long long>::decode(node, i)) return py::int_(i);
    if (YAML::convert<double>::decode(node, x)) return py::float_(x);
    if (YAML::convert<bool>::decode(node, b)) return py::bool_(b);
  }
  return py::str(node.Scalar());
}

/// The participant the scenario names in place of `process` (section `participants`): its class
/// made with its arguments. GIL held. @throws what the import or the class raises.
py::object scenario_participant(const std::string& process, const ParticipantSpec& spec) {
  return py::module_::import("nimble_rig.participant")
      .attr("load")(process, spec.python_file, spec.class_name, python_of(spec.arguments));
}

/// One Python participant: its inputs' bytes as they come, handed to its stepper at each step.
class PythonParticipant {
 public:
  /// `print_traceback`: an exception's traceback goes to stderr (the process's output file).
  PythonParticipant(std::unique_ptr<transport::ProcessNode> node, Declared declared, bool print_traceback = false)
      : node_(std::move(node)), declared_(std::move(declared)), print_traceback_(print_traceback) {
    if (!declared_.inputs.empty()) {
      node_->bus().subscribe_raw(channels_pattern(declared_.inputs),
                                 [this](const std::string& c, const void* data, int size, int64_t) {
                                   fresh_.emplace_back(c, std::string(static_cast<const char*>(data), size));
                                 });
    }
    node_->add_task(declared_.label, declared_.rate_hz, [this](int64_t t_ns) { step(t_ns); });
  }
  PythonParticipant(const PythonParticipant&) = delete;
  PythonParticipant& operator=(const PythonParticipant&) = delete;

  transport::ProcessNode& node() { return *node_; }

 private:
  /// Calls the stepper with the inputs that came since the last call, and publishes what it
  /// returns. @throws std::runtime_error naming the participant and the exception it raised,
  /// after a FATAL fault that says so with the simulated time (the launcher names it when the
  /// process ends).
  void step(int64_t t_ns) {
    try {
      publish(call(t_ns));
    } catch (const std::runtime_error& e) {
      char when[48];
      std::snprintf(when, sizeof when, " at simulated t = %.6f s", static_cast<double>(t_ns) * 1e-9);
      node_->fault(fault_event_t::SEVERITY_FATAL, fault_event_t::CODE_OTHER, "", e.what() + std::string(when));
      throw;
    }
  }

  std::vector<std::pair<std::string, std::string>> call(int64_t t_ns) {
    std::vector<std::pair<std::string, std::string>> out;
    py::gil_scoped_acquire gil;
    try {
      py::list fresh;
      for (auto& [channel, bytes] : fresh_) fresh.append(py::make_tuple(py::str(channel), py::bytes(bytes)));
      fresh_.clear();
      const py::object published = (*declared_.stepper)(static_cast<double>(t_ns) * 1e-9, fresh, node_->lockstep());
      for (const py::handle item : published) {
        const auto pair = item.cast<py::tuple>();
        out.emplace_back(pair[0].cast<std::string>(), pair[1].cast<std::string>());
      }
    } catch (const py::error_already_set& e) {
      // The exception's type and message (its first line; the traceback follows in e.what()).
      const std::string what = e.what();
      if (print_traceback_) std::fprintf(stderr, "%s raised %s\n", declared_.label.c_str(), what.c_str());
      throw std::runtime_error(declared_.label + " raised " + what.substr(0, what.find('\n')));
    }
    return out;
  }

  void publish(const std::vector<std::pair<std::string, std::string>>& out) {
    for (const auto& [channel, bytes] : out) {
      const auto it = declared_.outputs.find(channel);
      if (it == declared_.outputs.end())
        throw std::runtime_error(declared_.label + " published on " + channel + ", not an output");
      try {
        it->second(node_->bus(), channel, bytes);
      } catch (const std::runtime_error& e) {
        throw std::runtime_error(declared_.label + ": " + e.what());
      }
    }
  }

  std::unique_ptr<transport::ProcessNode> node_;
  Declared declared_;
  bool print_traceback_;
  std::vector<std::pair<std::string, std::string>> fresh_;  ///< (channel, bytes) since the last step
};

}  // namespace

std::map<std::string, launcher::ParticipantFactory> participants_of(const nimble::Scenario& scenario,
                                                                    const py::dict& participants) {
  // The scenario's own participants (section `participants`), unless the call names one in their place.
  py::dict all;
  for (const auto& [process, spec] : scenario.participants) {
    if (!participants.contains(py::str(process))) all[py::str(process)] = scenario_participant(process, spec);
  }
  for (const auto& [key, participant] : participants) all[key] = participant;
  std::map<std::string, launcher::ParticipantFactory> out;
  for (const auto& [key, participant] : all) {
    const std::string process = key.cast<std::string>();
    auto declared = std::make_shared<const Declared>(declare(process, participant));
    const nimble::Scenario* s = &scenario;
    out[process] = [s, declared](const transport::NodeOptions& options) {
      auto p = std::make_shared<PythonParticipant>(transport::make_process_node(*s, options), *declared);
      return launcher::CustomParticipant{&p->node(), p};
    };
  }
  return out;
}

int run_node(const std::vector<std::string>& args) {
  std::vector<std::string> argv_text = {"nimble_rig.node"};
  argv_text.insert(argv_text.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : argv_text) argv.push_back(a.data());
  argv.push_back(nullptr);
  return transport::run_process_main(
      static_cast<int>(argv_text.size()), argv.data(), "nimble_rig.node", "controller",
      [](const nimble::Scenario& scenario, const transport::NodeOptions& options) {
        const auto it = scenario.participants.find(options.name);
        if (it == scenario.participants.end()) {
          throw ConfigError(scenario.file, "participants", options.name,
                            "the scenario names no Python participant in place of process '" + options.name + "'");
        }
        PythonParticipant participant(transport::make_process_node(scenario, options),
                                      declare(options.name, scenario_participant(options.name, it->second)), true);
        try {
          py::gil_scoped_release free;  // taken again by each step
          return participant.node().run();
        } catch (const std::runtime_error& e) {
          // The participant's failure (its FATAL fault is out): the launcher ends the run on the exit.
          std::fprintf(stderr, "nimble_rig.node: %s\n", e.what());
          return transport::kExitFault;
        }
      });
}

}  // namespace nimble::python
