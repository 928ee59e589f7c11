#pragma once
/// The actuator command as the plant receives it (PlantModel::step()), and as an effect on the
/// commands sees it (effects/effect_process.h).

namespace nimble::effects {

struct ActuatorInput {
  double flap_freq_left_radps = 0.0;
  double flap_freq_right_radps = 0.0;
  double dihedral_rad = 0.0;
  double wing_root_rad = 0.0;
};

}  // namespace nimble::effects
