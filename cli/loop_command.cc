/// `rig loop`: the roll loop of a scenario as the rig flies it (controller/roll_loop.h): its
/// margins, sensitivity peak, bandwidth and closed-loop poles for one or every model set and
/// gain set, the robustness over the sets and a derivative box, and a PD design flown on the
/// scenario. The analysis is the loop library's (loop/loop_study.h); here the options, the text,
/// JSON and plots, --gains-out and the flight with the designed gains.

#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "cmdline/args.h"
#include "core/config.h"
#include "core/output_file.h"
#include "ident/plots.h"
#include "launcher/inprocess.h"
#include "launcher/run_plan.h"
#include "launcher/run_report.h"
#include "loop/loop_report.h"
#include "loop/loop_setup.h"
#include "loop/loop_study.h"
#include "plots/gnuplot.h"

namespace nimble::cli {
namespace {

using loop::DesignOutcome;
using loop::LoopRow;
using loop::LoopSetup;
using loop::WorstMargins;

constexpr const char* kDescription =
    "The roll loop of a scenario as the rig flies it, linear and exactly sampled: the lateral3 model,\n"
    "the flap actuator (thesis Eq 33), the PD with its 15 Hz Butterworth, the command map, the\n"
    "reference generator, 512 Hz zero-order hold and the latency from the controller's input to the\n"
    "command's action (in lockstep and in process none on the truth, two control periods on the\n"
    "estimate; in real time none; plus the plant's actuator_delay). Prints per model and gain set the gain margin (and "
    "the gain reduction margin of\n"
    "the unstable open loop), phase margin and crossover, delay margin, peak sensitivity Ms, the -3 dB\n"
    "bandwidth of phi/phi_ref and the closed-loop poles. --all-sets: model sets 1-5 (the files\n"
    "nimble_lateral_set1..5.yaml beside the scenario's model) with every gain set, and per gain set\n"
    "the worst margins over the sets and over a +-2 sigma derivative box (--box, default the\n"
    "scenario model's published sigma). --design proposes PD gains for a phase margin at a crossover.";

/// Flies the scenario in process with the designed gains in place of the gain set it flies.
void fly_design(DesignOutcome& d, const LoopSetup& s, const std::string& scenario, std::vector<Override> overrides,
                const std::string& log) {
  const std::string prefix = "controller.roll_gain_sets." + s.gain_set + ".";
  overrides.push_back(parse_override(prefix + "kp_per_rad=" + fmt("%.17g", d.design.gains.kp_per_rad)));
  overrides.push_back(parse_override(prefix + "kd_per_radps=" + fmt("%.17g", d.design.gains.kd_per_radps)));
  overrides.push_back(parse_override("controller.lowpass.roll_cutoff_hz=" + fmt("%.17g", d.design.lowpass_cutoff_hz)));
  launcher::RunOptions ro;
  ro.scenario_file = scenario;
  ro.overrides = overrides;
  ro.clock = "inprocess";
  ro.progress = false;
  ro.log_file = log;
  const launcher::RunPlan plan = launcher::load_run_plan(ro);
  launcher::InprocessOptions io;
  io.log_file = launcher::log_file_for(plan, ro);
  launcher::write_resolved_scenario(plan, io.log_file);
  const launcher::RunReport report = launcher::fly_inprocess(plan, io);
  std::ostringstream text;
  launcher::write_report_text(text, report);
  std::cout << "\nflight of scenario " << scenario << " with the designed gains in place of '" << s.gain_set
            << "' (in process, log " << io.log_file << "):\n"
            << text.str();
  d.flight = report.verdict.text;
  d.flight_exit = report.verdict.exit_code;
}

}  // namespace

int run_loop_command(const std::vector<std::string>& args) {
  std::string scenario, model_file, gains_text, input, clock, break_text = "actuator", box_file, json, plots;
  std::string design_text_arg, gains_out, design_name = "designed", fly_log;
  bool all_sets = false, fly = false;
  std::vector<Override> overrides;
  cmdline::CommandLine cl("rig loop", kDescription);
  cl->footer(
      "Exit code: 0 if every analysed loop is stable (and a design is feasible and its flight ok), 1 if "
      "not, 2 bad usage or input.");
  cl->add_option("scenario", scenario, "the scenario: model, controller, actuator and timing")->required();
  cl->add_option("--model", model_file, "a lateral3 model in place of the scenario's")->type_name("FILE");
  cl->add_option("--gains", gains_text, "a gain set of the controller, or KP,KD (default: the manoeuvre's set)")
      ->type_name("NAME|KP,KD");
  cmdline::each_value(cl->add_option("--set", "scenario override, as for rig run (repeatable)")
                          ->type_name("KEY.PATH=VALUE")
                          ->allow_extra_args(false)
                          ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll),
                      [&overrides](const std::string& v) { overrides.push_back(parse_override(v)); });
  cl->add_option("--on", input, "what the controller flies on (default: the scenario's run.controller_input)")
      ->check(CLI::IsMember({"truth", "estimate"}))
      ->type_name("truth|estimate");
  cl->add_option("--clock", clock, "whose timing the loop has (default: the scenario's clock)")
      ->check(CLI::IsMember({"realtime", "lockstep", "inprocess"}))
      ->type_name("realtime|lockstep|inprocess");
  cl->add_option("--break", break_text, "where the loop is broken: actuator, or sensor (phi and p, one at a time)")
      ->check(CLI::IsMember({"actuator", "sensor"}))
      ->capture_default_str();
  cl->add_flag("--all-sets", all_sets, "model sets 1-5 with every gain set, and the robustness lines");
  cl->add_option("--box", box_file, "the +-2 sigma box: a rig identify --json report or a model file with sigma")
      ->type_name("FILE");
  cl->add_option("--design", design_text_arg, "design PD gains: phase_margin_deg=45,crossover_hz=F")
      ->type_name("KEY=VALUE,...");
  cl->add_option("--gains-out", gains_out, "write the designed gain set (controller config format)")->type_name("FILE");
  cl->add_option("--design-name", design_name, "the designed gain set's name")->capture_default_str();
  cl->add_flag("--fly", fly,
               "fly the scenario in process with the designed gains and print its summary (the design "
               "then has the in-process timing unless --clock says otherwise)");
  cl->add_option("--log", fly_log, "the log of the --fly flight (default rig_logs/<name>-<time>.lcmlog)")
      ->type_name("F");
  cl.add_json(json, "the report");
  cl.add_plots(plots, "loop_bode.png, loop_nyquist.png, loop_step.png and loop_poles.png");
  if (const auto done = cl.parse(args)) return *done;
  if ((!gains_out.empty() || fly) && design_text_arg.empty()) return cl.fail("--gains-out and --fly need --design");
  if (!plots.empty()) plots::require_gnuplot();

