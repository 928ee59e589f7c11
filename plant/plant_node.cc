#include "plant/plant_node.h"

#include <cmath>
#include <cstdio>

#include "contract/messages.h"
#include "sensors/sensor_config.h"
#include "transport/process_main.h"

namespace nimble::plant {
namespace {

using contract::channels::kActuatorFeedback;
using contract::channels::kTruth;

}  // namespace

std::unique_ptr<PlantModel> plant_model_for(const Scenario& scenario, const PlantConfig& config) {
  const DerivativeModel lateral = load_model(scenario.model_file);
  std::optional<DerivativeModel> longitudinal;
  if (!scenario.longitudinal_model_file.empty()) longitudinal = load_model(scenario.longitudinal_model_file);
  const Vehicle vehicle = load_vehicle(scenario.vehicle_file.empty() ? lateral.vehicle_file : scenario.vehicle_file);
  return std::make_unique<PlantModel>(lateral, longitudinal, vehicle, config);
}

PlantNode::PlantNode(const Scenario& scenario, const transport::NodeOptions& options) {
  ConfigMap section = scenario.section("plant");
  config_ = plant_config_from(section);
  config_.seed = scenario.seed;
  model_ = plant_model_for(scenario, config_);
  actuators_ = std::make_unique<ActuatorInterface>(config_, model_->trim_command());
  ConfigMap sensing_section = scenario.section("sensing");
  const SensorConfig sensing = sensor_config_from(sensing_section);
  imu_ = std::make_unique<ImuModel>(sensing.imu, scenario.seed);
  imu_period_ns_ = std::llround(1e9 / sensing.imu.sample_rate_hz);
  truth_every_ = std::llround(config_.rate_hz / config_.truth_rate_hz);
  feedback_every_ = std::llround(config_.rate_hz / config_.feedback_rate_hz);

  node_ = transport::make_process_node(scenario, options);
  node_->set_lockstep_master(true);
  node_->set_ack_timeout_ms(lockstep_options(scenario).ack_timeout_ms);
  command_channel_ = plant_command_channel(scenario);
  controller_on_estimate_ = process_run_options(scenario).controller_input == "estimate";
  node_->set_expected_rate(command_channel_, scenario.expected_rate(command_channel_));
  node_->bus().subscribe<actuator_command_t>(command_channel_, [this](const actuator_command_t& c) { on_command(c); });
  node_->add_task("plant", config_.rate_hz, [this](int64_t t) { step(t); });
  stage_imu_out_ = node_->add_stage("plant: IMU sample published");
  stage_command_in_ = node_->add_stage("plant: ACTUATOR_CMD received");
}

int PlantNode::run() { return node_->run(); }

void PlantNode::on_command(const actuator_command_t& cmd) {
  const ActuatorInterface::Result result = actuators_->command(contract::from_message(cmd), node_->sim_time_ns());
  if (result.accepted && cmd.input_utime >= 0 && node_->stage_timing()) {
    node_->record_stage_ns(stage_command_in_, node_->age_ns(cmd.input_utime));
  }
  if (result.accepted && cmd.input_utime >= 0) {
    for (const auto& p : published_) {
      if (p.utime == cmd.input_utime) {
        node_->record_latency_ns(transport::monotonic_ns() - p.wall_ns);
        break;
      }
    }
  }
  for (const ActuatorEvent& e : result.events) report(e);
}

void PlantNode::report(const ActuatorEvent& event) {
  int8_t severity = fault_event_t::SEVERITY_ERROR;
  int32_t code = fault_event_t::CODE_MESSAGE_MALFORMED;
  switch (event.kind) {
    case ActuatorEvent::Kind::kRejected: break;
    case ActuatorEvent::Kind::kClamped:
      severity = fault_event_t::SEVERITY_WARNING;
      code = fault_event_t::CODE_COMMAND_CLAMPED;
      break;
    case ActuatorEvent::Kind::kTimeout: code = fault_event_t::CODE_COMMAND_TIMEOUT; break;
    case ActuatorEvent::Kind::kResumed:
      severity = fault_event_t::SEVERITY_INFO;
      code = fault_event_t::CODE_COMMAND_TIMEOUT;
      break;
  }
  node_->fault(severity, code, command_channel_, event.message);
}

void PlantNode::step(int64_t sim_time_ns) {
  if (sim_time_ns > 0) {
    if (const auto event = actuators_->update(sim_time_ns)) report(*event);
    model_->step(actuators_->input());
    ++step_index_;
  }
  // The control loop's latency counts from here: the step's state starts going out.
  step_out_ns_ = transport::monotonic_ns();
  const bool imu_due = sim_time_ns >= imu_next_ns_;
  if (imu_due && node_->lockstep()) {
    // The IMU sample goes out after the step's tick: consumers take it at their next tick.
    node_->defer([this, sim_time_ns] { publish_imu(sim_time_ns); });
  } else if (imu_due && controller_on_estimate_) {
    // Real time, the controller on the estimate: the control loop starts with the IMU sample.
    publish_imu(sim_time_ns);
  }
  if (step_index_ % truth_every_ == 0) publish_truth(sim_time_ns);
  if (imu_due && !node_->lockstep() && !controller_on_estimate_) publish_imu(sim_time_ns);
  if (step_index_ % feedback_every_ == 0) publish_feedback(sim_time_ns);
}

void PlantNode::publish_truth(int64_t sim_time_ns) {
  const truth_state_t m =
      contract::to_message(model_->truth(), sim_time_ns / 1000, truth_seq_++, node_->lockstep() ? step_index_ : -1);
  node_->bus().publish(kTruth, m);
  published_[static_cast<std::size_t>(m.seq) % published_.size()] = {m.utime, step_out_ns_};
}

void PlantNode::publish_imu(int64_t sim_time_ns) {
  const Truth& t = model_->truth();
  ImuTruthInput in;
  in.utime = sim_time_ns / 1000;
  in.omega_body_radps = t.omega_body_radps;
  in.specific_force_body_mps2 = t.specific_force_body_mps2;
  in.flap_freq_left_radps = t.flap_freq_left_radps;
  in.flap_freq_right_radps = t.flap_freq_right_radps;
  imu_sample_t m = contract::to_message(imu_->sample(in));
  m.seq = imu_seq_++;
  // m.utime is the IMU's own clock (sensing.imu.clock_offset_s, clock_drift_ppm); a scenario's
  // faults on IMU are timed in rig time.
  node_->bus().publish(contract::channels::kImu, m, in.utime);
  if (node_->stage_timing()) node_->record_stage_ns(stage_imu_out_, node_->age_ns(in.utime));
  // Next sample: the first period boundary after this step.
  imu_next_ns_ = (sim_time_ns / imu_period_ns_ + 1) * imu_period_ns_;
}

void PlantNode::publish_feedback(int64_t sim_time_ns) {
  const Truth& t = model_->truth();
  ActuatorFeedback m;
  m.utime = sim_time_ns / 1000;
  m.seq = feedback_seq_++;
  m.flap_freq_left_radps = t.flap_freq_left_radps;
  m.flap_freq_right_radps = t.flap_freq_right_radps;
  m.delta_f_radps = t.delta_f_radps;
  m.dihedral_rad = t.dihedral_rad;
  m.wing_root_rad = t.wing_root_rad;
  m.throttle_pct = t.throttle_pct;
  m.cmd_seq = actuators_->last_command_seq();
  m.cmd_age_us = actuators_->command_age_us(sim_time_ns);
  m.safe_state = actuators_->safe_state();
  node_->bus().publish(kActuatorFeedback, contract::to_message(m));
}

}  // namespace nimble::plant
