#include "can_bridge/bridge_node.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>

#include "contract/messages.h"
#include "contract/rates.h"
#include "core/config.h"
#include <nimble/fault_event_t.hpp>

#include "transport/clock.h"
#include "transport/process_main.h"

namespace nimble::can {

namespace {

using transport::ProcessNode;
namespace ch = contract::channels;

int64_t realtime_ns() {
  timespec ts{};
  ::clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

std::string hex_id(const can_frame& f) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%03X", f.can_id & CAN_EFF_MASK);
  return buf;
}

/// The controller's rate: one command per control cycle (the controller section's, else the
/// contract's default).
double controller_rate_hz(const Scenario& scenario) {
  ConfigMap controller = scenario.section("controller");
  if (!controller.has("rate_hz")) return contract::kDefaultControlRateHz;
  return controller.get_double("rate_hz", Range::closed(contract::kMinControlRateHz, contract::kMaxControlRateHz));
}

}  // namespace

CanBridgeNode::CanBridgeNode(const Scenario& scenario, const transport::NodeOptions& options,
                             InprocessCanBus* inprocess_bus) {
  if (options.name == kFlightProcess) {
    role_ = Role::kFlight;
  } else if (options.name == kRigProcess) {
    role_ = Role::kRig;
  } else {
    throw ConfigError(
        options.scenario_file, "--name", options.name,
        "the CAN bridge runs as '" + kFlightProcess + "' (flight-board side) or '" + kRigProcess + "' (rig side)");
  }
  ConfigMap section = scenario.section("can_bridge");
  config_ = can_bridge_config_from(section);
  // Every value read and checked before a socket is opened.
  const double cycle_hz = controller_rate_hz(scenario);

  CanSocketOptions so;
  // The rig's identifier block, not only its five identifiers: an unexpected identifier in
  // the block is counted and reported; other nodes' traffic on a shared bus stays in the kernel.
  so.filters = {rig_block_filter()};
  so.error_frames = true;
  so.timestamps = true;
  so.receive_buffer_bytes = config_.receive_buffer_bytes;
  so.fd = config_.fd;
  if (inprocess_bus != nullptr && options.hub != nullptr) {
    socket_ = inprocess_bus->attach(config_.interface, config_.fd);
  } else {
    socket_ = std::make_unique<CanSocket>(CanSocket::open(config_.interface, so));
  }
  if (role_ == Role::kRig && config_.candump_log && !config_.candump_file.empty()) {
    candump_ = std::make_unique<CandumpWriter>(config_.candump_file);
  }

  node_ = transport::make_process_node(scenario, options);
  link_faults_ = std::make_unique<CanLinkFaults>(scenario.faults, scenario.seed);
  if (socket_->fd() >= 0)
    node_->watch_fd(socket_->fd(), [this] { drain_socket(); });
  else
    options.hub->add_poller([this] { return drain_socket() > 0; });
  health_period_ns_ = static_cast<int64_t>(1e9 / config_.health_rate_hz);
  node_->on_housekeeping([this] {
    if (transport::monotonic_ns() >= next_health_wall_ns_) publish_health();
  });

  cycle_period_ns_ = static_cast<int64_t>(std::llround(1e9 / cycle_hz));
  // Lockstep only: in real time an input-triggered task never runs unless notified.
  node_->add_task(
      "control_cycle", cycle_hz, [this](int64_t t) { on_cycle(t); }, ProcessNode::Trigger::kInput);

  if (role_ == Role::kFlight) {
    node_->set_expected_rate(ch::kActuatorCommand, scenario.expected_rate(ch::kActuatorCommand));
    node_->bus().subscribe<actuator_command_t>(ch::kActuatorCommand,
                                               [this](const actuator_command_t& c) { on_command(c); });
  } else {
    node_->set_expected_rate(ch::kActuatorFeedback, scenario.expected_rate(ch::kActuatorFeedback));
    node_->bus().subscribe<actuator_feedback_t>(ch::kActuatorFeedback,
                                                [this](const actuator_feedback_t& f) { on_feedback(f); });
  }
}

CanBridgeNode::~CanBridgeNode() {
  if (candump_) candump_->flush();
}

int CanBridgeNode::run() {
  const int code = node_->run();
  // What arrived before the stop still crosses: messages waiting on LCM go out as frames, frames
  // waiting on the socket go out on LCM.
  node_->bus().drain();
  drain_socket();
  if (candump_) candump_->flush();
  publish_health();
  return code;
}

int64_t CanBridgeNode::rig_time_us() const {
  if (node_->lockstep()) return node_->sim_time_ns() / 1000;
  const int64_t t0 = node_->t0_monotonic_ns();
  return t0 > 0 ? (transport::monotonic_ns() - t0) / 1000 : 0;
}

void CanBridgeNode::on_cycle(int64_t /*sim_time_ns*/) {
  ++cycles_due_;
  skip_lost_commands();
  if (commands_crossed_ < cycles_due_) node_->hold_ack();
}

void CanBridgeNode::skip_lost_commands() {
  if (role_ != Role::kRig || link_faults_->empty()) return;
  // A command the link's faults destroy never comes: its cycle is acknowledged without it. Asked
  // for the next command owed, whether it is owed at this cycle or became the next at an arrival.
  while (commands_crossed_ < cycles_due_) {
    // The shadow decoder sees every command in order, also those that arrived before their cycle.
    while (shadow_next_ <= commands_crossed_) shadow_arrives_ = command_will_arrive(shadow_next_);
    if (shadow_arrives_) break;
    ++commands_crossed_;
    ++commands_never_came_;
  }
}

bool CanBridgeNode::command_will_arrive(int64_t m) {
  ++shadow_next_;
  const int64_t utime = m * cycle_period_ns_ / 1000;  // the controller's cycle time
  const auto counter = static_cast<uint8_t>(m % kCounterModulo);
  bool complete = false;
  for (std::size_t j = 0; j < kCommandFrames.size(); ++j) {
    if (link_faults_->fate(CanLinkFaults::Direction::kCommand, m, static_cast<int>(j), utime, CAN_MAX_DLEN, nullptr) !=
        CanLinkFaults::Fate::kSent) {
      continue;
    }
    if (!shadow_assembler_.accept_counter(j, counter, shadow_stats_)) continue;
    complete = shadow_assembler_.store(j, counter, shadow_stats_);
  }
  return complete;
}

void CanBridgeNode::update_bus_off(int64_t utime) {
  const contract::FaultSpec* active = link_faults_->active_at(utime);
  if (active != active_link_fault_ && role_ == Role::kFlight) {
    // The flight side announces the link's faults (its commands pace them, 512 a second).
    char when[40];
    std::snprintf(when, sizeof when, " at t = %.3f s", 1e-6 * static_cast<double>(utime));
    if (active_link_fault_ != nullptr) {
      node_->fault(fault_event_t::SEVERITY_INFO, fault_event_t::CODE_FAULT_INJECTED, contract::kFaultTargetCan,
                   "injected " + active_link_fault_->describe() + " ended" + when);
    }
    if (active != nullptr) {
      node_->fault(fault_event_t::SEVERITY_INFO, fault_event_t::CODE_FAULT_INJECTED, contract::kFaultTargetCan,
                   "injected " + active->describe() + " began" + when);
    }
  }
  active_link_fault_ = active;
  const contract::FaultSpec* off = link_faults_->bus_off_at(utime);
  if ((off != nullptr) == injected_bus_off_) return;
  injected_bus_off_ = off != nullptr;
  char when[40];
  std::snprintf(when, sizeof when, "t = %.3f s", 1e-6 * static_cast<double>(utime));
  if (injected_bus_off_) {
    bus_state_ = CanHealth::kBusOff;
    last_error_ = "bus-off (injected " + off->describe() + ")";
    node_->fault(fault_event_t::SEVERITY_ERROR, fault_event_t::CODE_CAN_ERROR_FRAME, "CAN " + config_.interface,
                 "bus-off on " + config_.interface + " at " + when + ": this controller sends nothing (injected " +
                     off->describe() + ")");
  } else {
    bus_state_ = CanHealth::kBusActive;
    node_->fault(fault_event_t::SEVERITY_INFO, fault_event_t::CODE_CAN_ERROR_FRAME, "CAN " + config_.interface,
                 "back to error-active on " + config_.interface + " at " + when + ": sending again");
  }
}

template <std::size_t N>
void CanBridgeNode::send_message(const std::array<can_frame, N>& frames, CanLinkFaults::Direction direction,
                                 int64_t message, int64_t utime) {
  if (link_faults_->empty()) {
    for (const can_frame& f : frames) send(f);
    return;
  }
  update_bus_off(utime);
  for (std::size_t j = 0; j < N; ++j) {
    can_frame f = frames[j];
    int bit = 0;
    switch (link_faults_->fate(direction, message, static_cast<int>(j), utime, f.len, &bit)) {
      case CanLinkFaults::Fate::kSent: send(f); break;
      case CanLinkFaults::Fate::kCorrupted:
        f.data[bit / 8] ^= static_cast<uint8_t>(1u << (bit % 8));
        send(f);
        break;
      case CanLinkFaults::Fate::kLost:
      case CanLinkFaults::Fate::kBusOff: ++frames_withheld_; break;
    }
  }
}

void CanBridgeNode::on_command_crossed() {
  ++commands_crossed_;
  skip_lost_commands();
  if (node_->ack_held() && commands_crossed_ >= cycles_due_) node_->release_ack();
}

void CanBridgeNode::log_frame(const ReceivedFrame& rx) {
  if (!candump_) return;
  const int64_t t = rx.has_kernel_time ? rx.kernel_time_ns : realtime_ns();
  const bool ok =
      rx.is_fd ? candump_->write(rx.fd_frame, t, config_.interface) : candump_->write(rx.frame, t, config_.interface);
  if (!ok) candump_failed();
}

void CanBridgeNode::candump_failed() {
  if (candump_failure_reported_) return;
  candump_failure_reported_ = true;
  // The bus record lost frames: the run ends on it, named, as it does for the run's own log.
  node_->fault(fault_event_t::SEVERITY_FATAL, fault_event_t::CODE_OTHER, "candump", candump_->failure());
  node_->end_run();
}

void CanBridgeNode::send(const can_frame& frame) {
  SendResult r;
  if (config_.fd) {
    const canfd_frame fd_frame = to_fd_frame(frame, CANFD_BRS);
    r = socket_->send(fd_frame);
    if (candump_ && !candump_->write(fd_frame, realtime_ns(), config_.interface)) candump_failed();
  } else {
    r = socket_->send(frame);
    if (candump_ && !candump_->write(frame, realtime_ns(), config_.interface)) candump_failed();
  }
  if (r == SendResult::kSent) return;
  node_->fault(fault_event_t::SEVERITY_ERROR, fault_event_t::CODE_QUEUE_DROP, "CAN " + config_.interface,
               "frame " + hex_id(frame) + " not sent on " + config_.interface + ": " +
                   (r == SendResult::kDropped ? "transmit queue full after every retry (ENOBUFS)"
                                              : std::string(std::strerror(socket_->stats().last_errno))));
}

void CanBridgeNode::on_command(const actuator_command_t& cmd) {
  send_message(command_encoder_.encode(cmd), CanLinkFaults::Direction::kCommand, command_messages_++, cmd.utime);
  ++messages_to_can_;
  on_command_crossed();
}

void CanBridgeNode::on_feedback(const actuator_feedback_t& fb) {
  send_message(feedback_encoder_.encode(fb), CanLinkFaults::Direction::kFeedback, feedback_messages_++, fb.utime);
  ++messages_to_can_;
}

int CanBridgeNode::drain_socket() {
  ReceivedFrame rx;
  // Bounded, so that a flooded bus cannot starve LCM; the wait loop comes back at once.
  int n = 0;
  for (; n < 256 && socket_->receive(&rx, 0) == ReceiveResult::kFrame; ++n) {
    if (rx.is_error_frame)
      on_error_frame(rx);
    else
      on_frame(rx);
  }
  return n;
}

void CanBridgeNode::on_frame(const ReceivedFrame& rx) {
  log_frame(rx);
  // An FD frame of up to 8 bytes is in rx.frame as a classical one; a longer one has length 0
  // there, which the decoders report as a wrong length (or an unknown identifier).
  if (role_ == Role::kRig) {
    actuator_command_t cmd;
    const DecodeResult r = command_decoder_.decode(rx.frame, &cmd);
    if (r == DecodeResult::kMessageComplete) {
      // Lockstep: the command of the next control cycle still owed an acknowledgement.
      cmd.utime = node_->lockstep() ? commands_crossed_ * cycle_period_ns_ / 1000 : rig_time_us();
      cmd.source = node_->name();
      cmd.input_utime = -1;
      node_->bus().publish(ch::kActuatorCommandCan, cmd);
      ++messages_to_lcm_;
      on_command_crossed();
    } else if (r != DecodeResult::kAccepted) {
      reject(rx, r);
    }
  } else {
    actuator_feedback_t fb;
    const DecodeResult r = feedback_decoder_.decode(rx.frame, &fb);
    if (r == DecodeResult::kMessageComplete) {
      fb.utime = rig_time_us();
      fb.seq = feedback_seq_++;
      node_->bus().publish(ch::kActuatorFeedbackCan, fb);
      ++messages_to_lcm_;
    } else if (r != DecodeResult::kAccepted) {
      reject(rx, r);
    }
  }
}

void CanBridgeNode::reject(const ReceivedFrame& rx, DecodeResult result) {
  const unsigned len =
      rx.is_fd ? std::min<unsigned>(rx.fd_frame.len, CANFD_MAX_DLEN) : std::min<unsigned>(rx.frame.len, CAN_MAX_DLEN);
  const uint8_t* bytes = rx.is_fd ? rx.fd_frame.data : rx.frame.data;
  std::string data;
  char byte[4];
  for (unsigned i = 0; i < len; ++i) {
    std::snprintf(byte, sizeof byte, "%02X ", bytes[i]);
    data += byte;
  }
  node_->fault(fault_event_t::SEVERITY_WARNING, fault_event_t::CODE_MESSAGE_MALFORMED, "CAN " + config_.interface,
               std::string("dropped ") + (rx.is_fd ? "FD frame " : "frame ") + hex_id(rx.frame) + " [" +
                   std::to_string(len) + "] " + data + "on " + config_.interface + ": " + to_string(result));
}

void CanBridgeNode::on_error_frame(const ReceivedFrame& rx) {
  log_frame(rx);
  const ErrorFrameInfo& e = rx.error;
  if (e.bus_off)
    bus_state_ = CanHealth::kBusOff;
  else if (e.error_passive)
    bus_state_ = CanHealth::kBusPassive;
  else if (e.error_warning)
    bus_state_ = CanHealth::kBusWarning;
  else if (e.back_to_error_active || e.restarted)
    bus_state_ = CanHealth::kBusActive;
  last_error_ = e.description;
  node_->fault(e.bus_off ? fault_event_t::SEVERITY_ERROR : fault_event_t::SEVERITY_WARNING,
               fault_event_t::CODE_CAN_ERROR_FRAME, "CAN " + config_.interface,
               "error frame on " + config_.interface + ": " + e.description);
}

void CanBridgeNode::publish_health() {
  const CanSocketStats& s = socket_->stats();
  const DecodeStats& d = role_ == Role::kRig ? command_decoder_.stats() : feedback_decoder_.stats();
  const EncodeStats& enc = role_ == Role::kFlight ? command_encoder_.stats() : feedback_encoder_.stats();
  CanHealth h;
  h.utime = transport::wall_us();
  h.seq = health_seq_++;
  h.process = node_->name();
  h.role = role_ == Role::kFlight ? CanHealth::kRoleFlight : CanHealth::kRoleRig;
  h.interface_name = config_.interface;
  h.messages_to_can = messages_to_can_;
  h.messages_to_lcm = messages_to_lcm_;
  h.frames_sent = static_cast<int64_t>(s.frames_sent);
  h.frames_received = static_cast<int64_t>(s.frames_received);
  h.fd = config_.fd;
  h.fd_frames_sent = static_cast<int64_t>(s.fd_frames_sent);
  h.fd_frames_received = static_cast<int64_t>(s.fd_frames_received);
  h.send_enobufs = static_cast<int64_t>(s.send_enobufs);
  h.send_retries = static_cast<int64_t>(s.send_retries);
  h.send_dropped = static_cast<int64_t>(s.send_dropped + s.send_errors);
  h.receive_dropped = static_cast<int64_t>(s.receive_dropped);
  h.rejected_unknown_id = static_cast<int64_t>(d.unknown_id);
  h.rejected_wrong_length = static_cast<int64_t>(d.wrong_length);
  h.rejected_bad_checksum = static_cast<int64_t>(d.bad_checksum);
  h.rejected_stale_counter = static_cast<int64_t>(d.stale_counter);
  h.rejected_out_of_range = static_cast<int64_t>(d.out_of_range);
  h.counter_gaps = static_cast<int64_t>(d.counter_gaps);
  h.saturated_values = static_cast<int64_t>(enc.saturated_values + enc.non_finite_values);
  h.error_frames = static_cast<int64_t>(s.error_frames);
  h.bus_state = bus_state_;
  h.last_error = last_error_;
  h.candump_file = candump_ ? candump_->path() : "";
  h.candump_lines = candump_ ? static_cast<int64_t>(candump_->lines_written()) : 0;
  node_->bus().publish(ch::kCanHealth, contract::to_message(h));
  next_health_wall_ns_ = transport::monotonic_ns() + health_period_ns_;
  if (candump_ && !candump_->flush()) candump_failed();
}

}  // namespace nimble::can
