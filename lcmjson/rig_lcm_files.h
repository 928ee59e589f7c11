#pragma once
/// The rig's .lcm files as built into the library (generated from lcmtypes/ at build time).

#include <string>
#include <vector>

namespace nimble::lcmjson {

struct LcmFileText {
  std::string name;  ///< e.g. "truth_state_t.lcm"
  std::string text;
};

/// Every lcmtypes/*.lcm file, sorted by name.
const std::vector<LcmFileText>& rig_lcm_files();

}  // namespace nimble::lcmjson
