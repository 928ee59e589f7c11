#pragma once
/// Gravity nonlinearity: g (sin phi - phi) cos theta0, the part of the gravity component that
/// Eq 21 linearises. The plant's equations of motion carry g cos(theta) sin(phi) exactly: a
/// model carrying it needs nothing added.

#include "effects/effect.h"

namespace nimble::effects {

/// The effect's definition and its mapping from a model (registry.h); it has no plant section.
Effect gravity_nonlinearity_effect();

}  // namespace nimble::effects
