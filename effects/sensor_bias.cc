#include "effects/sensor_bias.h"

#include "effects/constant_load.h"

namespace nimble::effects {

Effect sensor_bias_effect() {
  Effect e;
  e.definition = {kSensorBiasName,
                  "constant in both equations from a biased measurement: the rate gyro's p carries a constant offset, "
                  "which the kinematics show (p against phi's derivative)",
                  {},
                  {{"L", "L_0", "1", ColumnForm::kTerm, "1"}, {"Y", "Y_0", "1", ColumnForm::kTerm, "1"}},
                  Scan::kNone,
                  Signature::kRateGyroBias,
                  EffectivenessChange::kNone,
                  "plant.effects.constant_load: constant roll moment L_0 and side force Y_0"};
  // The workflow's sensor_bias fits the same constant L_0 and Y_0 as constant_load (they differ
  // in what the rate gyro shows against the kinematics): the plant flies it as that constant
  // load, the same moment and force.
  e.from_model = config_from_model(constant_load_from_model);
  return e;
}

}  // namespace nimble::effects
