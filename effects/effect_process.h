#pragma once
/// An effect while the plant flies: its state (a gust's filter, a delay line, seeded phases)
/// and the ways it may act on the plant, each a hook whose default does nothing. The plant
/// holds one process per effect that acts (registry.h, PlantSide::make) and calls every hook
/// of every process in the registry's order, so the plant model has no line for any one effect.

#include <memory>
#include <random>
#include <vector>

#include "effects/actuator_input.h"

namespace nimble::effects {

/// What an effect's loads depend on, at one evaluation of the dynamics.
struct LoadInputs {
  double du = 0.0;              ///< forward-speed perturbation u - u0 [m/s]
  double p = 0.0;               ///< roll rate [rad/s]
  double v_rel = 0.0;           ///< side velocity relative to the side wind [m/s]
  double flap_phase_rad = 0.0;  ///< the plant's flapping phase at this instant [rad]
  double t_s = 0.0;             ///< time [s]
  double roll_input_nm = 0.0;   ///< the roll input's moment of the derivative model, L_df delta_f [N m]
  double roll_input_n = 0.0;    ///< and its side force, Y_df delta_f [N]
};

/// What the plant lends a process when it is made: its step and its random stream (the
/// processes are made in the registry's order, so each draws in a fixed place of the stream).
struct ProcessContext {
  double dt_s;
  std::mt19937_64& rng;
  std::normal_distribution<double>& normal;
};

class EffectProcess {
 public:
  virtual ~EffectProcess() = default;
  /// The command the actuators see at t_s, given the one issued (`trim`: the hover command).
  virtual ActuatorInput command(double /*t_s*/, const ActuatorInput& issued, const ActuatorInput& /*trim*/) {
    return issued;
  }
  /// The side wind the aerodynamics see [m/s]: they act on v minus the sum of the effects' winds.
  virtual double side_wind_mps() const { return 0.0; }
  /// The factor on the lateral stability derivatives (the p, r and v terms of L, N and Y) at
  /// forward-speed perturbation du [m/s].
  virtual double stability_factor(double /*du*/) const { return 1.0; }
  /// Adds its roll moment L [N m] and side force Y [N].
  virtual void add_loads(const LoadInputs& /*in*/, double& /*L*/, double& /*Y*/) const {}
  /// Advances its state by one plant step of h seconds.
  virtual void step(double /*h*/, std::mt19937_64& /*rng*/, std::normal_distribution<double>& /*normal*/) {}
};

/// The process of an effect that only adds a load computed from its configuration and the
/// inputs.
template <class Config>
class LoadProcess : public EffectProcess {
 public:
  using Add = void (*)(const Config& config, const LoadInputs& in, double& L, double& Y);
  LoadProcess(const Config& config, Add add) : config_(config), add_(add) {}
  void add_loads(const LoadInputs& in, double& L, double& Y) const override { add_(config_, in, L, Y); }

 private:
  Config config_;
  Add add_;
};

/// A LoadProcess of `config` if it is enabled, else none.
template <class Config>
std::unique_ptr<EffectProcess> load_process(const Config& config, typename LoadProcess<Config>::Add add) {
  if (!config.enabled) return nullptr;
  return std::make_unique<LoadProcess<Config>>(config, add);
}

}  // namespace nimble::effects
