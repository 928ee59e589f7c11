#include "detection_power/effect_size.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

#include "cmdline/args.h"
#include "effects/registry.h"

namespace nimble::detection_power {
namespace {

[[noreturn]] void fail(const SizedEffect& e, const std::string& problem) {
  throw std::invalid_argument("effect " + e.effect + " (SIZE sets plant.effects." + e.effect + "." + e.parameter +
                              " [" + e.unit + "], " + e.range.describe() + "): " + problem);
}

}  // namespace

const std::vector<SizedEffect>& sized_effects() {
  // Every plant effect that declares its sizing (effects/effect_sizing.h), in the
  // registry's order.
  static const std::vector<SizedEffect> effects = [] {
    std::vector<SizedEffect> v;
    for (const effects::Effect* effect : effects::plant_effects()) {
      if (effect->plant.sizing == nullptr) continue;
      const effects::EffectSizing sizing = effect->plant.sizing();
      v.push_back(
          {effect->name(), sizing.parameter, sizing.unit, sizing.range, effect->name(), sizing.scales, sizing.values});
    }
    return v;
  }();
  return effects;
}

const SizedEffect& sized_effect(const std::string& effect) {
  for (const auto& e : sized_effects()) {
    if (e.effect == effect) return e;
  }
  throw std::invalid_argument("unknown effect '" + effect +
                              "'; the plant effects and what SIZE sets: " + sized_effect_list());
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
    throw std::invalid_argument("'" + text +
                                "' is not NAME=SIZE; the plant effects and what SIZE sets: " + sized_effect_list());
  }
  const SizedEffect& e = sized_effect(text.substr(0, eq));
  EffectSizes out;
  out.effect = e.effect;
  try {
    out.sizes = cmdline::number_grid(text.substr(eq + 1));
  } catch (const std::invalid_argument& bad) {
    fail(e, "SIZE '" + text.substr(eq + 1) + "': " + bad.what());
  }
  for (const double s : out.sizes) {
    if (!e.range.contains(s)) fail(e, "SIZE " + shortest_text(s) + " is not " + e.range.describe());
  }
  return out;
}

std::vector<Override> size_overrides(const YAML::Node& tree, const std::string& effect, double size) {
  const SizedEffect& e = sized_effect(effect);
  if (!e.range.contains(size)) fail(e, "SIZE " + shortest_text(size) + " is not " + e.range.describe());
  const std::string prefix = "plant.effects." + effect + ".";
  std::vector<Override> out = {{prefix + "enabled", size == 0.0 ? "false" : "true"}};
  if (size == 0.0) return out;
  const YAML::Node plant = tree["plant"];
  const YAML::Node section = plant && plant["effects"] ? plant["effects"][effect] : YAML::Node();
  try {
    for (const effects::EffectValue& value : e.values(section, size))
      out.push_back({prefix + value.first, value.second});
  } catch (const std::invalid_argument& bad) {
    fail(e, bad.what());
  }
  return out;
}

}  // namespace nimble::detection_power
