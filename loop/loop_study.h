#pragma once
/// The study of a scenario's roll loop that `rig loop` reports (cli/loop_command.cc), for it and
/// any other front end: the scenario's loop, every model and gain set broken where asked, the
/// robustness over the model sets and a derivative box, and a PD design. Printing, --gains-out and
/// the flight with the designed gains stay the front end's.

#include <optional>
#include <string>
#include <vector>

#include "loop/loop_report.h"
#include "loop/loop_setup.h"
#include "scenario/scenario.h"

namespace nimble::loop {

/// What a study is asked for: `rig loop`'s options. The empty text is the option left out.
struct LoopRequest {
  std::string scenario_file;
  std::vector<Override> overrides;       ///< --set
  std::string model_file;                ///< a lateral3 model in place of the scenario's
  std::string gains;                     ///< NAME of a gain set or "KP,KD" (default: the manoeuvre's set;
                                         ///< with all_sets every set)
  std::string input;                     ///< truth | estimate (default: the scenario's run.controller_input)
  std::string clock;                     ///< realtime | lockstep | inprocess (default: the scenario's)
  std::string break_at = "actuator";     ///< actuator | sensor (phi and p, one at a time)
  bool all_sets = false;                 ///< model sets 1-5 with every gain set, and the robustness lines
  std::string box_file;                  ///< the +-2 sigma box (default: the scenario model's published sigma)
  std::string design;                    ///< "phase_margin_deg=45,crossover_hz=F": design PD gains
  std::string design_name = "designed";  ///< the designed gain set's name
};

/// What a study found.
struct LoopStudy {
  LoopSetup setup;
  std::vector<LoopRow> rows;            ///< per model, per gain set, per break
  std::vector<WorstMargins> worst;      ///< all_sets: per gain set, over the sets and over the box
  std::optional<DesignOutcome> design;  ///< with a design asked for
  /// Every loop stable, and the design (if any) feasible and its flight (if flown) ok: `rig loop`'s
  /// exit code 0.
  bool ok() const;
};

/// The study `request` asks for.
/// @throws ConfigError or std::invalid_argument naming the problem (in `rig loop`'s words:
/// "--gains KP,KD takes ...", "--design: unknown key ...").
LoopStudy study_loop(const LoopRequest& request);

}  // namespace nimble::loop
