#pragma once
/// Actuator delay: a pure delay on every actuator command (flap frequencies and servos), the
/// transmission and motor driver. Flies the model effect actuator_delay (delay_s): a pure delay
/// commutes with the linear flap actuator, so delaying the command is the dynamics the
/// regression finds on the actuator's output.

#include <deque>
#include <memory>
#include <utility>

#include "core/config.h"
#include "core/param_table.h"
#include "effects/effect_process.h"
#include "effects/effect_sizing.h"
#include "effects/model_section.h"
#include "effects/effect.h"

namespace nimble::effects {

struct ActuatorDelayConfig {
  bool enabled = false;
  double delay_s = 0.0;
};

/// `plant.effects.actuator_delay`: key, range, unit, meaning.
const ParamTable<ActuatorDelayConfig>& actuator_delay_params();

/// Reads the section (enabled is required). @throws ConfigError naming the key.
ActuatorDelayConfig actuator_delay_from(ConfigMap& map);

/// The model effect actuator_delay: delay_s (required); the regression's <eq>_df_delayed,
/// <eq>_df_fraction_delayed and <eq>_cmd_delayed are accepted and not needed.
void actuator_delay_from_model(const ModelSection& section, ActuatorDelayConfig& config);

/// The effect's process: the command the actuators see at time t is the newest one issued at
/// least delay_s before (`trim` before any was).
template <typename Command>
class CommandDelay {
 public:
  Command apply(const ActuatorDelayConfig& c, double t_s, const Command& cmd, const Command& trim) {
    if (!c.enabled || c.delay_s <= 0.0) return cmd;
    line_.emplace_back(t_s, cmd);
    const double cutoff = t_s - c.delay_s + 1e-9;
    while (line_.size() >= 2 && line_[1].first <= cutoff) line_.pop_front();
    return line_.front().first <= cutoff ? line_.front().second : trim;
  }

 private:
  std::deque<std::pair<double, Command>> line_;
};

/// The effect's process: a CommandDelay of the plant's commands; none when it is off or its
/// delay is not positive.
std::unique_ptr<EffectProcess> actuator_delay_process(const ActuatorDelayConfig& config);

/// SIZE sets delay_s.
EffectSizing actuator_delay_sizing();

/// The effect's definition, its mapping from a model and its plant section (registry.h).
Effect actuator_delay_effect();

}  // namespace nimble::effects
