#include "plant/effects/effect_sizing.h"

#include <cstdio>
#include <cstdlib>
#include <stdexcept>

namespace nimble::plant {

std::string size_text(double x) {
  char text[40];
  for (int digits = 15; digits <= 17; ++digits) {
    std::snprintf(text, sizeof text, "%.*g", digits, x);
    if (std::strtod(text, nullptr) == x) break;
  }
  return text;
}

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
    throw std::invalid_argument("the scenario's ratio makes " + key + " " + size_text(value) + ", not " +
                                range.describe());
  }
  return value;
}

std::vector<EffectValue> parameter_alone(const std::string& parameter, double size) {
  return {{parameter, size_text(size)}};
}

}  // namespace nimble::plant
