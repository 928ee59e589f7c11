#include "mocap/mocap_node.h"

#include <nimble/mocap_pose_t.hpp>
#include <nimble/truth_state_t.hpp>

#include "sensors/sensor_config.h"

namespace nimble {

MocapNode::MocapNode(const Scenario& scenario, const transport::NodeOptions& options) {
  ConfigMap section = scenario.section("sensing");
  const SensorConfig sensing = sensor_config_from(section);
  // An offset keeps the mocap noise independent of the IMU noise of the same seed.
  emulator_ = std::make_unique<MocapEmulator>(sensing.mocap, scenario.seed + 0x6d6f636170ULL);
  node_ = std::make_unique<transport::ProcessNode>(options);
  node_->set_expected_rate(contract::channels::kTruth, 1000.0);
  node_->bus().subscribe<truth_state_t>(contract::channels::kTruth, [this](const truth_state_t& t) {
    MocapTruthInput in;
    in.utime = t.utime;
    in.position_ned_m = Eigen::Vector3d(t.position_ned_m[0], t.position_ned_m[1], t.position_ned_m[2]);
    in.q_body_to_ned =
        Eigen::Quaterniond(t.quaternion_wxyz[0], t.quaternion_wxyz[1], t.quaternion_wxyz[2], t.quaternion_wxyz[3]);
    for (const MocapPose& pose : emulator_->step(in)) {
      if (node_->lockstep()) outbox_.push(pose.publish_utime, pose);
      else publish(pose);
    }
  });
  // Lockstep ticks only: in real time frames go out as the truth shows they are due.
  node_->add_task("mocap", sensing.mocap.frame_rate_hz, [this](int64_t t) { flush(t); },
                  transport::ProcessNode::Trigger::kInput);
}

int MocapNode::run() { return node_->run(); }

void MocapNode::flush(int64_t sim_time_ns) {
  outbox_.drain(sim_time_ns / 1000, [this](const MocapPose& pose) { publish(pose); });
}

void MocapNode::publish(const MocapPose& pose) {
  mocap_pose_t m;
  m.utime = pose.utime;
  m.seq = pose.seq;
  m.frame_number = pose.frame_number;
  m.latency_us = pose.latency_us;
  m.rigid_body_id = pose.rigid_body_id;
  for (int i = 0; i < 3; ++i) m.position_m[i] = pose.position_ned_m[i];
  m.quaternion_wxyz[0] = pose.q_body_to_ned.w();
  m.quaternion_wxyz[1] = pose.q_body_to_ned.x();
  m.quaternion_wxyz[2] = pose.q_body_to_ned.y();
  m.quaternion_wxyz[3] = pose.q_body_to_ned.z();
  m.tracking_valid = pose.tracking_valid;
  m.mean_marker_error_m = pose.mean_marker_error_m;
  m.num_markers = pose.num_markers;
  node_->bus().publish(contract::channels::kMocapPose, m);
}

}  // namespace nimble
