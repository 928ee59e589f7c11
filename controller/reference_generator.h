#pragma once
/// Second-order attitude reference generator with rate and acceleration limits,
/// after the Paparazzi 'int_euler' stabilisation reference that runs on the
/// Delfly Nimble (the vehicle's onboard Paparazzi 'int_euler' stabilisation).
///
/// Per axis, every control cycle of length dt:
///   angle_ref += rate_ref * dt
///   rate_ref  += accel_ref * dt
///   accel_ref  = -2 zeta omega rate_ref - omega^2 (angle_ref - angle_sp)
///   accel_ref  clamped to +-accel_max
///   rate_ref   clamped to +-rate_max; at the limit, an accel_ref that pushes
///              further out is set to zero
/// with angle_sp clamped to +-setpoint_max first.

#include <cstdint>

namespace nimble {

/// Parameters of one axis of the reference generator.
struct ReferenceGeneratorConfig {
  /// Natural frequency omega [rad/s]; 800 deg/s in the onboard code.
  double omega_radps = 13.962634015954636;
  /// Damping ratio zeta [-].
  double zeta = 0.85;
  /// Limit on |rate_ref| [rad/s]; 400 deg/s.
  double rate_max_radps = 6.981317007977318;
  /// Limit on |accel_ref| [rad/s^2]; 8000 deg/s^2.
  double accel_max_radps2 = 139.62634015954637;
  /// Limit on |angle set-point| [rad]; 60 deg.
  double setpoint_max_rad = 1.0471975511965976;
};

/// State of one axis of the reference generator.
struct ReferenceState {
  double angle_rad = 0.0;     ///< reference angle [rad]
  double rate_radps = 0.0;    ///< reference rate [rad/s]
  double accel_radps2 = 0.0;  ///< reference acceleration [rad/s^2]
};

/// One axis of the reference generator, integrated at a fixed step.
class ReferenceGenerator {
 public:
  /// @throws std::invalid_argument if dt_s or any parameter is not positive and
  ///         finite (zeta may be zero, not negative).
  ReferenceGenerator(const ReferenceGeneratorConfig& config, double dt_s);

  /// Advances one step towards `setpoint_rad` [rad] and returns the new state.
  /// A set-point beyond +-setpoint_max is clamped (counted); a non-finite one
  /// is replaced by the previous set-point (counted). Never throws.
  const ReferenceState& step(double setpoint_rad);

  /// Restarts at rest at `angle_rad` [rad] (rate and acceleration zero).
  void reset(double angle_rad = 0.0);

  /// Current state.
  const ReferenceState& state() const { return state_; }
  /// Parameters in use.
  const ReferenceGeneratorConfig& config() const { return config_; }
  /// Step length [s].
  double dt_s() const { return dt_s_; }
  /// Number of steps whose set-point was clamped or replaced.
  std::int64_t setpoint_clamp_count() const { return setpoint_clamp_count_; }

 private:
  ReferenceGeneratorConfig config_;
  double dt_s_;
  ReferenceState state_;
  double last_setpoint_rad_ = 0.0;
  std::int64_t setpoint_clamp_count_ = 0;
};

/// Checks a reference-generator parameter set.
/// @throws std::invalid_argument naming the first bad parameter and its value.
void validate(const ReferenceGeneratorConfig& config);

}  // namespace nimble
