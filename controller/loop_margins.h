#pragma once
/// Stability margins of a sampled single-loop feedback system, from its state-space form
/// broken at one point: the frequency response of the loop, its gain, phase and delay
/// margins, the peak of its sensitivity and its closed-loop eigenvalues. Used by the roll
/// loop (controller/roll_loop.h, `rig loop`); nothing in it is specific to one axis.
///
/// The broken loop: x[k+1] = A x[k] + B w[k], y[k] = C x[k] + D w[k], sampled every dt_s.
/// Closing it sets w = y. The return ratio is L(z) = -(C (zI - A)^-1 B + D), so that the
/// closed loop's characteristic polynomial is det(zI - A) (1 + L(z)) and the Nyquist point
/// is -1, as in the textbooks (Skogestad & Postlethwaite, Multivariable Feedback Control,
/// Ch. 2; Franklin, Powell & Workman, Digital Control, Ch. 7).
///
/// Margins, all on z = exp(j w dt) for w in (0, pi/dt]:
///  - gain margin: the closed loop with the loop gain scaled by k is on its stability boundary
///    exactly where 1 + k L = 0, i.e. where L is real and negative (a phase crossover, or
///    w = 0 or the Nyquist frequency) and k = -1/L. The candidates k nearest above and below 1
///    at which the closed loop's stability really changes (checked on its eigenvalues) bound
///    the stable range: gain_margin (upward, the usual one) and gain_reduction_margin
///    (downward, finite when the open loop is unstable, as the roll loop of the Nimble is).
///  - phase margin: at each gain crossover (|L| = 1), 180 deg + arg L, wrapped to
///    (-180, 180]; the smallest in magnitude is reported with its crossover.
///  - delay margin: the smallest extra pure delay tau that brings a gain crossover's phase to
///    -180 deg: (phase margin, made positive modulo 360 deg) / w_c, smallest over crossovers.
///  - sensitivity peak Ms = max |1 / (1 + L)|.
/// Crossovers are found on a logarithmic grid and refined by bisection to 1e-9 relative.

#include <complex>
#include <functional>
#include <limits>
#include <vector>

#include <Eigen/Dense>

namespace nimble {

/// A sampled single loop broken at one point (see the file comment).
struct BrokenLoop {
  Eigen::MatrixXd A;
  Eigen::VectorXd B;
  Eigen::RowVectorXd C;
  double D = 0.0;
  double dt_s = 0.0;  ///< sampling period [s]
};

/// Frequency response of a broken loop, fast: A is reduced once to Hessenberg form, so that
/// each frequency costs one O(n^2) solve.
class LoopResponse {
 public:
  /// @throws std::invalid_argument if the sizes do not agree or dt_s is not positive.
  explicit LoopResponse(const BrokenLoop& loop);
  /// G(z) = C (zI - A)^-1 B + D at z = exp(j omega dt). Infinite where z is an eigenvalue.
  std::complex<double> open(double omega_radps) const;
  /// Return ratio L = -G at `omega_radps` [rad/s].
  std::complex<double> ratio(double omega_radps) const { return -open(omega_radps); }
  /// Nyquist frequency pi / dt [rad/s].
  double nyquist_radps() const { return nyquist_radps_; }

 private:
  Eigen::MatrixXd H_;    // Hessenberg form of A
  Eigen::VectorXd QtB_;  // Q^T B
  Eigen::RowVectorXd CQ_;
  double D_ = 0.0;
  double dt_s_ = 0.0;
  double nyquist_radps_ = 0.0;
};

/// Options of loop_margins().
struct MarginOptions {
  double f_min_hz = 0.01;  ///< lowest frequency of the search grid [Hz]
  int grid_points = 600;   ///< logarithmic grid from f_min_hz to the Nyquist frequency
};

/// The margins of a loop (see the file comment). A margin that does not exist (no crossing)
/// is +infinity (gain, delay), -infinity (gain reduction) or NaN (phase, its crossover);
/// its frequency is NaN.
struct LoopMargins {
  bool closed_loop_stable = false;  ///< every closed-loop eigenvalue inside the unit circle
  bool open_loop_stable = false;    ///< every eigenvalue of A inside the unit circle
  double gain_margin = std::numeric_limits<double>::infinity();  ///< factor [-], > 1
  double gain_margin_hz = std::numeric_limits<double>::quiet_NaN();
  double gain_reduction_margin = 0.0;  ///< factor [-], < 1; 0: the gain may go to zero
  double gain_reduction_margin_hz = std::numeric_limits<double>::quiet_NaN();
  double phase_margin_deg = std::numeric_limits<double>::quiet_NaN();
  double crossover_hz = std::numeric_limits<double>::quiet_NaN();
  double delay_margin_s = std::numeric_limits<double>::infinity();
  double sensitivity_peak = std::numeric_limits<double>::quiet_NaN();  ///< Ms [-]
  double sensitivity_peak_hz = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> crossovers_hz;  ///< every gain crossover found [Hz]
  /// 20 log10 of gain_margin [dB].
  double gain_margin_db() const;
  /// 20 log10 of gain_reduction_margin [dB] (negative; -infinity if it is 0).
  double gain_reduction_margin_db() const;
};

/// A root of `f` in [a, b], where f(a) and f(b) have opposite signs, by bisection to 1e-9
/// relative: the crossings of the margins and the bandwidth.
double bisect_sign_change(const std::function<double(double)>& f, double a, double b);

/// Closed-loop state matrix of `loop` closed with the loop gain scaled by `k` (w = k y).
/// @throws std::invalid_argument if k D = 1 (an algebraic loop without solution).
Eigen::MatrixXd closed_loop_matrix(const BrokenLoop& loop, double k = 1.0);

/// True if every eigenvalue of `phi` lies strictly inside the unit circle.
bool schur_stable(const Eigen::MatrixXd& phi);

/// The margins of `loop`.
/// @throws std::invalid_argument as LoopResponse, or for options out of range.
LoopMargins loop_margins(const BrokenLoop& loop, const MarginOptions& options = {});

/// One closed-loop pole.
struct LoopPole {
  std::complex<double> z;   ///< discrete eigenvalue
  std::complex<double> s;   ///< its continuous equivalent ln(z) / dt [1/s]
  double damping = 1.0;     ///< -Re(s) / |s| [-]
  double natural_hz = 0.0;  ///< |s| / 2 pi [Hz]
};

/// The eigenvalues of `phi` (a closed-loop transition matrix over `dt_s`) as poles, sorted by
/// decreasing real part of s (the slowest first). Eigenvalues with |z| below `origin_tol`
/// (pure delays) are left out and counted in `at_origin`.
std::vector<LoopPole> loop_poles(const Eigen::MatrixXd& phi, double dt_s, int* at_origin = nullptr,
                                 double origin_tol = 1e-9);

}  // namespace nimble
