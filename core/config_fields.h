#pragma once
/// Optional fields of a ConfigMap that the sensing loaders share (sensors/sensor_config.h,
/// estimator/sensing_config.h): 3-vectors written as mappings, optional integers and booleans,
/// and a struct validator run as a backstop of a section.

#include <array>
#include <stdexcept>
#include <string>

#include <Eigen/Core>

#include "core/config.h"

namespace nimble {

/// Keys of the three components of a 3-vector mapping.
using AxisNames = std::array<const char*, 3>;
/// Sensor axes x y z.
constexpr AxisNames kXyzAxes = {"x", "y", "z"};

/// Optional 3-vector written as a mapping with the keys `names` (each optional, falling back to its
/// component of `fallback`), every component within `range`; `fallback` when `key` is absent.
/// @throws ConfigError naming the component's key.
Eigen::Vector3d get_vec3_or(ConfigMap& map, const std::string& key, const Eigen::Vector3d& fallback, const Range& range,
                            const AxisNames& names = kXyzAxes);

/// Optional integer within `range`; `fallback` when `key` is absent. @throws ConfigError.
long long get_int_or(ConfigMap& map, const std::string& key, long long fallback, const Range& range);

/// Optional boolean; `fallback` when `key` is absent. @throws ConfigError.
bool get_bool_or(ConfigMap& map, const std::string& key, bool fallback);

/// Runs `validate(config)` (found by argument-dependent lookup) as a backstop of the loader and
/// turns its std::invalid_argument into a ConfigError of the section `map`.
template <typename Config>
void validate_section(const ConfigMap& map, const Config& config) {
  try {
    validate(config);
  } catch (const std::invalid_argument& e) {
    std::string section = map.key_path("");
    if (!section.empty() && section.back() == '.') section.pop_back();
    throw ConfigError(map.file(), section, "", e.what());
  }
}

}  // namespace nimble
