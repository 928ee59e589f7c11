/// Participants written in Python, flown in process (nimble_rig.fly(participants=)): a Python
/// object in place of one of the scenario's processes (nimble_rig/participant.py says what it is),
/// on the run's hub with the process's own frame (heartbeat, health, faults), its step() called
/// by its task at its rate with the GIL taken for the call alone.

#include <cstdio>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <pybind11/stl.h>

#include <nimble/actuator_command_t.hpp>
#include <nimble/actuator_feedback_t.hpp>
#include <nimble/attitude_setpoint_t.hpp>
#include <nimble/can_health_t.hpp>
#include <nimble/controller_status_t.hpp>
#include <nimble/estimator_state_t.hpp>
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

/// One Python participant: its inputs' newest bytes, handed to its stepper once per task run.
class PythonParticipant {
 public:
  /// `stepper` is held, not copied: it is a Python object, and this may be built and destroyed
  /// without the GIL.
  PythonParticipant(const nimble::Scenario& scenario, const transport::NodeOptions& options,
                    std::shared_ptr<py::object> stepper, const std::vector<std::string>& inputs,
                    const std::map<std::string, std::string>& outputs, double rate_hz, std::string label)
      : node_(transport::make_process_node(scenario, options)), stepper_(std::move(stepper)), label_(std::move(label)) {
    for (const auto& [channel, type] : outputs) publish_[channel] = typed_publish(type);
    if (!inputs.empty()) {
      node_->bus().subscribe_raw(channels_pattern(inputs),
                                 [this](const std::string& c, const void* data, int size, int64_t) {
                                   fresh_.emplace_back(c, std::string(static_cast<const char*>(data), size));
                                 });
    }
    node_->add_task(label_, rate_hz, [this](int64_t t_ns) { step(t_ns); });
  }
  PythonParticipant(const PythonParticipant&) = delete;
  PythonParticipant& operator=(const PythonParticipant&) = delete;

  transport::ProcessNode& node() { return *node_; }

 private:
  /// Calls the stepper with the inputs that came since the last call, and publishes what it
  /// returns. @throws std::runtime_error naming the participant and the exception it raised.
  void step(int64_t t_ns) {
    std::vector<std::pair<std::string, std::string>> out;
    {
      py::gil_scoped_acquire gil;
      try {
        py::dict fresh;
        for (auto& [channel, bytes] : fresh_) fresh[py::str(channel)] = py::bytes(bytes);
        fresh_.clear();
        const py::object published = (*stepper_)(static_cast<double>(t_ns) * 1e-9, fresh);
        for (const py::handle item : published) {
          const auto pair = item.cast<py::tuple>();
          out.emplace_back(pair[0].cast<std::string>(), pair[1].cast<std::string>());
        }
      } catch (const py::error_already_set& e) {
        // The exception's type and message (its first line; the traceback follows in e.what()).
        const std::string what = e.what();
        throw std::runtime_error(label_ + " raised " + what.substr(0, what.find('\n')));
      }
    }
    for (const auto& [channel, bytes] : out) {
      const auto it = publish_.find(channel);
      if (it == publish_.end()) throw std::runtime_error(label_ + " published on " + channel + ", not an output");
      try {
        it->second(node_->bus(), channel, bytes);
      } catch (const std::runtime_error& e) {
        throw std::runtime_error(label_ + ": " + e.what());
      }
    }
  }

  std::unique_ptr<transport::ProcessNode> node_;
  std::shared_ptr<py::object> stepper_;
  std::string label_;
  std::vector<std::pair<std::string, std::string>> fresh_;  ///< (channel, bytes) since the last step
  std::map<std::string, TypedPublish> publish_;             ///< its outputs, each by its type
};

}  // namespace

std::map<std::string, launcher::ParticipantFactory> participants_of(const nimble::Scenario& scenario,
                                                                    const py::dict& participants) {
  std::map<std::string, launcher::ParticipantFactory> out;
  const py::object make_stepper = py::module_::import("nimble_rig.participant").attr("stepper");
  // The contract's channels: each one's type and publishers, which the check holds a participant to.
  py::dict channels;
  for (const contract::ChannelSpec& c : contract::channel_table())
    channels[py::str(c.name)] = py::make_tuple(c.type, c.publishers);
  for (const auto& [key, participant] : participants) {
    const std::string process = key.cast<std::string>();
    // The participant's declaration, checked in Python (nimble_rig/participant.py): the callable
    // that steps it, its inputs, its rate and its name for messages.
    const py::tuple made = make_stepper(process, participant, channels);
    // Released with the GIL taken, wherever the last holder lets go of it.
    std::shared_ptr<py::object> stepper(new py::object(made[0]), [](py::object* o) {
      py::gil_scoped_acquire gil;
      delete o;
    });
    const auto inputs = made[1].cast<std::vector<std::string>>();
    const double rate_hz = made[2].cast<double>();
    const std::string label = made[3].cast<std::string>();
    const auto outputs = made[4].cast<std::map<std::string, std::string>>();
    for (const auto& [channel, type] : outputs) typed_publish(type);  // every output has its way out
    const nimble::Scenario* s = &scenario;
    out[process] = [s, stepper, inputs, outputs, rate_hz, label](const transport::NodeOptions& options) {
      auto p = std::make_shared<PythonParticipant>(*s, options, stepper, inputs, outputs, rate_hz, label);
      return launcher::CustomParticipant{&p->node(), p};
    };
  }
  return out;
}

}  // namespace nimble::python
