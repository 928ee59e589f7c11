#pragma once
/// Test support: the shipped configuration folder (RIG_SOURCE_DIR is a compile definition).

#include <string>

namespace nimble::test {

/// <source>/rig_configs/, with the trailing slash.
inline const std::string kConfigs = std::string(RIG_SOURCE_DIR) + "/rig_configs/";

}  // namespace nimble::test
