#include "effects/kinematic_coupling.h"

namespace nimble::effects {

Effect kinematic_coupling_effect() {
  Effect e;
  e.definition = {"kinematic_coupling",
                  "p (w - w0): the vertical-velocity part of the kinematic term p w of v_dot that Eq 21 linearises at "
                  "w0 (coefficient the mass)",
                  {"w"},
                  {{"Y", "Y_pw", "p (w - w0)", ColumnForm::kTerm, "p*(w - w0)"}},
                  Scan::kNone,
                  Signature::kNone,
                  EffectivenessChange::kNone,
                  "nothing to add: the plant's equations of motion carry p w exactly"};
  // Nothing to add: the plant's equations of motion (thesis Eq 3.1) carry p w with the
  // vehicle's mass; the coefficient (the mass) is not used.
  e.from_model = [](const ModelSection& s, EffectsConfig&, std::map<std::string, double>&) { s.check_keys({"Y_pw"}); };
  return e;
}

}  // namespace nimble::effects
