#pragma once
/// The analyses `rig loop` reports (cli/loop_command.cc; loop/loop_study.h runs them), their
/// text, JSON and plots, and the frequency response the plots draw.

#include <string>
#include <vector>

#include "loop/loop_setup.h"
#include "controller/roll_loop.h"

namespace nimble::loop {

/// One analysed loop: a model with a gain set, broken at one point.
struct LoopRow {
  std::string model;  ///< the model's name
  std::string gains;  ///< the gain set's name
  GainSet gain_values;
  LoopBreak where = LoopBreak::kActuator;
  RollLoopConfig config;
  StateSpace lateral;  ///< the model's state space
  RollLoopAnalysis analysis;
};

/// The worst margins over a family of loops, each naming the loop it comes from.
struct WorstMargins {
  std::string gains;  ///< the gain set
  std::string over;   ///< what the family is ("sets 1-5", "nimble_lateral_set1 +-2 sigma")
  int loops = 0, unstable = 0;
  double gain_margin_db = INFINITY, phase_margin_deg = INFINITY, delay_margin_ms = INFINITY;
  double gain_reduction_margin_db = -INFINITY, sensitivity_peak = 0.0;
  std::string gain_margin_at, phase_margin_at, delay_margin_at, gain_reduction_margin_at, sensitivity_peak_at;
  std::string unstable_at;  ///< the first unstable loop
  /// Box only: the derivatives that alone, at +-2 sigma with the others at their centre, leave
  /// the loop unstable ("Lv-"), and every corner's count of unstable corners by the sign of
  /// each derivative ("Lv-": 32 of 32).
  std::vector<std::string> unstable_alone;
  std::vector<std::pair<std::string, int>> unstable_by_sign;
  /// Takes in one loop, named `name`.
  void add(const std::string& name, const RollLoopAnalysis& a);
};

/// The header: model, timing, what the linear loop leaves out.
std::string loop_header_text(const LoopSetup& setup, const std::string& scenario);
/// One loop in full (margins, bandwidth, poles).
std::string loop_text(const LoopRow& row);
/// The table of many loops.
std::string loop_table_text(const std::vector<LoopRow>& rows);
/// One robustness line.
std::string worst_text(const WorstMargins& w);

/// A design and what it reached.
struct DesignOutcome {
  DesignRequest request;
  RollDesign design;
  std::string name;  ///< the gain set's name in --gains-out
  std::string model;
  std::string flight;  ///< the flight's verdict with --fly ("" without)
  int flight_exit = 0;
};
std::string design_text(const DesignOutcome& d);
/// The gain set as a controller configuration fragment (rig_configs/controller format).
std::string design_yaml(const DesignOutcome& d, const std::string& command);

/// The JSON report: {"scenario", "latency_s", "input", "loops": [...], "robustness": [...],
/// "design": {...}}.
std::string loop_json(const LoopSetup& setup, const std::vector<LoopRow>& rows, const std::vector<WorstMargins>& worst,
                      const DesignOutcome* design);

/// loop_bode.png, loop_nyquist.png, loop_step.png, loop_poles.png of `rows` into `dir`;
/// returns the PNG paths. @throws std::runtime_error if gnuplot fails.
std::vector<std::string> plot_loops(const std::string& dir, const std::vector<LoopRow>& rows);

/// The frequencies the Bode and Nyquist plots draw the loops at [rad/s]: 800 points, evenly
/// spaced in log frequency from 0.01 Hz to the Nyquist frequency of a controller at `rate_hz`.
std::vector<double> response_grid_radps(double rate_hz);

/// The frequency response of `row`'s loop at `omega_radps`: its return ratio L at the break and
/// phi/phi_ref (controller/roll_loop.h roll_loop_response).
RollLoopResponse row_response(const LoopRow& row, const std::vector<double>& omega_radps);

/// The same on response_grid_radps(row.config.rate_hz): what plot_loops draws for `row`.
RollLoopResponse row_response(const LoopRow& row);

}  // namespace nimble::loop
