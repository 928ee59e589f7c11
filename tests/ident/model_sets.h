#pragma once
/// The model sets of rig_configs/models (nimble_lateral_set<set>.yaml) with their vehicles, loaded
/// once per program (needs RIG_SOURCE_DIR): what the discrepancy suites' generators fly.

#include <map>
#include <string>

#include "core/model.h"
#include "core/vehicle.h"

namespace nimble::ident::test {

struct ModelSet {
  DerivativeModel model;
  Vehicle vehicle;
};

inline const ModelSet& model_set(int set) {
  static std::map<int, ModelSet> sets;
  auto it = sets.find(set);
  if (it == sets.end()) {
    DerivativeModel m = load_model(std::string(RIG_SOURCE_DIR) + "/rig_configs/models/nimble_lateral_set" +
                                   std::to_string(set) + ".yaml");
    Vehicle v = load_vehicle(m.vehicle_file);
    it = sets.emplace(set, ModelSet{std::move(m), std::move(v)}).first;
  }
  return it->second;
}

inline const ModelSet& set1() { return model_set(1); }

}  // namespace nimble::ident::test
