#pragma once
/// Periodic forcing at the flapping frequency and its harmonics (thesis §7: oscillations at
/// hover not captured by the linear model). Amplitude h-1 of a list acts at h times the
/// flapping frequency of the actual collective (about 16-17 Hz at trim), phase-locked to the
/// plant's flapping phase; the phases relative to it are drawn from the seed. Flies the model
/// effect flapping_forcing: amplitude hypot(<eq>_sin<h>, <eq>_cos<h>) (or <eq>_amp<h>) at
/// harmonic h; its flapping_hz is not needed (the plant forces at its own flapping frequency).

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "core/config.h"
#include "effects/effect_process.h"
#include "effects/effect_sizing.h"
#include "effects/model_section.h"
#include "effects/effect.h"

namespace nimble::effects {

struct FlappingForcingConfig {
  bool enabled = false;
  std::vector<double> roll_moment_amplitudes_nm;  ///< per harmonic [N m]
  std::vector<double> side_force_amplitudes_n;    ///< per harmonic [N]
};

/// `plant.effects.flapping_forcing` as Markdown rows (its parameters are lists, which a
/// parameter table does not hold): key, default, allowed, unit, meaning.
std::string flapping_forcing_markdown_rows(const std::string& prefix);

/// Reads the section (enabled is required; the lists are numbers with |amplitude| <= 1).
/// @throws ConfigError naming the key.
FlappingForcingConfig flapping_forcing_from(ConfigMap& map);

/// The model effect flapping_forcing (flapping_hz, <eq>_sin<h>, <eq>_cos<h>, <eq>_amp<h> for eq
/// L and Y and h = 1..10).
void flapping_forcing_from_model(const ModelSection& section, FlappingForcingConfig& config);

/// Adds the forcing at flapping phase `phase` [rad], with the seeded phases of each harmonic.
inline void add_flapping_forcing(const FlappingForcingConfig& c, double phase, const std::vector<double>& phases_roll,
                                 const std::vector<double>& phases_side, double& L, double& Y) {
  if (!c.enabled) return;
  for (std::size_t h = 0; h < c.roll_moment_amplitudes_nm.size(); ++h) {
    L += c.roll_moment_amplitudes_nm[h] * std::sin(static_cast<double>(h + 1) * phase + phases_roll[h]);
  }
  for (std::size_t h = 0; h < c.side_force_amplitudes_n.size(); ++h) {
    Y += c.side_force_amplitudes_n[h] * std::sin(static_cast<double>(h + 1) * phase + phases_side[h]);
  }
}

/// The effect's process, with the phase of each harmonic drawn from the plant's stream (the roll
/// moment's, then the side force's, uniform in [0, 2 pi)). The phases are drawn whether the
/// effect is on or not, so switching it leaves the draws of every effect made after it as they
/// were; none when it is off.
std::unique_ptr<EffectProcess> flapping_forcing_process(const FlappingForcingConfig& config, ProcessContext& context);

/// SIZE sets the first roll amplitude; every amplitude of both lists scales with it.
EffectSizing flapping_forcing_sizing();

/// The effect's definition, its mapping from a model and its plant section (registry.h).
Effect flapping_forcing_effect();

}  // namespace nimble::effects
