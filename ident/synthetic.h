#pragma once
/// Synthetic flight data from a linear lateral model, for tests, benchmarks
/// and dry runs of the identification.
///
/// The model (lateral3 or lateral4, inputs delta_f and optionally delta_t) is
/// flown in closed loop by a roll PD law on a doublet train of roll set-points,
///   delta_f_cmd = k_phi (phi_sp - phi) - k_p p        [rad/s],
/// with throttle doublets on delta_t_cmd [%]. Both commands pass a first-order
/// actuator a/(s + a), so the recorded delta_f and delta_t are continuous and
/// the model relation holds exactly between the samples. Process noise enters
/// as white (piecewise-constant) moment and force disturbances; measurement
/// noise is added to the recorded channels. Simulation: exact ZOH
/// discretisation of the augmented system at the output rate.
///
/// Doublet of main frequency f: +A for 1/(2f) s, then -A for 1/(2f) s
/// (it lasts 1/f s).

#include <cstdint>
#include <vector>

#include "contract/default_rates.h"
#include "core/model.h"
#include "core/vehicle.h"
#include "ident/flight_data.h"

namespace nimble::ident {

/// Options of simulate_synthetic(). Defaults: a set-1-like identification
/// flight with the fast gains scaled by 80 rad/s per unit command.
struct SyntheticOptions {
  double duration_s = 60.0;
  double rate_hz = contract::kDefaultImuRateHz;
  double hover_s = 5.0;  ///< hover before the first doublet [s]
  std::vector<double> doublet_frequencies_hz{7.0, 4.0};
  double doublet_amplitude_rad = 0.35;  ///< roll set-point amplitude [rad]
  double doublet_gap_s = 1.5;           ///< hover after each doublet [s]
  double tail_hover_s = 5.0;            ///< hover at the end [s]
  double k_phi_radps_per_rad = 112.0;   ///< PD gain on the roll error
  double k_p_radps_per_radps = 16.0;    ///< PD gain on the roll rate
  double throttle_amplitude_pct = 2.0;  ///< throttle doublet amplitude [%]
  double throttle_frequency_hz = 2.0;   ///< main frequency of the throttle doublets
  double throttle_period_s = 3.7;       ///< one throttle doublet every this many s
  double actuator_pole_radps = 12.56;   ///< a of a/(s + a)
  double moment_noise_Nm = 0.0;         ///< std of the L (and N) disturbance per sample
  double force_noise_N = 0.0;           ///< std of the Y disturbance per sample
  double noise_p_radps = 0.0;           ///< measurement noise std of p (and r)
  double noise_v_mps = 0.0;
  double noise_phi_rad = 0.0;
  double noise_delta_f_radps = 0.0;
  double noise_delta_t_pct = 0.0;
  std::uint64_t seed = 1;
};

/// Simulates `model` flown as described above and returns the recorded
/// channels t, p, (r), v, phi, delta_f, delta_t (zero if the model has no
/// delta_t input), phi_sp.
/// @throws std::invalid_argument if the model is not lateral3/lateral4, has
///         an input other than delta_f/delta_t or no delta_f, an option is out
///         of range, or the closed loop is not stable.
FlightData simulate_synthetic(const DerivativeModel& model, const Vehicle& vehicle, const SyntheticOptions& options);

/// Roll set-point of the doublet train at time t_s [rad].
double doublet_train_rad(const SyntheticOptions& options, double t_s);

}  // namespace nimble::ident
