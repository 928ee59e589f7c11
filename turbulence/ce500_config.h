#pragma once
/// Configuration of the Ce500 practical (rig_configs/turbulence/ce500_practical.yaml): flight
/// condition, derivatives, turbulence, excitation, roll damper, reduced-model choice,
/// simulation settings and the practical's published tables. Every value's source is
/// commented in the YAML file; loading is strict (core/config.h): a missing, unknown,
/// non-numeric or out-of-range value is a ConfigError naming the file, key and value.

#include <array>
#include <complex>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "core/config.h"

namespace nimble::turbulence {

/// Flight condition and inertia (non-dimensional, Ce500 practical).
struct Ce500FlightCondition {
  double V_mps = 0.0;  ///< true airspeed, > 0
  double S_m2 = 0.0;   ///< wing area, > 0 (not used by the non-dimensional construction)
  double b_m = 0.0;    ///< span, > 0
  double mu_b = 0.0;   ///< relative density, > 0
  double KX2 = 0.0;    ///< KX^2, > 0
  double KZ2 = 0.0;    ///< KZ^2, > 0
  double KXZ = 0.0;    ///< KXZ, with KX2 KZ2 - KXZ^2 > 0
  double CL = 0.0;     ///< trim lift coefficient, >= 0
};

/// Non-dimensional derivatives [-].
struct Ce500Derivatives {
  double CYb = 0, CYp = 0, CYr = 0, CYda = 0, CYdr = 0;
  double Clb = 0, Clp = 0, Clr = 0, Clda = 0, Cldr = 0;
  double Cnb = 0, Cnp = 0, Cnr = 0, Cnda = 0, Cndr = 0;
  /// Gust derivatives as fractions of the aircraft ones.
  double Clpw_per_Clp = 0, Cnpw_per_Cnp = 0, Clrw_per_Clr = 0, Cnrw_per_Cnr = 0;
};

/// Dryden turbulence of the practical.
struct Ce500Turbulence {
  double Lg_m = 0.0;
  double sigma_ug_mps = 0.0, sigma_vg_mps = 0.0, sigma_wg_mps = 0.0;
  double Iug0_factor = 0.0;     ///< Iug0 = factor (sigma_ug / V)^2
  double Iag0_factor = 0.0;     ///< Iag0 = factor (sigma_wg / V)^2
  std::array<double, 6> tau{};  ///< tau1..tau6 [-] in units of Lg / V
};

/// Which white-noise inputs drive the filters and with what intensity.
struct Ce500Excitation {
  bool u_g = false, v_g = true, w_g = true;
  double intensity = 1.0;
};

/// How the gust columns join the reduced model (ce500_model.h).
enum class ReducedGustColumns { kMomentRows, kFullModelRows };

/// Simulation defaults (the command line overrides them).
struct Ce500Simulation {
  double dt_s = 0.05;
  double duration_s = 600.0;
  std::uint64_t seed = 1;
  std::size_t welch_segment = 0;  ///< 0: default_welch_segment()
};

/// The practical's Table 5.1 row of one output: [controlled, reduced] per method.
struct PublishedVarianceRow {
  std::array<double, 2> analytical{}, fft{}, pwelch{}, var{};
};

/// The practical's published numbers, for comparison.
struct Ce500Published {
  double eigenvalue_tolerance = 1e-3;
  double record_length_s = 30.0;  ///< assumed record length behind Table 5.1's var.m column [s]
  std::vector<std::complex<double>> uncontrolled, controlled, reduced;  ///< Table 2.1 columns
  std::map<std::string, PublishedVarianceRow> table_5_1;                ///< by output name
};

/// The whole practical.
struct Ce500Config {
  std::string file;
  Ce500FlightCondition flight;
  Ce500Derivatives derivatives;
  Ce500Turbulence turbulence;
  Ce500Excitation excitation;
  double K_phi = 0.0;  ///< roll damper gain on phi [rad/rad], delta_a = -K x
  double K_p = 0.0;    ///< roll damper gain on pb/2V [rad]
  ReducedGustColumns reduced_gust_columns = ReducedGustColumns::kFullModelRows;
  Ce500Simulation simulation;
  Ce500Published published;
};

/// The output names of rig turbulence, in order: beta [deg], phi [deg], p_hat = pb/2V [-],
/// r_hat = rb/2V [-], a_y [m/s^2].
const std::vector<std::string>& ce500_output_names();

/// Reads the practical from a root mapping. @throws ConfigError naming file, key and value.
Ce500Config ce500_config_from_map(ConfigMap& map);

/// Loads and validates a practical file. @throws ConfigError.
Ce500Config load_ce500_config(const std::string& file);

}  // namespace nimble::turbulence