  // --fly flies in process: the design is for that loop unless another clock is asked for.
  if (fly && clock.empty()) clock = "inprocess";
  loop::LoopRequest request;
  request.scenario_file = scenario;
  request.overrides = overrides;
  request.model_file = model_file;
  request.gains = gains_text;
  request.input = input;
  request.clock = clock;
  request.break_at = break_text;
  request.all_sets = all_sets;
  request.box_file = box_file;
  request.design = design_text_arg;
  request.design_name = design_name;
  loop::LoopStudy study = loop::study_loop(request);
  const LoopSetup& s = study.setup;
  const std::vector<LoopRow>& rows = study.rows;
  const std::vector<WorstMargins>& worst = study.worst;
  DesignOutcome* design = study.design ? &*study.design : nullptr;

  const bool quiet = json == "-";
  if (!quiet) {
    std::cout << loop::loop_header_text(s, scenario);
    if (all_sets) {
      std::cout << loop::loop_table_text(rows) << "\n";
      for (const WorstMargins& w : worst) std::cout << loop::worst_text(w);
    } else {
      for (const LoopRow& r : rows) std::cout << loop::loop_text(r);
    }
    if (design) std::cout << loop::design_text(*design);
  }
  if (design && design->design.feasible && !gains_out.empty()) {
    std::string command = "rig loop";
    for (const auto& a : args) command += " " + a;
    write_file(gains_out, loop::design_yaml(*design, command));
    if (!quiet) std::cout << "  written " << gains_out << "\n";
  }
  if (design && design->design.feasible && fly) fly_design(*design, s, scenario, overrides, fly_log);
  if (!json.empty()) cmdline::write_json(json, loop::loop_json(s, rows, worst, design));
  if (!plots.empty()) {
    std::vector<LoopRow> plotted;
    for (const LoopRow& r : rows) {
      if (r.model == s.model.name || !all_sets) plotted.push_back(r);
    }
    for (const auto& p : loop::plot_loops(plots, plotted)) {
      if (!quiet) std::cout << "plot " << p << "\n";
    }
  }
  return study.ok() ? 0 : 1;
}

}  // namespace nimble::cli
