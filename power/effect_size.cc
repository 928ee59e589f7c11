#include "power/effect_size.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

#include "cmdline/args.h"
#include "plant/effects/effects.h"
#include "plant/effects/registry.h"

namespace nimble::power {
namespace {

/// The range of `key` in a plant effect's parameter table.
template <typename Config>
Range range_in(const ParamTable<Config>& table, const std::string& key) {
  for (const auto& p : table) {
    if (p.key == key) return p.range;
  }
  throw std::logic_error("power: no parameter " + key + " in the plant's table");
}

/// The name the workflow gives plant effect `effect` (the registry effect it flies).
std::string model_effect_of(const std::string& effect) {
  for (const auto& e : plant::plant_effects()) {
    if (e.name == effect) return e.model_effect;
  }
  throw std::logic_error("power: no plant effect " + effect);
}

/// The shortest text that reads back as `x`.
std::string number(double x) {
  char text[40];
  for (int digits = 15; digits <= 17; ++digits) {
    std::snprintf(text, sizeof text, "%.*g", digits, x);
    if (std::strtod(text, nullptr) == x) break;
  }
  return text;
}

/// The scenario's value of plant.effects.<effect>.<key>, or `fallback` if it has none.
YAML::Node configured(const YAML::Node& tree, const std::string& effect, const std::string& key) {
  const YAML::Node plant = tree["plant"];
  if (!plant || !plant["effects"] || !plant["effects"][effect]) return YAML::Node();
  return plant["effects"][effect][key];
}

double configured_number(const YAML::Node& tree, const std::string& effect, const std::string& key, double fallback) {
  const YAML::Node n = configured(tree, effect, key);
  return n && n.IsScalar() ? n.as<double>() : fallback;
}

std::vector<double> configured_list(const YAML::Node& tree, const std::string& effect, const std::string& key) {
  const YAML::Node n = configured(tree, effect, key);
  std::vector<double> out;
  if (n && n.IsSequence()) {
    for (const auto& x : n) out.push_back(x.as<double>());
  }
  return out;
}

std::string list(const std::vector<double>& values) {
  std::string out = "[";
  for (std::size_t i = 0; i < values.size(); ++i) out += (i ? "," : "") + number(values[i]);
  return out + "]";
}

[[noreturn]] void fail(const SizedEffect& e, const std::string& problem) {
  throw std::invalid_argument("effect " + e.effect + " (SIZE sets plant.effects." + e.effect + "." + e.parameter +
                              " [" + e.unit + "], " + e.range.describe() + "): " + problem);
}

/// `scaled` (a companion of SIZE) within `range`, or an error naming it.
double checked(const SizedEffect& e, const std::string& key, double scaled, const Range& range) {
  if (!range.contains(scaled)) {
    fail(e, "the scenario's ratio makes " + key + " " + number(scaled) + ", not " + range.describe());
  }
  return scaled;
}

}  // namespace

const std::vector<SizedEffect>& sized_effects() {
  static const std::vector<SizedEffect> effects = [] {
    using namespace plant;
    const Range amplitude = Range::closed(-1.0, 1.0);  // flapping_forcing's lists (flapping_forcing.cc)
    std::vector<SizedEffect> v = {
        {"forward_speed_coupling", "gain_per_mps", "1/(m/s)",
         range_in(forward_speed_coupling_params(), "gain_per_mps"), "", "the explicit coefficients stay as set"},
        {"constant_load", "roll_moment_nm", "N m", range_in(constant_load_params(), "roll_moment_nm"), "",
         "side_force_n keeps its ratio to the moment"},
        {"lateral_inflow", "Y_vv_ns2pm2", "N s^2/m^2", range_in(lateral_inflow_params(), "Y_vv_ns2pm2"), "",
         "L_vv_ns2pm keeps its ratio to Y_vv (0.01 m if Y_vv is 0)"},
        {"flapping_forcing", "roll_moment_amplitudes_nm[0]", "N m", amplitude, "",
         "every amplitude of both lists scales with the first roll amplitude"},
        {"actuator_delay", "delay_s", "s", range_in(actuator_delay_params(), "delay_s"), "", "nothing else"},
        {"lateral_gust", "sigma_mps", "m/s", range_in(lateral_gust_params(), "sigma_mps"), "",
         "form, tau_s and time_scale_s stay as set"},
    };
    for (auto& e : v) e.named_as = model_effect_of(e.effect);
    return v;
  }();
  return effects;
}

const SizedEffect& sized_effect(const std::string& effect) {
  for (const auto& e : sized_effects()) {
    if (e.effect == effect) return e;
  }
  throw std::invalid_argument("unknown effect '" + effect + "'; the plant effects and what SIZE sets: " +
                              sized_effect_list());
}

std::string sized_effect_list() {
  std::string out;
  for (const auto& e : sized_effects()) {
    out += (out.empty() ? "" : ", ") + e.effect + "=" + e.parameter + " [" + e.unit + "]";
  }
  return out;
}

EffectSizes parse_effect_sizes(const std::string& text) {
  const std::size_t eq = text.find('=');
  if (eq == std::string::npos || eq == 0) {
    throw std::invalid_argument("'" + text + "' is not NAME=SIZE; the plant effects and what SIZE sets: " +
                                sized_effect_list());
  }
  const SizedEffect& e = sized_effect(text.substr(0, eq));
  EffectSizes out;
  out.effect = e.effect;
  try {
    out.sizes = cli::number_grid(text.substr(eq + 1));
  } catch (const std::invalid_argument& bad) {
    fail(e, "SIZE '" + text.substr(eq + 1) + "': " + bad.what());
  }
  for (const double s : out.sizes) {
    if (!e.range.contains(s)) fail(e, "SIZE " + number(s) + " is not " + e.range.describe());
  }
  return out;
}

std::vector<Override> size_overrides(const YAML::Node& tree, const std::string& effect, double size) {
  const SizedEffect& e = sized_effect(effect);
  if (!e.range.contains(size)) fail(e, "SIZE " + number(size) + " is not " + e.range.describe());
  const std::string prefix = "plant.effects." + effect + ".";
  std::vector<Override> out = {{prefix + "enabled", size == 0.0 ? "false" : "true"}};
  if (size == 0.0) return out;
  if (effect == "lateral_inflow") {
    const double y = configured_number(tree, effect, "Y_vv_ns2pm2", 0.0);
    const double ratio = y != 0.0 ? configured_number(tree, effect, "L_vv_ns2pm", 0.0) / y : 0.01;
    out.push_back({prefix + "Y_vv_ns2pm2", number(size)});
    out.push_back({prefix + "L_vv_ns2pm", number(checked(e, "L_vv_ns2pm", ratio * size,
                                                         range_in(plant::lateral_inflow_params(), "L_vv_ns2pm")))});
  } else if (effect == "constant_load") {
    const double l = configured_number(tree, effect, "roll_moment_nm", 0.0);
    const double ratio = l != 0.0 ? configured_number(tree, effect, "side_force_n", 0.0) / l : 0.0;
    out.push_back({prefix + "roll_moment_nm", number(size)});
    out.push_back({prefix + "side_force_n", number(checked(e, "side_force_n", ratio * size,
                                                           range_in(plant::constant_load_params(), "side_force_n")))});
  } else if (effect == "flapping_forcing") {
    std::vector<double> roll = configured_list(tree, effect, "roll_moment_amplitudes_nm");
    std::vector<double> side = configured_list(tree, effect, "side_force_amplitudes_n");
    if (roll.empty() || roll[0] == 0.0) fail(e, "the scenario has no first roll amplitude to scale from");
    const double k = size / roll[0];
    for (auto& a : roll) a = checked(e, "roll_moment_amplitudes_nm", k * a, e.range);
    for (auto& a : side) a = checked(e, "side_force_amplitudes_n", k * a, e.range);
    out.push_back({prefix + "roll_moment_amplitudes_nm", list(roll)});
    out.push_back({prefix + "side_force_amplitudes_n", list(side)});
  } else {
    out.push_back({prefix + e.parameter, number(size)});
  }
  return out;
}

}  // namespace nimble::power
