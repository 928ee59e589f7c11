#pragma once
/// What `rig loop` takes from a scenario: the model, the controller and its gain sets, the
/// flap actuator and the loop's timing (controller/roll_loop.h), and the derivative box of its
/// robustness line.

#include <map>
#include <string>
#include <vector>

#include "contract/default_rates.h"
#include "controller/attitude_controller.h"
#include "controller/roll_loop.h"
#include "core/model.h"
#include "core/vehicle.h"
#include "scenario/scenario.h"

namespace nimble::loop {

/// The loop of a scenario, as the rig flies it.
struct LoopSetup {
  std::string scenario_file;
  DerivativeModel model;
  Vehicle vehicle;
  ControllerConfig controller;
  std::string gain_set;           ///< the set the scenario's manoeuvre flies
  double flap_gain_per_s = 8.97;  ///< the plant's flap actuator
  double flap_pole_radps = 12.56;
  double plant_rate_hz = contract::kDefaultPlantRateHz;
  std::string input;                           ///< truth | estimate: what the controller flies on
  std::string clock;                           ///< realtime | lockstep | inprocess: whose timing the loop has
  std::string trigger;                         ///< state | timer: what starts a real-time controller cycle
  double pipeline_latency_s = 0.0;             ///< from the input's sample to the command's action
  double actuator_delay_s = 0.0;               ///< the plant's actuator_delay effect, whole plant steps
  std::vector<std::string> nonlinear_effects;  ///< plant effects on that the linear loop leaves out
  /// The latency the loop has: pipeline + actuator delay [s].
  double latency_s() const { return pipeline_latency_s + actuator_delay_s; }
  /// The roll loop with `gains` (the controller's rate, cut-off, map and reference generator).
  RollLoopConfig loop_config(const GainSet& gains) const;
};

/// Reads `file` with `overrides`. `model_file` (if not empty) replaces the scenario's model;
/// `input` ("" or truth | estimate) replaces what the controller flies on, `clock` ("" or a
/// clock) the scenario's clock.
/// @throws ConfigError or std::invalid_argument naming the problem.
LoopSetup loop_setup(const std::string& file, const std::vector<Override>& overrides, const std::string& model_file,
                     const std::string& input, const std::string& clock = "");

/// The latency from the controller's input sample to its command's action (docs/loop.md):
///  - lockstep and in process: each consumer takes what was published at earlier ticks. On the
///    truth none (the controller ticks on the plant step whose TRUTH it reads, and the plant's
///    next step integrates from there with the new command); on the estimate two control
///    periods (the IMU sample reaches the estimator one period later, its estimate the
///    controller one more; 3.907 ms measured on a hover log, mean).
///  - real time, each cycle started by its state (run.controller_trigger state): none; the
///    chain IMU -> estimator -> controller -> plant takes a few hundred us (bench_rig), within the
///    plant step that integrates with the new command.
///  - real time on the controller's own timer: up to one control period; one period is assumed.
double pipeline_latency_s(const std::string& input, const std::string& clock, const std::string& trigger,
                          double control_rate_hz);

/// A derivative box: centre values and standard deviations of the loop's derivatives.
struct DerivativeBox {
  std::string source;                   ///< the file it came from
  std::map<std::string, double> value;  ///< centre
  std::map<std::string, double> sigma;  ///< standard deviations
};

/// The derivatives of the roll loop: Lp Lv L_df Yp Yv Y_df.
const std::vector<std::string>& loop_derivatives();

/// The box of `file`: a `rig identify --json` report (parameters.<name>.value and .sigma) or a
/// model file with published.sigma.
/// @throws std::invalid_argument naming the file and a missing derivative or sigma.
DerivativeBox derivative_box(const std::string& file);

/// The box of a model's published sigma (values: the model's).
/// @throws std::invalid_argument naming a missing sigma.
DerivativeBox derivative_box(const DerivativeModel& model);

/// `model` with the derivatives of `box` at centre + signs[i] * k * sigma (signs: -1, 0, +1,
/// one per loop_derivatives() entry).
DerivativeModel box_point(const DerivativeModel& model, const DerivativeBox& box, const std::vector<int>& signs,
                          double k = 2.0);

}  // namespace nimble::loop
