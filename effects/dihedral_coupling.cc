#include "effects/dihedral_coupling.h"

namespace nimble::effects {

Effect dihedral_coupling_effect() {
  Effect e;
  e.definition = {
      "dihedral_coupling",
      "delta_d in roll moment and side force: the dihedral input the 3-state model leaves out",
      {"delta_d"},
      {{"L", "L_dd", "delta_d", ColumnForm::kTerm, "delta_d"}, {"Y", "Y_dd", "delta_d", ColumnForm::kTerm, "delta_d"}},
      Scan::kNone,
      Signature::kNone,
      EffectivenessChange::kNone,
      "the dihedral derivatives L_dd, Y_dd"};
  e.from_model = [](const ModelSection& s, EffectsConfig&, std::map<std::string, double>& derivatives) {
    s.check_keys({"L_dd", "Y_dd"});
    s.set_derivative("L_dd", derivatives, kRollDerivativeRange);
    s.set_derivative("Y_dd", derivatives, kSideDerivativeRange);
  };
  return e;
}

}  // namespace nimble::effects
