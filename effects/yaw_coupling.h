#pragma once
/// Yaw coupling: the yaw rate r in roll moment and side force, which the 3-state model leaves
/// out. The plant flies it as the derivatives Lr, Yr; they act only where r is a state (a
/// lateral4 model); with a lateral3 model the plant holds r at trim (0), as the vehicle's yaw
/// loop would, and they are inert.

#include "effects/effect.h"

namespace nimble::effects {

/// The effect's definition and its mapping from a model (registry.h); it has no plant section.
Effect yaw_coupling_effect();

}  // namespace nimble::effects
