#pragma once
/// Kinematic coupling: p (w - w0), the vertical-velocity part of the kinematic term p w of v_dot
/// that Eq 21 linearises at w0. The plant's equations of motion carry p w exactly: a model
/// carrying it needs nothing added.

#include "effects/effect.h"

namespace nimble::effects {

/// The effect's definition and its mapping from a model (registry.h); it has no plant section.
Effect kinematic_coupling_effect();

}  // namespace nimble::effects
