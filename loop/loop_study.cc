#include "loop/loop_study.h"

#include <filesystem>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "cmdline/args.h"
#include "core/config.h"

namespace nimble::loop {
namespace {

namespace fs = std::filesystem;

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
                                     const std::vector<std::pair<std::string, GainSet>>& sets,
                                     const DerivativeBox& box) {
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
        if (!margins_at(signs).margins.closed_loop_stable)
          over_box.unstable_alone.push_back(name + (sign > 0 ? "+" : "-"));
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

}  // namespace

bool LoopStudy::ok() const {
  bool stable = true;
  for (const LoopRow& r : rows) stable = stable && r.analysis.margins.closed_loop_stable;
  if (design) stable = stable && design->design.feasible && (design->flight.empty() || design->flight_exit == 0);
  return stable;
}

LoopStudy study_loop(const LoopRequest& q) {
  if (q.break_at != "actuator" && q.break_at != "sensor") {
    throw std::invalid_argument("--break must be actuator or sensor, got '" + q.break_at + "'");
  }
  LoopStudy study;
  study.setup = loop_setup(q.scenario_file, q.overrides, q.model_file, q.input, q.clock);
  const LoopSetup& s = study.setup;
  const auto sets = gain_sets_of(s, q.gains, q.all_sets);
  std::vector<LoopBreak> breaks{LoopBreak::kActuator};
  if (q.break_at == "sensor") breaks = {LoopBreak::kPhi, LoopBreak::kP};
  std::vector<DerivativeModel> models{s.model};
  if (q.all_sets) models = model_sets(s);

  for (const DerivativeModel& m : models) {
    for (const auto& [name, gains] : sets) {
      for (const LoopBreak b : breaks) study.rows.push_back(analyse(s, m, name, gains, b));
      if (q.all_sets && q.break_at == "sensor") study.rows.push_back(analyse(s, m, name, gains, LoopBreak::kActuator));
    }
  }
  if (q.all_sets) {
    study.worst =
        robustness(s, study.rows, sets, q.box_file.empty() ? derivative_box(s.model) : derivative_box(q.box_file));
  }

  if (!q.design.empty()) {
    DesignOutcome& d = study.design.emplace();
    d.request = parse_design(q.design);
    d.name = q.design_name;
    d.model = s.model.name;
    d.design = design_roll_gains(build_state_space(s.model, s.vehicle), s.loop_config(sets.front().second), d.request);
  }
  return study;
}

}  // namespace nimble::loop
