#pragma once
/// Shared helpers of the turbulence tests.

#include <string>

#include "turbulence/ce500_config.h"

namespace nimble::turbulence::test {

/// rig_configs/turbulence/ce500_practical.yaml.
inline std::string practical_file() {
  return std::string(RIG_SOURCE_DIR) + "/rig_configs/turbulence/ce500_practical.yaml";
}

/// The practical's configuration.
inline const Ce500Config& practical() {
  static const Ce500Config config = load_ce500_config(practical_file());
  return config;
}

}  // namespace nimble::turbulence::test
