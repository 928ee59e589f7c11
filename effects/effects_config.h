#pragma once
/// The plant's effects beyond the paper's linear model (section `plant.effects`), one file
/// each in this folder, and where a model's `effects:` section goes: registry.h. The plant
/// file rig_configs/plant/nimble_plant.yaml documents each effect's size and source.

#include <any>
#include <map>
#include <typeindex>
#include <typeinfo>

namespace nimble::effects {

/// Every plant effect's configuration, each held by its type (`effects.get<LateralGustConfig>()`),
/// so that an effect's file pair and its registry line (registry.cc) are all the plant needs of
/// it. An effect not set is its configuration's default: off.
class EffectsConfig {
 public:
  /// The configuration of type `Config`, made at its default if it is not there yet.
  template <class Config>
  Config& get() {
    std::any& slot = slots_[std::type_index(typeid(Config))];
    if (!slot.has_value()) slot = Config{};
    return std::any_cast<Config&>(slot);
  }

  /// The configuration of type `Config`, or its default (off) if it was never set.
  template <class Config>
  const Config& get() const {
    const auto it = slots_.find(std::type_index(typeid(Config)));
    if (it == slots_.end()) {
      static const Config kOff{};
      return kOff;
    }
    return std::any_cast<const Config&>(it->second);
  }

 private:
  std::map<std::type_index, std::any> slots_;
};

}  // namespace nimble::effects
