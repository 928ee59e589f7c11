#pragma once
/// The plant's effects beyond the paper's linear model (section `plant.effects`), one file
/// each in this folder, and where a model's `effects:` section goes: registry.h. The plant
/// file rig_configs/plant/nimble_plant.yaml documents each effect's size and source.

#include <vector>

#include "plant/effects/actuator_delay.h"
#include "plant/effects/constant_load.h"
#include "plant/effects/effectiveness_drift.h"
#include "plant/effects/effectiveness_step.h"
#include "plant/effects/flapping_forcing.h"
#include "plant/effects/forward_speed_coupling.h"
#include "plant/effects/lateral_gust.h"
#include "plant/effects/lateral_inflow.h"

namespace nimble::plant {

/// What an effect's roll moment and side force depend on, at one evaluation of the dynamics.
struct LoadInputs {
  double du = 0.0;              ///< forward-speed perturbation u - u0 [m/s]
  double p = 0.0;               ///< roll rate [rad/s]
  double v_rel = 0.0;           ///< side velocity relative to the lateral gust [m/s]
  double flap_phase_rad = 0.0;  ///< the plant's flapping phase at this instant [rad]
  const std::vector<double>* phases_roll = nullptr;  ///< flapping forcing's seeded phases, roll moment
  const std::vector<double>* phases_side = nullptr;  ///< and side force
  double t_s = 0.0;             ///< time [s]
  double roll_input_nm = 0.0;   ///< the roll input's moment of the derivative model, L_df delta_f [N m]
  double roll_input_n = 0.0;    ///< and its side force, Y_df delta_f [N]
};

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
