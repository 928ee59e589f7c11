#pragma once
/// The plant process: PlantModel on the rig's LCM bus.
///
/// Subscribes:
///   ACTUATOR_CMD  actuator_command_t   512 Hz   left/right flapping frequencies, servos; over
///                                      the CAN link (actuator_link: can) ACTUATOR_CMD_CAN instead,
///                                      as the rig side of nimble_can_bridge decoded it
///   RUN_CONTROL   run_control_t        events   start/stop (ProcessNode)
///   STEP_ACK      step_ack_t           lockstep (ProcessNode, the plant is the lockstep master)
/// Publishes:
///   TRUTH         truth_state_t        plant.truth_rate_hz (default 1 kHz)
///   IMU           imu_sample_t         sensing.imu.sample_rate_hz (default 512 Hz): the onboard
///                                      IMU emulated from the truth (sensors/imu_model.h), each
///                                      sample taken at the first plant step at or after its time
///   ACTUATOR_FB   actuator_feedback_t  plant.feedback_rate_hz (default 100 Hz)
///   RIG_CLOCK     rig_clock_t          lockstep only, once per plant step
///   FAULT         fault_event_t        command timeout, malformed or out-of-range commands
///   HEARTBEAT, TIMING_HEALTH           (ProcessNode)
///
/// Command timeout: when no ACTUATOR_CMD has arrived for plant.command_timeout_s of simulated
/// time, the plant holds the safe state (both wings at the trim flapping frequency, servos
/// neutral), reports it in ACTUATOR_FB.safe_state and publishes a FAULT; it leaves the safe
/// state on the next valid command. Commands are rounded to plant.command_resolution, the
/// resolution of the actuator interface. The decoding, clamps, rounding and timeout are
/// ActuatorInterface's (plant/actuator_interface.h); this node publishes what it raises.

#include <memory>
#include <optional>
#include <vector>

#include <nimble/actuator_command_t.hpp>

#include "sensors/imu_model.h"
#include "plant/actuator_interface.h"
#include "plant/plant_model.h"
#include "scenario/scenario.h"
#include "transport/node.h"

namespace nimble::plant {

/// The plant model of a scenario: its lateral model, optional longitudinal model and vehicle
/// (the scenario's, else the lateral model's) with `config`.
/// @throws ConfigError for a file that does not load; std::invalid_argument if the models do
///         not fit together (PlantModel).
std::unique_ptr<PlantModel> plant_model_for(const Scenario& scenario, const PlantConfig& config);

class PlantNode {
 public:
  /// Builds the model from the scenario; @throws ConfigError on bad configuration.
  PlantNode(const Scenario& scenario, const transport::NodeOptions& options);
  /// Runs until stopped; returns the exit code.
  int run();
  /// The process frame (its bus, for in-process tests on memq://).
  transport::ProcessNode& node() { return *node_; }

 private:
  void on_command(const actuator_command_t& cmd);
  /// Publishes an event of the actuator interface as a FAULT on the command channel.
  void report(const ActuatorEvent& event);
  void step(int64_t sim_time_ns);
  void publish_truth(int64_t sim_time_ns);
  void publish_feedback(int64_t sim_time_ns);
  void publish_imu(int64_t sim_time_ns);

  PlantConfig config_;
  std::unique_ptr<PlantModel> model_;
  std::unique_ptr<ImuModel> imu_;
  int64_t imu_period_ns_ = 0;
  int64_t imu_next_ns_ = 0;
  int64_t imu_seq_ = 0;
  std::unique_ptr<transport::ProcessNode> node_;
  std::unique_ptr<ActuatorInterface> actuators_;
  std::string command_channel_;          ///< ACTUATOR_CMD, or ACTUATOR_CMD_CAN over the CAN link
  bool controller_on_estimate_ = false;  ///< run.controller_input: estimate (the IMU goes out first)
  int64_t step_index_ = 0;
  int64_t truth_every_ = 1;
  int64_t feedback_every_ = 10;
  int64_t truth_seq_ = 0;
  int64_t feedback_seq_ = 0;
  /// CLOCK_MONOTONIC time at which the current step's outputs (IMU, TRUTH) started going out.
  int64_t step_out_ns_ = 0;
  /// The control loop's stages the plant times (ProcessNode::add_stage): the IMU sample going
  /// out, the command computed from it coming back (each as the sample's age).
  int stage_imu_out_ = -1, stage_command_in_ = -1;
  /// For recent TRUTH messages, by seq modulo the ring size: the time their step's outputs
  /// started going out, to measure the control loop's latency from
  /// actuator_command_t.input_utime (the state's time the command was computed from).
  struct Published {
    int64_t utime = -1;
    int64_t wall_ns = 0;
  };
  std::vector<Published> published_ = std::vector<Published>(256);
};

}  // namespace nimble::plant
