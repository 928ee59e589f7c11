#pragma once
/// The Ce500 lateral model of the practical, built from the derivatives and the flight
/// condition (paper-facts section 8; ce500_practical.yaml), never from printed matrices.
///
/// Full model: states [beta, phi, pb/2V, rb/2V, u_g, u_g*, alpha_g, alpha_g*, beta_g, beta_g*]
/// (angles in rad, the rates non-dimensional, the gust states u_g = u_g/V, alpha_g, beta_g
/// non-dimensional), inputs [delta_a, delta_r, w1, w3, w2] (rad, rad, then the unit-intensity
/// white noises of the u_g, alpha_g and beta_g filters):
///   beta_dot     = y_b beta + y_phi phi + y_p p^ + y_r r^ + y_bg beta_g + y_dr delta_r
///   phi_dot      = (2V/b) p^
///   p^_dot       = l_b beta + l_p p^ + l_r r^ + l_ug u_g + l_ag alpha_g + l_bg beta_g + l_da delta_a + l_dr delta_r
///   r^_dot       = the same with n
///   (u_g, u_g*), (alpha_g, alpha_g*), (beta_g, beta_g*): the practical's filters (dryden.h)
/// with y_b = (V/b) CYb/(2 mu_b), y_phi = (V/b) CL/(2 mu_b), y_p = (V/b) CYp/(2 mu_b),
/// y_r = (V/b)(CYr - 4 mu_b)/(2 mu_b), y_dr = (V/b) CYdr/(2 mu_b), y_bg = y_b, and with
/// den = b 4 mu_b (KX^2 KZ^2 - KXZ^2)/V, l_* = (Cl* KZ^2 + Cn* KXZ)/den,
/// n_* = (Cl* KXZ + Cn* KX^2)/den for (Cl*, Cn*) = (Clb, Cnb), (Clp, Cnp), (Clr, Cnr),
/// (Clda, Cnda), (Cldr, Cndr), u_g: (-Clrw, -Cnrw), alpha_g: (Clpw, Cnpw), beta_g: (Clb, Cnb).
///
/// Roll damper: delta_a = -K x with K_phi on phi and K_p on pb/2V (K_phi = -0.1, K_p = 0).
///
/// Reduced model (practical Eqs 2.9-2.13, beta = -psi with phi kept): the aircraft block is
/// P^-1 Q and its control columns P^-1 R, with
///   P = [[b/2V, 0, 0, 0], [0, -b/2V, 0, 0], [0, 0, -4 mu_b KX^2 b/V, 4 mu_b KXZ b/V],
///        [0, 0, 4 mu_b KXZ b/V, -4 mu_b KZ^2 b/V]]
/// (the practical prints KXZ^2 in row 4: a misprint, paper-facts 8.1 and the moment equations
/// have KXZ), Q = [[0,0,0,-1], [0,0,-1,0], [-Clb,0,-Clp,-Clr], [-Cnb,0,-Cnp,-Cnr]],
/// R = [[0,0], [0,0], [-Clda,-Cldr], [-Cnda,-Cndr]].
/// Gust columns (the practical does not print them): the gust moments enter the moment rows as
/// in the full model, P^-1 [0; 0; Cl_g; Cn_g] for Cl_g = (-Clrw, Clpw, Clb) on (u_g, alpha_g,
/// beta_g), which is exactly the full model's l_ug .. n_bg because P's moment block is the
/// full model's inertia coupling. ReducedGustColumns::kFullModelRows (the practical file's
/// choice) also copies the full model's side-force gust term y_bg beta_g into the kinematic row
/// beta_dot = -(2V/b) r^: the practical concatenates the full model's gust columns (text after
/// its Eq 2.13), and its Table 5.1 R column agrees better with it. kMomentRows leaves that row
/// as the pure kinematics of beta = -psi. The gust filters are the full model's, so the
/// reduced model keeps 10 states.
///
/// Outputs of every system: beta [deg], phi [deg], p_hat = pb/2V [-], r_hat = rb/2V [-],
/// a_y = V (beta_dot + r) [m/s^2] (practical Eq 3.2) with r = (2V/b) r^ [rad/s] and beta_dot
/// from the full model's side-force equation (closed loop where the damper is on). For the
/// reduced model this evaluates the side-force equation on its states: its own kinematics
/// beta_dot = -r make V (beta_dot + r) vanish identically.

#include <complex>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "turbulence/ce500_config.h"
#include "turbulence/dryden.h"
#include "turbulence/linear_system.h"

namespace nimble::turbulence {

/// The state layout of the CE-500 model: the aircraft's four states (beta, phi, pb/2V, rb/2V)
/// first, then the six of the gust filters.
inline constexpr Eigen::Index kCe500AircraftStates = 4;
inline constexpr Eigen::Index kCe500GustStates = 6;
inline constexpr Eigen::Index kCe500States = kCe500AircraftStates + kCe500GustStates;

/// The dimensional coefficients of the full model [1/s].
struct Ce500Coefficients {
  double y_b = 0, y_phi = 0, y_p = 0, y_r = 0, y_dr = 0, y_bg = 0;
  double l_b = 0, l_p = 0, l_r = 0, l_da = 0, l_dr = 0, l_ug = 0, l_ag = 0, l_bg = 0;
  double n_b = 0, n_p = 0, n_r = 0, n_da = 0, n_dr = 0, n_ug = 0, n_ag = 0, n_bg = 0;
  PracticalFilterCoefficients u_g, alpha_g, beta_g;
};

/// The coefficients from the configuration.
Ce500Coefficients ce500_coefficients(const Ce500Config& config);

/// The open-loop full model with the five outputs.
LinearSystem ce500_full_model(const Ce500Config& config);

/// K of delta_a = -K x (1 x 10): K_phi on phi, K_p on pb/2V.
Eigen::RowVectorXd ce500_roll_damper_gain(const Ce500Config& config);

/// The full model with the roll damper closed on delta_a.
LinearSystem ce500_controlled_model(const Ce500Config& config);

/// The reduced model (with the roll damper closed unless `with_damper` is false).
LinearSystem ce500_reduced_model(const Ce500Config& config, bool with_damper = true);

/// White-noise intensity per input of the Ce500 models: 0 for delta_a, delta_r and an input
/// not excited, config.excitation.intensity for the excited ones.
Eigen::VectorXd ce500_noise_intensity(const Ce500Config& config);

/// The gust filters of the configuration (u_g, alpha_g, beta_g).
std::vector<ShapingFilter> ce500_gust_filters(const Ce500Config& config);

/// An eigenvalue with the name of its mode.
struct NamedEigenvalue {
  std::complex<double> value;
  std::string mode;
};

/// Eigenvalues of a Ce500 system (10 states as above) with mode names. The model is block
/// upper triangular (the gust filters are not driven by the aircraft), so the aircraft
/// eigenvalues are those of the 4 x 4 aircraft block and the gust poles those of each filter.
/// Aircraft names: a single complex pair is the Dutch roll; of two pairs, the Dutch roll is the
/// faster oscillation (larger imaginary part), the other the roll pair (aperiodic roll and bank
/// angle joined by the roll damper); of two real eigenvalues the faster is the
/// aperiodic roll and the slower the spiral; a zero eigenvalue is the neutral bank angle.
/// Sorted by real part descending, then imaginary part descending.
std::vector<NamedEigenvalue> ce500_named_eigenvalues(const LinearSystem& sys);

}  // namespace nimble::turbulence
