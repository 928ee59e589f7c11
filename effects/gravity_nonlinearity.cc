#include "effects/gravity_nonlinearity.h"

namespace nimble::effects {

Effect gravity_nonlinearity_effect() {
  Effect e;
  e.definition = {"gravity_nonlinearity",
                  "g (sin phi - phi) cos theta0: the part of the gravity component that Eq 21 linearises "
                  "(coefficient the mass)",
                  {},
                  {{"Y", "Y_gphi", "g (sin phi - phi) cos theta0", ColumnForm::kGravityResidual}},
                  Scan::kNone,
                  Signature::kNone,
                  EffectivenessChange::kNone,
                  "nothing to add: the plant's equations of motion carry g cos(theta) sin(phi) exactly"};
  // Nothing to add: the plant's equations of motion (thesis Eq 3.1) carry g cos(theta) sin(phi)
  // with the vehicle's mass; the coefficient (the mass) is not used.
  e.from_model = [](const ModelSection& s, EffectsConfig&, std::map<std::string, double>&) {
    s.check_keys({"Y_gphi"});
  };
  return e;
}

}  // namespace nimble::effects
