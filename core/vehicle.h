#pragma once
/// Physical properties of a Delfly Nimble airframe (thesis Table A.1).

#include <limits>
#include <string>
#include <vector>

#include "core/config.h"

namespace nimble {

/// Largest magnitudes recorded flight data of the airframe can have (vehicle file section
/// `data_bounds`, every key optional, each default the value the shipped vehicle files write):
/// a sample beyond one is no measurement of a flight (a diverged simulation, a corrupted or
/// mis-scaled record), and the identification toolkit refuses the record (ident/data_check.h).
/// Sources: data_bounds_params() and the vehicle files' comments; kNone switches a bound off.
struct DataBounds {
  static constexpr double kNone = std::numeric_limits<double>::infinity();
  double rate_max_radps = 50.0;            ///< |p|, |q|, |r|
  double speed_max_mps = 20.0;             ///< |u|, |v|, |w|
  double angle_max_rad = 3.14159265;       ///< |phi|, |theta|, |phi_sp|
  double delta_f_max_radps = 500.0;        ///< |delta_f|, |delta_f_cmd| (flapping-frequency difference)
  double throttle_max_pct = 100.0;         ///< |delta_t|
  double servo_max_rad = 1.5707963;        ///< |delta_d|, |delta_w|
  double specific_force_max_mps2 = 200.0;  ///< |ax|, |ay|, |az|
};

template <typename Config>
struct Param;
/// The parameter table of DataBounds (core/param_table.h: ParamTable<DataBounds>): key, range,
/// unit and meaning with its source; the loader reads the section through it, `rig params
/// vehicle.data_bounds` prints it.
const std::vector<Param<DataBounds>>& data_bounds_params();

/// Mass, inertia and wing properties of one airframe configuration.
/// Body axes: x forward, y right wing, z down. Inertias about the centre of gravity.
struct Vehicle {
  std::string name;
  std::string file;  ///< file it was loaded from (empty if built in code)
  double mass_kg = 0.0;
  double Ixx_kgm2 = 0.0;
  double Iyy_kgm2 = 0.0;
  double Izz_kgm2 = 0.0;
  double Ixz_kgm2 = 0.0;  ///< product of inertia (negative for the Nimble)
  double wing_span_m = 0.0;
  double wing_area_m2 = 0.0;  ///< Aw, area of the wings
  double mean_chord_m = 0.0;
  double r2_m = 0.0;               ///< radius of the second moment of wing area
  double flap_frequency_hz = 0.0;  ///< mean flapping frequency at hover
  double flap_amplitude_rad = 0.0;
  double air_density_kgpm3 = 0.0;
  double gravity_mps2 = 0.0;
  DataBounds data_bounds;  ///< physical bounds of recorded flight data

  /// Ic = Ixx*Izz - Ixz^2 [kg^2 m^4]; positive for a physical inertia tensor.
  double Ic() const { return Ixx_kgm2 * Izz_kgm2 - Ixz_kgm2 * Ixz_kgm2; }
  /// Mean flapping frequency in rad/s.
  double flap_frequency_radps() const;
};

/// Reads a vehicle from a mapping (the root of a vehicle file).
/// The section `data_bounds` and each of its keys are optional (DataBounds's defaults).
/// @throws ConfigError on a missing/unknown key, non-numeric value,
///         non-positive mass, inertia, geometry or data bound, or Ixx*Izz - Ixz^2 <= 0.
Vehicle vehicle_from_config(ConfigMap& map);

/// Loads and validates a vehicle file (rig_configs/vehicles/*.yaml).
/// @throws ConfigError as vehicle_from_config.
Vehicle load_vehicle(const std::string& file);

}  // namespace nimble
