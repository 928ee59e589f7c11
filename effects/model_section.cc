#include "effects/model_section.h"

#include <algorithm>
#include <cmath>

namespace nimble::effects {

std::string ModelSection::where() const {
  return "plant: model '" + model.name + "'" + (model.file.empty() ? "" : " (" + model.file + ")") + ", effects." +
         effect;
}

void ModelSection::fail(const std::string& problem) const { throw std::invalid_argument(where() + ": " + problem); }

void ModelSection::fail(const std::string& key, const std::string& problem) const {
  throw std::invalid_argument(where() + "." + key + ": " + problem);
}

void ModelSection::check_keys(const std::function<bool(const std::string&)>& known, const std::string& expected) const {
  for (const auto& [key, value] : params) {
    if (!known(key)) fail(key, "not a parameter of " + effect + " (expected " + expected + ")");
    if (!std::isfinite(value)) fail(key, "must be finite");
  }
}

void ModelSection::check_keys(const std::vector<std::string>& names) const {
  std::string list;
  for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
  check_keys([&](const std::string& k) { return std::find(names.begin(), names.end(), k) != names.end(); }, list);
}

double ModelSection::or_zero(const std::string& key, const Range& range) const {
  const auto it = params.find(key);
  if (it == params.end()) return 0.0;
  in_range(key, it->second, range);
  return it->second;
}

double ModelSection::required(const std::string& key, const Range& range) const {
  const auto it = params.find(key);
  if (it == params.end()) fail("needs the parameter " + key);
  in_range(key, it->second, range);
  return it->second;
}

void ModelSection::in_range(const std::string& key, double value, const Range& range) const {
  if (!range.contains(value)) fail(key, std::to_string(value) + ": must be " + range.describe());
}

void ModelSection::set_derivative(const std::string& key, std::map<std::string, double>& derivatives,
                                  const Range& range) const {
  const auto it = params.find(key);
  if (it == params.end()) return;
  if (model.derivatives.count(key))
    fail(key, "the model also carries " + key + " among its derivatives; give it in one place only");
  in_range(key, it->second, range);
  derivatives[key] = it->second;
}

}  // namespace nimble::effects
