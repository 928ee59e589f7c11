#pragma once
/// Dryden turbulence shaping filters: unit-intensity white noise in (S_ww = 1, see
/// spectral_density.h), gust velocity (or gust angle) out, each as a continuous state space
/// with its analytical PSD in the library's convention sigma^2 = (1/pi) int_0^inf S d omega.
///
/// Time-based forms (hovering vehicle: intensity sigma and a correlation time T instead of a
/// length scale flown through at V):
///   first order   S(omega) = 2 sigma^2 T / (1 + (omega T)^2),
///                 H(s) = sigma sqrt(2 T) / (1 + T s);
///   second order  S(omega) = sigma^2 T (1 + 3 (omega T)^2) / (1 + (omega T)^2)^2,
///                 H(s) = sigma sqrt(T) (1 + sqrt(3) T s) / (1 + T s)^2.
/// MIL-F-8785C (spatial PSDs Phi(Omega) with int_0^inf Phi dOmega = sigma^2, converted by
/// S(omega) = (pi / V) Phi(omega / V)): longitudinal u_g is the first-order form with T = L_u/V,
/// lateral v_g and vertical w_g the second-order form with T = L_v/V, L_w/V.
/// MIL-HDBK-1797 writes the lateral and vertical Dryden PSDs with 2 L (Phi = sigma^2 (2L/pi)
/// (1 + 12 (L Omega)^2) / (1 + 4 (L Omega)^2)^2): the same second-order form with T = 2 L / V;
/// its u_g form equals 8785C's.
///
/// The practical's filters (paper-facts section 8; L_g the scale length, tau in units of L_g/V):
///   u_g and alpha_g: x1_dot = x2 + b1 w, x2_dot = a1 x1 + a2 x2 + b2 w, out x1, with
///     a1 = -(V/L)^2/(ta tb), a2 = -(ta+tb)(V/L)/(ta tb), b1 = tc sqrt(I0 V/L)/(ta tb),
///     b2 = (1 - tc (ta+tb)/(ta tb)) sqrt(I0 (V/L)^3)/(ta tb)
///     (ta, tb, tc = tau1..3 for u_g with I0 = Iug0, tau4..6 for alpha_g with I0 = Iag0);
///   beta_g: the same realisation with a1 = -(V/L)^2, a2 = -2V/L, b1 = (sigma/V) sqrt(3 V/L),
///     b2 = (1 - 2 sqrt 3)(sigma/V) sqrt((V/L)^3): its transfer function is exactly the
///     second-order (MIL-F-8785C lateral) form of sigma/V with T = L/V.

#include <functional>
#include <string>

#include "turbulence/linear_system.h"

namespace nimble::turbulence {

/// A shaping filter: one unit-intensity white-noise input "w", one output, and its PSD.
struct ShapingFilter {
  std::string name;
  LinearSystem system;                ///< input "w", output the gust quantity
  std::function<double(double)> psd;  ///< S(omega) [output unit^2/(rad/s)], omega [rad/s]
  double variance = 0.0;              ///< (1/pi) int_0^inf S: closed form where one exists
};

/// Which standard's Dryden lateral/vertical scale convention to use.
enum class DrydenStandard { kMilF8785C, kMilHdbk1797 };

/// First-order time-based filter (sigma > 0 [unit], T > 0 [s]). @throws std::invalid_argument.
ShapingFilter time_based_first_order(double sigma, double T_s);
/// Second-order time-based filter (sigma > 0 [unit], T > 0 [s]). @throws std::invalid_argument.
ShapingFilter time_based_second_order(double sigma, double T_s);

/// Longitudinal u_g [m/s]: sigma_u [m/s], L_u [m], V [m/s] > 0. @throws std::invalid_argument.
ShapingFilter dryden_longitudinal(double sigma_mps, double L_m, double V_mps);
/// Lateral v_g [m/s] (sigma_v, L_v, V > 0) in the scale convention of `standard`.
ShapingFilter dryden_lateral(double sigma_mps, double L_m, double V_mps,
                             DrydenStandard standard = DrydenStandard::kMilF8785C);
/// Vertical w_g [m/s]: the same form as the lateral one with sigma_w, L_w.
ShapingFilter dryden_vertical(double sigma_mps, double L_m, double V_mps,
                              DrydenStandard standard = DrydenStandard::kMilF8785C);

/// Coefficients of the practical's two-state realisation (see the header comment).
struct PracticalFilterCoefficients {
  double a1 = 0.0, a2 = 0.0, b1 = 0.0, b2 = 0.0;
};

/// a1, a2, b1, b2 of the practical's u_g or alpha_g filter (V, L > 0, ta, tb > 0, tc >= 0,
/// I0 > 0 the intensity [-]). @throws std::invalid_argument.
PracticalFilterCoefficients practical_asymmetric_coefficients(double V_mps, double L_m, double ta, double tb, double tc,
                                                              double I0);
/// a1, a2, b1, b2 of the practical's beta_g filter (sigma, V, L > 0).
PracticalFilterCoefficients practical_beta_g_coefficients(double sigma_mps, double V_mps, double L_m);

/// The practical's two-state filter with these coefficients, named `name` (output [rad] for
/// the gust angles); its PSD is |b1 i omega + b2 - a2 b1|^2 / |a1 + a2 i omega + omega^2|^2.
/// @throws std::invalid_argument if the filter is not stable (a1 < 0, a2 < 0 required).
ShapingFilter practical_filter(const std::string& name, const PracticalFilterCoefficients& c);

}  // namespace nimble::turbulence
