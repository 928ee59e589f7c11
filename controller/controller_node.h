#pragma once
/// The attitude controller process: ManoeuvrePlayer + AttitudeController on the rig's bus.
///
/// Subscribes:
///   TRUTH          truth_state_t        plant rate   attitude and rates (run.controller_input: truth)
///   ESTIMATE       estimator_state_t    512 Hz       attitude and corrected rates (run.controller_input: estimate)
///   MOCAP_POSE     mocap_pose_t         200 Hz       the pilot's height (pilot.enabled; controller/pilot.h;
///                                                    without the process mocap, the TRUTH height)
///   RUN_CONTROL, RIG_CLOCK                            (ProcessNode; lockstep participant)
/// Publishes, each at controller.rate_hz (default 512 Hz):
///   ATTITUDE_SP        attitude_setpoint_t   the manoeuvre player's set-point
///   ACTUATOR_CMD       actuator_command_t    left/right flapping frequencies, servos (MODE_LEFT_RIGHT)
///   CONTROLLER_STATUS  controller_status_t   references, errors, gains, saturation
///   FAULT, HEARTBEAT, TIMING_HEALTH, STEP_ACK (ProcessNode)
///
/// Each control cycle uses the newest input. Failsafe (controller.failsafe): when the input is
/// older than input_stale_s (an estimate by the time of the IMU sample it rests on, so a
/// repeated or frozen estimate ages too), or none has come by first_input_timeout_s, the
/// controller raises CODE_INPUT_STALE and CODE_FAILSAFE and from then on, until the run ends,
/// commands zero roll and pitch (wings neutral, no differential flapping) at
/// failsafe.throttle_pct, a slow descent. CONTROLLER_STATUS carries `failsafe`.
///
/// With the `pilot` section enabled, the pilot's throttle correction (controller/pilot.h) is added
/// to the manoeuvre's throttle set-point before THRF; ATTITUDE_SP carries the sum.

#include <memory>

#include <nimble/estimator_state_t.hpp>
#include <nimble/truth_state_t.hpp>

#include "controller/attitude_controller.h"
#include "controller/manoeuvre.h"
#include "controller/pilot.h"
#include "scenario/scenario.h"
#include "transport/latched_input.h"
#include "transport/node.h"

namespace nimble {

class ControllerNode {
 public:
  /// @throws ConfigError on bad configuration.
  ControllerNode(const Scenario& scenario, const transport::NodeOptions& options);
  int run();
  /// The process frame (its bus, for in-process tests on memq://).
  transport::ProcessNode& node() { return *node_; }

 private:
  void cycle(int64_t sim_time_ns);

  ControllerConfig config_;
  std::unique_ptr<AttitudeController> controller_;
  std::unique_ptr<ManoeuvrePlayer> player_;
  /// The pilot on the throttle (pilot.enabled), fed the motion-capture height.
  std::unique_ptr<AltitudePilot> pilot_;
  /// No motion capture in the run (ideal sensing, flying on TRUTH): the pilot watches TRUTH.
  bool pilot_on_truth_ = false;
  std::unique_ptr<transport::ProcessNode> node_;
  /// The state the next cycle uses (from TRUTH or ESTIMATE).
  struct Input {
    int64_t utime = -1;           ///< the message's stamp (a lockstep estimate's tick)
    int64_t measured_utime = -1;  ///< the time the state refers to (an estimate: its IMU sample)
    double phi_rad = 0, theta_rad = 0, p_radps = 0, q_radps = 0, psi_rad = 0, r_radps = 0;
  };
  Input input_{};
  /// Estimates received (stamped with their tick): a lockstep cycle uses the newest one
  /// published at an earlier tick, whatever arrived meanwhile.
  transport::LatchedInput<Input> estimates_{transport::LatchedInput<Input>::Release::kAfterStamp, 8};
  bool use_estimate_ = false;
  /// The control loop's stages the controller times (ProcessNode::add_stage), on the estimate in
  /// real time, and when the newest estimate arrived [ns, CLOCK_MONOTONIC] (0: already used).
  int stage_estimate_in_ = -1, stage_command_out_ = -1, stage_work_ = -1, stage_publish_ = -1;
  int64_t input_received_ns_ = 0;
  bool have_input_ = false;
  bool failsafe_ = false;
  /// Engages the failsafe at `utime` for `why` (CODE_INPUT_STALE and CODE_FAILSAFE).
  void engage_failsafe(int64_t utime, const std::string& why);
  int64_t sp_seq_ = 0, cmd_seq_ = 0, status_seq_ = 0;
  int8_t rolling_counter_ = 0;
};

}  // namespace nimble
