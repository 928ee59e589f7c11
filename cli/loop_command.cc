/// `rig loop`: the roll loop of a scenario as the rig flies it (controller/roll_loop.h): its
/// margins, sensitivity peak, bandwidth and closed-loop poles for one or every model set and
/// gain set, the robustness over the sets and a derivative box, and a PD design flown on the
/// scenario.

#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "cli/loop_report.h"
#include "cli/loop_setup.h"
#include "cli/report_files.h"
#include "cmdline/args.h"
#include "ident/plots.h"
#include "launcher/inprocess.h"
#include "launcher/run_plan.h"
#include "launcher/run_report.h"

namespace nimble::cli {
namespace {

namespace fs = std::filesystem;

constexpr const char* kDescription =
    "The roll loop of a scenario as the rig flies it, linear and exactly sampled: the lateral3 model,\n"
    "the flap actuator (thesis Eq 33), the PD with its 15 Hz Butterworth, the command map, the\n"
    "reference generator, 512 Hz zero-order hold and the latency from the controller's input to the\n"
    "command's action (in lockstep and in process none on the truth, two control periods on the\n"
    "estimate; in real time none; plus the plant's actuator_delay). Prints per model and gain set the gain margin (and the gain reduction margin of\n"
    "the unstable open loop), phase margin and crossover, delay margin, peak sensitivity Ms, the -3 dB\n"
    "bandwidth of phi/phi_ref and the closed-loop poles. --all-sets: model sets 1-5 (the files\n"
    "nimble_lateral_set1..5.yaml beside the scenario's model) with every gain set, and per gain set\n"
    "the worst margins over the sets and over a +-2 sigma derivative box (--box, default the\n"
    "scenario model's published sigma). --design proposes PD gains for a phase margin at a crossover.";

/// The gain sets a command line names: "NAME" of the controller, or "KP,KD".
std::vector<std::pair<std::string, GainSet>> gain_sets_of(const LoopSetup& s, const std::string& text, bool all) {
  std::vector<std::pair<std::string, GainSet>> sets;
  if (all && text.empty()) {
    for (const auto& [name, g] : s.controller.roll_gain_sets) sets.emplace_back(name, g);
    return sets;
  }
  const std::string name = text.empty() ? s.gain_set : text;
  if (name.find(',') != std::string::npos) {
    const std::vector<double> v = cmdline::number_list(name);
    if (v.size() != 2 || v[0] < 0.0 || v[1] < 0.0) {
      throw std::invalid_argument("--gains KP,KD takes two gains >= 0, got '" + name + "'");
    }
    sets.emplace_back("kp" + fmt("%g", v[0]) + "_kd" + fmt("%g", v[1]), GainSet{v[0], v[1]});
  } else {
    sets.emplace_back(name, roll_gain_set(s.controller, name));
  }
  return sets;
}

/// The five model sets beside the scenario's model.
std::vector<DerivativeModel> model_sets(const LoopSetup& s) {
  const fs::path dir = fs::path(s.model.file).parent_path();
  std::vector<DerivativeModel> models;
  for (int i = 1; i <= 5; ++i) {
    const fs::path file = dir / ("nimble_lateral_set" + std::to_string(i) + ".yaml");
    if (!fs::exists(file)) throw std::invalid_argument("--all-sets: no model set " + file.string());
    models.push_back(load_model(file.string()));
  }
  return models;
}

LoopRow analyse(const LoopSetup& s, const DerivativeModel& model, const std::string& gains_name, const GainSet& gains,
                LoopBreak where) {
  LoopRow r;
  r.model = model.name;
  r.gains = gains_name;
  r.gain_values = gains;
  r.where = where;
  r.config = s.loop_config(gains);
  r.lateral = build_state_space(model, s.vehicle);
  r.analysis = analyse_roll_loop(r.lateral, r.config, where);
  return r;
}

/// The box's corners need the margins only: a grid of 300 points (the crossovers are refined by
/// bisection all the same; the table's loops use 600).
const MarginOptions kBoxGrid{0.01, 300};

/// Per gain set: the worst over the given rows and over the +-2 sigma box (every corner).
std::vector<WorstMargins> robustness(const LoopSetup& s, const std::vector<LoopRow>& rows,
                                     const std::vector<std::pair<std::string, GainSet>>& sets, const DerivativeBox& box) {
  std::vector<WorstMargins> out;
  const auto& names = loop_derivatives();
  const int corners = 1 << names.size();
  for (const auto& [gname, gains] : sets) {
    WorstMargins over_sets;
    over_sets.gains = gname;
    over_sets.over = "model sets 1-5";
    for (const LoopRow& r : rows) {
      if (r.gains == gname && r.where == LoopBreak::kActuator) over_sets.add(r.model, r.analysis);
    }
    out.push_back(over_sets);
    WorstMargins over_box;
    over_box.gains = gname;
    over_box.over = fs::path(box.source).filename().string() + " +-2 sigma, every corner";
    const RollLoopConfig config = s.loop_config(gains);
    // The margins of the model at one point of the box.
    auto margins_at = [&](const std::vector<int>& signs) {
      return analyse_roll_loop(build_state_space(box_point(s.model, box, signs), s.vehicle), config,
                               LoopBreak::kActuator, kBoxGrid, false);
    };
    std::map<std::string, int> by_sign;
    for (int c = 0; c < corners; ++c) {
      std::vector<int> signs(names.size());
      std::string label;
      for (std::size_t i = 0; i < names.size(); ++i) {
        signs[i] = (c >> i) & 1 ? 1 : -1;
        label += names[i] + (signs[i] > 0 ? "+" : "-") + (i + 1 < names.size() ? " " : "");
      }
      const RollLoopAnalysis a = margins_at(signs);
      over_box.add(label, a);
      if (!a.margins.closed_loop_stable) {
        for (std::size_t i = 0; i < names.size(); ++i) by_sign[names[i] + (signs[i] > 0 ? "+" : "-")] += 1;
      }
    }
    for (const auto& name : names) {
      for (const int sign : {-1, 1}) {
        std::vector<int> signs(names.size(), 0);
        signs[static_cast<std::size_t>(&name - names.data())] = sign;
        if (!margins_at(signs).margins.closed_loop_stable) over_box.unstable_alone.push_back(name + (sign > 0 ? "+" : "-"));
      }
    }
    for (const auto& [key, count] : by_sign) over_box.unstable_by_sign.emplace_back(key, count);
    out.push_back(over_box);
  }
  return out;
}

DesignRequest parse_design(const std::string& text) {
  DesignRequest r;
  std::istringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    const auto eq = item.find('=');
    const std::string key = item.substr(0, eq);
    if (eq == std::string::npos) throw std::invalid_argument("--design: '" + item + "' is not KEY=VALUE");
    const double v = cmdline::finite_number(item.substr(eq + 1));
    if (key == "phase_margin_deg") {
      r.phase_margin_deg = v;
    } else if (key == "crossover_hz") {
      r.crossover_hz = v;
    } else {
      throw std::invalid_argument("--design: unknown key '" + key + "' (phase_margin_deg, crossover_hz)");
    }
  }
  return r;
}

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
  cl->footer("Exit code: 0 if every analysed loop is stable (and a design is feasible and its flight ok), 1 if "
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
  cl->add_flag("--fly", fly, "fly the scenario in process with the designed gains and print its summary (the design "
                             "then has the in-process timing unless --clock says otherwise)");
  cl->add_option("--log", fly_log, "the log of the --fly flight (default rig_logs/<name>-<time>.lcmlog)")->type_name("F");
  cl.add_json(json, "the report");
  cl.add_plots(plots, "loop_bode.png, loop_nyquist.png, loop_step.png and loop_poles.png");
  if (const auto done = cl.parse(args)) return *done;
  if ((!gains_out.empty() || fly) && design_text_arg.empty()) return cl.fail("--gains-out and --fly need --design");
  if (!plots.empty()) ident::require_gnuplot();

  // --fly flies in process: the design is for that loop unless another clock is asked for.
  if (fly && clock.empty()) clock = "inprocess";
  const LoopSetup s = loop_setup(scenario, overrides, model_file, input, clock);
  const auto sets = gain_sets_of(s, gains_text, all_sets);
  std::vector<LoopBreak> breaks{LoopBreak::kActuator};
  if (break_text == "sensor") breaks = {LoopBreak::kPhi, LoopBreak::kP};
  std::vector<DerivativeModel> models{s.model};
  if (all_sets) models = model_sets(s);

  std::vector<LoopRow> rows;
  for (const DerivativeModel& m : models) {
    for (const auto& [name, gains] : sets) {
      for (const LoopBreak b : breaks) rows.push_back(analyse(s, m, name, gains, b));
      if (all_sets && break_text == "sensor") rows.push_back(analyse(s, m, name, gains, LoopBreak::kActuator));
    }
  }
  std::vector<WorstMargins> worst;
  if (all_sets) worst = robustness(s, rows, sets, box_file.empty() ? derivative_box(s.model) : derivative_box(box_file));

  std::unique_ptr<DesignOutcome> design;
  if (!design_text_arg.empty()) {
    design = std::make_unique<DesignOutcome>();
    design->request = parse_design(design_text_arg);
    design->name = design_name;
    design->model = s.model.name;
    design->design = design_roll_gains(build_state_space(s.model, s.vehicle), s.loop_config(sets.front().second),
                                       design->request);
  }

  const bool quiet = json == "-";
  if (!quiet) {
    std::cout << loop_header_text(s, scenario);
    if (all_sets) {
      std::cout << loop_table_text(rows) << "\n";
      for (const WorstMargins& w : worst) std::cout << worst_text(w);
    } else {
      for (const LoopRow& r : rows) std::cout << loop_text(r);
    }
    if (design) std::cout << design_text(*design);
  }
  if (design && design->design.feasible && !gains_out.empty()) {
    std::string command = "rig loop";
    for (const auto& a : args) command += " " + a;
    write_file(gains_out, design_yaml(*design, command));
    if (!quiet) std::cout << "  written " << gains_out << "\n";
  }
  if (design && design->design.feasible && fly) fly_design(*design, s, scenario, overrides, fly_log);
  if (!json.empty()) cmdline::write_json(json, loop_json(s, rows, worst, design.get()));
  if (!plots.empty()) {
    std::vector<LoopRow> plotted;
    for (const LoopRow& r : rows) {
      if (r.model == s.model.name || !all_sets) plotted.push_back(r);
    }
    for (const auto& p : plot_loops(plots, plotted)) {
      if (!quiet) std::cout << "plot " << p << "\n";
    }
  }
  bool ok = true;
  for (const LoopRow& r : rows) ok = ok && r.analysis.margins.closed_loop_stable;
  if (design) ok = ok && design->design.feasible && (design->flight.empty() || design->flight_exit == 0);
  return ok ? 0 : 1;
}

}  // namespace nimble::cli
