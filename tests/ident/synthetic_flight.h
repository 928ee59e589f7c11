#pragma once
// Seeded synthetic identification flights shared by the identification tests.

#include <cstdint>
#include <string>

#include "core/model.h"
#include "core/vehicle.h"
#include "ident/synthetic.h"

namespace nimble::ident::test {

inline const std::string kConfigs = std::string(RIG_SOURCE_DIR) + "/rig_configs/";

/// The set-1 model (thesis Table 9.2) the synthetic flights are generated with.
inline DerivativeModel set1_model() { return load_model(kConfigs + "models/nimble_lateral_set1.yaml"); }

/// A 60 s identification flight at 512 Hz: 5 s hover, doublet train of 7 and
/// 4 Hz roll set-points (0.35 rad) under the roll PD law, small throttle
/// doublets (0.5 %: delta_t poorly excited), 5 s hover. The equation error is
/// dominated by white moment and force disturbances (as unmodelled
/// aerodynamics would be); measurement noise is small, so the correct
/// structure leaves (nearly) white residuals.
inline SyntheticOptions identification_flight(std::uint64_t seed) {
  SyntheticOptions o;
  o.duration_s = 60.0;
  o.rate_hz = 512.0;
  o.throttle_amplitude_pct = 0.5;
  o.moment_noise_Nm = 1e-4;
  o.force_noise_N = 3e-3;
  o.noise_p_radps = 0.01;
  o.noise_v_mps = 0.001;
  o.noise_phi_rad = 0.0005;
  o.noise_delta_f_radps = 0.1;
  o.noise_delta_t_pct = 0.02;
  o.seed = seed;
  return o;
}

/// A short identification flight of `duration_s` (a few seconds: doublets from 0.3 s, 0.5 s apart),
/// for the tests of short and damaged records.
inline SyntheticOptions short_identification_flight(double duration_s, std::uint64_t seed) {
  SyntheticOptions o = identification_flight(seed);
  o.duration_s = duration_s;
  o.hover_s = 0.3;
  o.doublet_gap_s = 0.5;
  o.tail_hover_s = 0.3;
  o.throttle_period_s = 1.0;
  o.throttle_amplitude_pct = 2.0;
  return o;
}

}  // namespace nimble::ident::test
