#pragma once
/// The motion-capture emulator process: an OptiTrack-like rigid-body stream from the
/// plant's truth (sensors/mocap_emulator.h): 200 Hz frames stamped at mid-exposure,
/// marker noise (mean 3-D error 0.85 mm), attitude noise, a configurable latency, and
/// seeded occlusion bursts. Configured by the scenario's `sensing.mocap` section.
///
/// Subscribes:
///   TRUTH        truth_state_t   plant rate   position and attitude
///   RUN_CONTROL, RIG_CLOCK                     (ProcessNode; lockstep participant at the frame rate)
/// Publishes:
///   MOCAP_POSE   mocap_pose_t    200 Hz       each frame once its latency has passed
///   FAULT, HEARTBEAT, TIMING_HEALTH, STEP_ACK (ProcessNode)
///
/// Real time: a frame goes out as soon as the truth shows its publication time has come.
/// Lockstep: frames go out at the frame-rate ticks, so that what a consumer has seen at a
/// tick does not depend on process timing. A frame's latency_us is then its mid-exposure to
/// the tick it went out at (at least the configured latency, less than one frame period
/// more), so that its publication time is that tick and consumers take it from their next
/// tick on, as they take every other participant's messages.

#include <memory>

#include "sensors/mocap_emulator.h"
#include "scenario/scenario.h"
#include "transport/latched_input.h"
#include "transport/node.h"

namespace nimble {

class MocapNode {
 public:
  /// @throws ConfigError on bad configuration.
  MocapNode(const Scenario& scenario, const transport::NodeOptions& options);
  int run();
  transport::ProcessNode& node() { return *node_; }

 private:
  void publish(const MocapPose& pose);
  void flush(int64_t sim_time_ns);

  std::unique_ptr<MocapEmulator> emulator_;
  std::unique_ptr<transport::ProcessNode> node_;
  /// Lockstep: frames computed, each going out at the first tick at or after its publication time.
  transport::LatchedInput<MocapPose> outbox_{transport::LatchedInput<MocapPose>::Release::kAtStamp};
};

}  // namespace nimble
