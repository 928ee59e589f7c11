#include "mocap/mocap_node.h"

#include "contract/messages.h"

#include "sensors/sensor_config.h"
#include "transport/process_main.h"

namespace nimble {

MocapNode::MocapNode(const Scenario& scenario, const transport::NodeOptions& options) {
  ConfigMap section = scenario.section("sensing");
  const SensorConfig sensing = sensor_config_from(section);
  // An offset keeps the mocap noise independent of the IMU noise of the same seed.
  emulator_ = std::make_unique<MocapEmulator>(sensing.mocap, scenario.seed + 0x6d6f636170ULL);
  node_ = transport::make_process_node(scenario, options);
  node_->set_expected_rate(contract::channels::kTruth, scenario.expected_rate(contract::channels::kTruth));
  node_->bus().subscribe<truth_state_t>(contract::channels::kTruth, [this](const truth_state_t& t) {
    if (!transport::plausible_sim_utime(t.utime)) {
      // Found by fuzz_node_mocap: the emulator captured every frame up to a stray time.
      node_->fault(fault_event_t::SEVERITY_WARNING, fault_event_t::CODE_MESSAGE_MALFORMED, contract::channels::kTruth,
                   "TRUTH at utime " + std::to_string(t.utime) + " us lies outside any run; ignored");
      return;
    }
    const Truth truth = contract::from_message(t);
    MocapTruthInput in;
    in.utime = t.utime;
    in.position_ned_m = truth.position_ned_m;
    const Eigen::Vector4d& q = truth.quaternion_wxyz;
    in.q_body_to_ned = Eigen::Quaterniond(q[0], q[1], q[2], q[3]);
    for (const MocapPose& pose : emulator_->step(in)) {
      if (node_->lockstep())
        outbox_.push(pose.publish_utime, pose);
      else
        publish(pose);
    }
  });
  // Lockstep ticks only: in real time frames go out as the truth shows they are due.
  node_->add_task(
      "mocap", sensing.mocap.frame_rate_hz, [this](int64_t t) { flush(t); }, transport::ProcessNode::Trigger::kInput);
}

int MocapNode::run() { return node_->run(); }

void MocapNode::flush(int64_t sim_time_ns) {
  const int64_t tick_utime = sim_time_ns / 1000;
  outbox_.drain(tick_utime, [this, tick_utime](MocapPose pose) {
    // The frame goes out at this tick, so it says so: a consumer takes a message published at
    // a tick from its next tick on, whether it arrives before its own turn at this tick or
    // after. Stamped with its due time instead, it would count at this tick if it arrived in
    // time, and the run would depend on process timing.
    pose.publish_utime = tick_utime;
    pose.latency_us = static_cast<int32_t>(tick_utime - pose.utime);
    publish(pose);
  });
}

void MocapNode::publish(const MocapPose& pose) {
  node_->bus().publish(contract::channels::kMocapPose, contract::to_message(pose));
}

}  // namespace nimble
