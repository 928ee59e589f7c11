#include "effects/yaw_coupling.h"

namespace nimble::effects {

Effect yaw_coupling_effect() {
  Effect e;
  e.definition = {"yaw_coupling",
                  "r in roll moment and side force: the yaw rate the 3-state model leaves out",
                  {"r"},
                  {{"L", "Lr", "r", ColumnForm::kTerm, "r"}, {"Y", "Yr", "r", ColumnForm::kTerm, "r"}},
                  Scan::kNone,
                  Signature::kNone,
                  EffectivenessChange::kNone,
                  "the yaw-rate derivatives Lr, Yr (inert on a lateral3 model: r held at trim)"};
  e.from_model = [](const ModelSection& s, EffectsConfig&, std::map<std::string, double>& derivatives) {
    s.check_keys({"Lr", "Yr"});
    s.set_derivative("Lr", derivatives, kRollDerivativeRange);
    s.set_derivative("Yr", derivatives, kSideDerivativeRange);
  };
  return e;
}

}  // namespace nimble::effects
