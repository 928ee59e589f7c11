#pragma once
/// The plant's effects beyond the paper's linear model (section `plant.effects`), one file
/// each in this folder, and where a model's `effects:` section goes: registry.h. The plant
/// file rig_configs/plant/nimble_plant.yaml documents each effect's size and source.

#include "plant/effects/actuator_delay.h"
#include "plant/effects/constant_load.h"
#include "plant/effects/effect_process.h"
#include "plant/effects/effectiveness_drift.h"
#include "plant/effects/effectiveness_step.h"
#include "plant/effects/flapping_forcing.h"
#include "plant/effects/forward_speed_coupling.h"
#include "plant/effects/lateral_gust.h"
#include "plant/effects/lateral_inflow.h"

namespace nimble::plant {

/// Every plant effect's configuration (all off by default).
struct EffectsConfig {
  FlappingForcingConfig flapping_forcing;
  LateralInflowConfig lateral_inflow;
  ForwardSpeedCouplingConfig forward_speed_coupling;
  ActuatorDelayConfig actuator_delay;
  LateralGustConfig lateral_gust;
  ConstantLoadConfig constant_load;
  EffectivenessDriftConfig effectiveness_drift;
  EffectivenessStepConfig effectiveness_step;
};

}  // namespace nimble::plant
