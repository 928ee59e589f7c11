#pragma once
/// Physical properties of a Delfly Nimble airframe (thesis Table A.1).

#include <string>

#include "core/config.h"

namespace nimble {

/// Mass, inertia and wing properties of one airframe configuration.
/// Body axes: x forward, y right wing, z down. Inertias about the centre of gravity.
struct Vehicle {
  std::string name;
  std::string file;               ///< file it was loaded from (empty if built in code)
  double mass_kg = 0.0;
  double Ixx_kgm2 = 0.0;
  double Iyy_kgm2 = 0.0;
  double Izz_kgm2 = 0.0;
  double Ixz_kgm2 = 0.0;          ///< product of inertia (negative for the Nimble)
  double wing_span_m = 0.0;
  double wing_area_m2 = 0.0;      ///< Aw, area of the wings
  double mean_chord_m = 0.0;
  double r2_m = 0.0;              ///< radius of the second moment of wing area
  double flap_frequency_hz = 0.0; ///< mean flapping frequency at hover
  double flap_amplitude_rad = 0.0;
  double air_density_kgpm3 = 0.0;
  double gravity_mps2 = 0.0;

  /// Ic = Ixx*Izz - Ixz^2 [kg^2 m^4]; positive for a physical inertia tensor.
  double Ic() const { return Ixx_kgm2 * Izz_kgm2 - Ixz_kgm2 * Ixz_kgm2; }
  /// Mean flapping frequency in rad/s.
  double flap_frequency_radps() const;
};

/// Reads a vehicle from a mapping (the root of a vehicle file).
/// @throws ConfigError on a missing/unknown key, non-numeric value,
///         non-positive mass, inertia or geometry, or Ixx*Izz - Ixz^2 <= 0.
Vehicle vehicle_from_config(ConfigMap& map);

/// Loads and validates a vehicle file (rig_configs/vehicles/*.yaml).
/// @throws ConfigError as vehicle_from_config.
Vehicle load_vehicle(const std::string& file);

}  // namespace nimble
