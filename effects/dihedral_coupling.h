#pragma once
/// Dihedral coupling: the dihedral input delta_d in roll moment and side force, which the
/// 3-state model leaves out. The plant flies it as the derivatives L_dd, Y_dd.

#include "effects/effect.h"

namespace nimble::effects {

/// The effect's definition and its mapping from a model (registry.h); it has no plant section.
Effect dihedral_coupling_effect();

}  // namespace nimble::effects
