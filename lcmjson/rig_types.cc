/// The rig's types, parsed once from the .lcm files built into the library.

#include <stdexcept>
#include <string>
#include <vector>

#include "contract/channels.h"
#include "lcmjson/lcm_json.h"
#include "lcmjson/rig_lcm_files.h"

namespace nimble::lcmjson {

const std::vector<LcmStruct>& rig_types() {
  static const std::vector<LcmStruct> types = [] {
    std::vector<LcmStruct> all;
    for (const auto& file : rig_lcm_files()) {
      for (auto& s : parse_lcm(file.text, file.name)) all.push_back(std::move(s));
    }
    return all;
  }();
  return types;
}

const LcmStruct* find_rig_type(const std::string& name) {
  for (const auto& t : rig_types()) {
    if (t.name == name || t.full_name() == name) return &t;
  }
  return nullptr;
}

const LcmStruct* rig_type_for_channel(const std::string& channel) {
  const contract::ChannelSpec* spec = contract::find_channel(channel);
  return spec ? find_rig_type(spec->type) : nullptr;
}

}  // namespace nimble::lcmjson
