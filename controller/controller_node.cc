#include "controller/controller_node.h"
#include "transport/process_main.h"

#include <cmath>
#include <cstdio>
#include <string>

#include "contract/messages.h"

namespace nimble {
namespace {

using contract::channels::kActuatorCommand;
using contract::channels::kAttitudeSetpoint;
using contract::channels::kControllerStatus;
using contract::channels::kTruth;

}  // namespace

ControllerNode::ControllerNode(const Scenario& scenario, const transport::NodeOptions& options) {
  ConfigMap section = scenario.section("controller");
  config_ = controller_config_from(section);
  const Manoeuvre manoeuvre = load_manoeuvre(manoeuvre_file(scenario, true, "the controller plays a manoeuvre file"));
  check_gain_sets(manoeuvre, config_);
  controller_ = std::make_unique<AttitudeController>(config_);
  player_ = std::make_unique<ManoeuvrePlayer>(manoeuvre, config_.trim_throttle_pct);

  ConfigMap pilot_section = scenario.section("pilot");
  const PilotConfig pilot = pilot_config_from(pilot_section);
  if (pilot.enabled) {
    pilot_ = std::make_unique<AltitudePilot>(
        pilot, throttle_accel_per_pct(config_.f_trim_radps, config_.throttle_to_freq_radps_per_pct));
  }

  const ProcessRunOptions run = process_run_options(scenario);
  node_ = transport::make_process_node(scenario, options);
  pilot_on_truth_ = pilot_ && !scenario.runs("mocap");
  if (pilot_ && !pilot_on_truth_) {
    // The pilot watches the vehicle's height (up = -down) as motion capture measures it; heights
    // are used reaction_delay_s after their exposure, long after they were published. Without
    // the motion capture (ideal sensing) he watches the TRUTH height (the TRUTH handler below).
    node_->bus().subscribe<mocap_pose_t>(contract::channels::kMocapPose, [this](const mocap_pose_t& message) {
      const MocapPose pose = contract::from_message(message);
      if (!pose.tracking_valid || !transport::plausible_sim_utime(pose.utime)) return;
      pilot_->observe(static_cast<double>(pose.utime) * 1e-6, -pose.position_ned_m[2]);
    });
  }
  node_->set_expected_rate(kTruth, scenario.expected_rate(kTruth));
  use_estimate_ = run.controller_input == "estimate";
  if (use_estimate_) {
    node_->set_expected_rate(contract::channels::kEstimate, scenario.expected_rate(contract::channels::kEstimate));
    node_->bus().subscribe<estimator_state_t>(contract::channels::kEstimate, [this](const estimator_state_t& message) {
      const Estimate e = contract::from_message(message);
      // Times outside any run are not an estimate to fly on (and would overflow its age).
      if (!transport::plausible_sim_utime(e.utime) || !transport::plausible_sim_utime(e.imu_utime)) {
        node_->fault(fault_event_t::SEVERITY_WARNING, fault_event_t::CODE_MESSAGE_MALFORMED,
                     contract::channels::kEstimate,
                     "estimate stamped outside any run (utime " + std::to_string(e.utime) + " us, imu_utime " +
                         std::to_string(e.imu_utime) + " us): not used");
        return;
      }
      const Input in{e.utime,        e.imu_utime,           e.euler_rad[0],
                     e.euler_rad[1], e.omega_body_radps[0], e.omega_body_radps[1],
                     e.euler_rad[2], e.omega_body_radps[2]};
      if (node_->lockstep()) {
        estimates_.push(in.utime, in);  // used from the next tick on (see cycle)
      } else {
        if (node_->stage_timing()) {
          input_received_ns_ = transport::monotonic_ns();
          node_->record_stage_ns(stage_estimate_in_, node_->age_ns(in.measured_utime, input_received_ns_));
        }
        input_ = in;
        have_input_ = true;
        node_->notify_input(transport::message_us_to_ns(e.imu_utime));
      }
    });
  } else {
    node_->bus().subscribe<truth_state_t>(kTruth, [this](const truth_state_t& message) {
      const int64_t utime = message.utime;  // exact: the truth's time_s is utime / 1e6
      if (!transport::plausible_sim_utime(utime)) {
        node_->fault(fault_event_t::SEVERITY_WARNING, fault_event_t::CODE_MESSAGE_MALFORMED, kTruth,
                     "TRUTH stamped outside any run (utime " + std::to_string(utime) + " us): not used");
        return;
      }
      const Truth t = contract::from_message(message);
      input_ = Input{utime,
                     utime,
                     t.euler_rad[0],
                     t.euler_rad[1],
                     t.omega_body_radps[0],
                     t.omega_body_radps[1],
                     t.euler_rad[2],
                     t.omega_body_radps[2]};
      if (pilot_on_truth_) pilot_->observe(static_cast<double>(utime) * 1e-6, -t.position_ned_m[2]);
      have_input_ = true;
      node_->notify_input(transport::message_us_to_ns(utime));
    });
  }
  stage_estimate_in_ = node_->add_stage("controller: ESTIMATE received");
  stage_command_out_ = node_->add_stage("controller: ACTUATOR_CMD published");
  stage_work_ = node_->add_stage("controller: its work, ESTIMATE received to ACTUATOR_CMD published");
  stage_publish_ = node_->add_stage("controller: its work, of which publishing ACTUATOR_CMD");
  node_->add_task(
      "controller", config_.rate_hz, [this](int64_t t) { cycle(t); },
      run.controller_trigger == "state" ? transport::ProcessNode::Trigger::kInput
                                        : transport::ProcessNode::Trigger::kTimer,
      // Triggered by its input, it still runs once that input is stale, to take the failsafe.
      static_cast<int64_t>(config_.input_stale_s * 1e9));
}

int ControllerNode::run() { return node_->run(); }

void ControllerNode::engage_failsafe(int64_t utime, const std::string& why) {
  failsafe_ = true;
  const std::string& channel = use_estimate_ ? contract::channels::kEstimate : kTruth;
  char when[40];
  std::snprintf(when, sizeof when, "at t = %.3f s", 1e-6 * static_cast<double>(utime));
  node_->fault(fault_event_t::SEVERITY_WARNING, fault_event_t::CODE_INPUT_STALE, channel,
               std::string("controller input ") + channel + " " + when + ": " + why);
  char action[120];
  std::snprintf(action, sizeof action, "zero roll and pitch commands at %.1f %% throttle until the run ends",
                config_.failsafe_throttle_pct);
  node_->fault(fault_event_t::SEVERITY_ERROR, fault_event_t::CODE_FAILSAFE, channel,
               std::string("failsafe engaged ") + when + " (" + channel + ": " + why + "): " + action);
}

void ControllerNode::cycle(int64_t sim_time_ns) {
  const double t_s = static_cast<double>(sim_time_ns) / 1e9;
  const int64_t utime = sim_time_ns / 1000;
  const Setpoint sp = player_->at(t_s);
  if (!sp.gain_set.empty() && sp.gain_set != controller_->gain_set()) controller_->select_gain_set(sp.gain_set);

  // Lockstep on estimates: an estimate published at an earlier tick (its utime is the tick
  // time) is used; one published at this very tick waits for the next cycle.
  if (use_estimate_ && node_->lockstep()) {
    if (const Input* latched = estimates_.newest(utime)) {
      input_ = *latched;
      have_input_ = true;
    }
  }
  ControllerInput in;
  in.phi_rad = input_.phi_rad;
  in.theta_rad = input_.theta_rad;
  in.p_radps = input_.p_radps;
  in.q_radps = input_.q_radps;
  in.psi_rad = input_.psi_rad;
  in.r_radps = input_.r_radps;
  in.roll_sp_rad = sp.roll_sp_rad;
  in.pitch_sp_rad = sp.pitch_sp_rad;
  in.throttle_pct = sp.throttle_pct + (pilot_ ? pilot_->correction_pct(t_s) : 0.0);
  in.throttle_factor = sp.throttle_factor;
  const int64_t input_age_us = have_input_ ? utime - input_.measured_utime : -1;
  if (!failsafe_) {
    // Not finite is as good as none: the controller never flies on NaN.
    const bool finite = std::isfinite(in.phi_rad) && std::isfinite(in.theta_rad) && std::isfinite(in.p_radps) &&
                        std::isfinite(in.q_radps);
    if (have_input_ && input_age_us > static_cast<int64_t>(config_.input_stale_s * 1e6)) {
      engage_failsafe(utime, "its input is " + std::to_string(input_age_us / 1000) + " ms old (limit " +
                                 std::to_string(static_cast<int>(config_.input_stale_s * 1e3)) + " ms)");
    } else if (!have_input_ && utime > static_cast<int64_t>(config_.first_input_timeout_s * 1e6)) {
      engage_failsafe(utime, "no input at all after " + std::to_string(config_.first_input_timeout_s) + " s");
    } else if (have_input_ && !finite) {
      engage_failsafe(utime, "its input is not finite");
    }
  }
  const ControllerOutput out =
      failsafe_ ? controller_->failsafe_output(config_.failsafe_throttle_pct) : controller_->step(in);
  // The command goes out first: it is what the plant waits for.

  ActuatorCommand cmd;
  cmd.utime = utime;
  cmd.seq = cmd_seq_++;
  cmd.mode = ActuatorCommand::kModeLeftRight;
  cmd.flap_freq_left_radps = out.flap_freq_left_radps;
  cmd.flap_freq_right_radps = out.flap_freq_right_radps;
  cmd.delta_f_radps = out.delta_f_cmd_radps;
  cmd.flap_freq_collective_radps = out.collective_radps;
  cmd.throttle_pct = out.throttle_cmd_pct;
  cmd.dihedral_rad = out.dihedral_rad;
  cmd.wing_root_rad = out.wing_root_rad;
  cmd.input_utime = have_input_ ? input_.utime : -1;
  cmd.rolling_counter = rolling_counter_;
  rolling_counter_ = static_cast<int8_t>((rolling_counter_ + 1) % 16);
  cmd.source = node_->name();
  const int64_t publish_ns = transport::monotonic_ns();
  node_->bus().publish(kActuatorCommand, contract::to_message(cmd));
  if (use_estimate_ && have_input_ && input_received_ns_ > 0 && node_->stage_timing()) {
    // Once per estimate: the command computed from it.
    const int64_t done_ns = transport::monotonic_ns();
    node_->record_stage_ns(stage_command_out_, node_->age_ns(input_.measured_utime, done_ns));
    node_->record_stage_ns(stage_work_, done_ns - input_received_ns_);
    node_->record_stage_ns(stage_publish_, done_ns - publish_ns);
    input_received_ns_ = 0;
  }

  // Set-point and status records go out after the command and the step's acknowledgement.
  const double throttle_sp_pct = in.throttle_pct;
  node_->defer([this, sp, out, utime, input_age_us, throttle_sp_pct] {
    AttitudeSetpoint asp;
    asp.utime = utime;
    asp.seq = sp_seq_++;
    asp.roll_sp_rad = sp.roll_sp_rad;
    asp.pitch_sp_rad = sp.pitch_sp_rad;
    asp.yaw_rate_sp_radps = 0.0;
    asp.throttle_pct = throttle_sp_pct;
    asp.throttle_factor = sp.throttle_factor;
    asp.manoeuvre = sp.manoeuvre;
    asp.segment_index = sp.segment_index;
    asp.segment_name = sp.segment_name;
    asp.gain_set = controller_->gain_set();
    node_->bus().publish(kAttitudeSetpoint, contract::to_message(asp));

    ControllerStatus st;
    st.utime = utime;
    st.seq = status_seq_++;
    st.gain_set = controller_->gain_set();
    st.kp = out.roll_kp_per_rad;
    st.kd = out.roll_kd_per_radps;
    st.roll_ref_rad = out.roll_ref_rad;
    st.roll_rate_ref_radps = out.roll_rate_ref_radps;
    st.roll_error_rad = out.roll_error_rad;
    st.roll_cmd_norm = out.roll_cmd_norm;
    st.pitch_cmd_norm = out.pitch_cmd_norm;
    st.delta_f_cmd_radps = out.delta_f_cmd_radps;
    st.throttle_pct = out.throttle_cmd_pct;
    st.saturated = out.saturated;
    st.input_source = use_estimate_ ? ControllerStatus::kInputEstimate : ControllerStatus::kInputTruth;
    st.input_age_us = input_age_us;
    st.failsafe = failsafe_;
    node_->bus().publish(kControllerStatus, contract::to_message(st));
  });
}

}  // namespace nimble
