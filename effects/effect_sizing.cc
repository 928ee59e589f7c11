#include "effects/effect_sizing.h"

#include <stdexcept>

namespace nimble::effects {

double section_number(const YAML::Node& section, const std::string& key, double fallback) {
  if (!section || !section.IsMap()) return fallback;
  const YAML::Node n = section[key];
  return n && n.IsScalar() ? n.as<double>() : fallback;
}

std::vector<double> section_list(const YAML::Node& section, const std::string& key) {
  std::vector<double> out;
  if (!section || !section.IsMap()) return out;
  const YAML::Node n = section[key];
  if (n && n.IsSequence()) {
    for (const auto& x : n) out.push_back(x.as<double>());
  }
  return out;
}

double companion_within(const std::string& key, double value, const Range& range) {
  if (!range.contains(value)) {
    throw std::invalid_argument("the scenario's ratio makes " + key + " " + shortest_text(value) + ", not " +
                                range.describe());
  }
  return value;
}

std::vector<EffectValue> with_companion_ratio(const YAML::Node& section, double size, const std::string& parameter,
                                              const std::string& companion, const Range& companion_range,
                                              double ratio_if_zero) {
  const double main = section_number(section, parameter, 0.0);
  const double ratio = main != 0.0 ? section_number(section, companion, 0.0) / main : ratio_if_zero;
  const double value = companion_within(companion, ratio * size, companion_range);
  return {{parameter, shortest_text(size)}, {companion, shortest_text(value)}};
}

std::vector<EffectValue> parameter_alone(const std::string& parameter, double size) {
  return {{parameter, shortest_text(size)}};
}

}  // namespace nimble::effects
