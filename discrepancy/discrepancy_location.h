#pragma once
/// The discrepancy workflow's location of what the model leaves in the residual (defined in
/// discrepancy_locate.cc): the excitation's filter bank, the frame the location tests see an
/// equation through, and the tests themselves. A part of the workflow as discrepancy_parts.h
/// is: discrepancy.cc and discrepancy_terms.cc (the open world's confirmation through the
/// excitation) use it. Not an interface.

#include <string>
#include <vector>

#include "discrepancy/discrepancy_parts.h"

namespace nimble::ident::discrepancy_parts {

// ---------------------------------------------------------------------------------------
// Location.

/// The excitation of the record: its exogenous signals (DiscrepancyOptions::excitation, those the
/// data has and that move) through orthonormal discrete Laguerre filter banks of
/// kExcitationOrder filters at each of kExcitationTimeConstants, plus a constant. The closed
/// loop's linear response to the excitation lies (nearly) in their span, whatever the
/// manoeuvre's shape; the measurement noise and the process noise are independent of it.
inline constexpr double kExcitationTimeConstants[] = {0.05, 0.5};  ///< [s]: the roll loop's and the side drift's
inline constexpr int kExcitationOrder = 8;
struct Excitation {
  std::vector<std::string> signals;  ///< the exogenous signals used (empty: none, no location test)
  MatrixXd Z;                        ///< the bank's columns
};
Excitation excitation_bank(const UniformData& d, const std::vector<std::string>& names);

/// The column span of a matrix, by an orthonormal basis Q: from the eigen-decomposition of its
/// column-scaled Gram matrix, directions below kSpanTolerance of the largest dropped (the
/// Laguerre banks of neighbouring time constants, and a model's intercept against the bank's
/// constant, are nearly collinear; a projection needs only the span).
inline constexpr double kSpanTolerance = 1e-10;
/// The location tests' batch means have at least this many blocks (score_block()).
inline constexpr Index kMinScoreBlocks = 10;
struct Span {
  explicit Span(const MatrixXd& A);
  MatrixXd Q;
  VectorXd project(const VectorXd& c) const { return Q * (Q.transpose() * c); }
  VectorXd residualise(const VectorXd& c) const { return c - project(c); }
  Index rank() const { return Q.cols(); }
};

/// One equation as the location tests see it: y against the span of [X, Z], the baseline
/// design and the excitation's bank. The residual keeps what is neither the model's linear
/// structure nor a linear response to the excitation: under a linear plant that is process and
/// measurement noise, independent of the excitation however biased the baseline fit is by noisy
/// regressors (errors in variables) or by the feedback.
struct LocationFrame {
  LocationFrame(const MatrixXd& X, const VectorXd& y, const MatrixXd& Z);
  VectorXd y;
  MatrixXd excitation_columns;  ///< Z
  Span excitation;              ///< span of Z
  Span model_and_excitation;    ///< span of [X, Z]
  VectorXd residual;            ///< y minus its projection on [X, Z]
};

/// Dependence of the frame's residual on a nonlinear function (z^2 and z^3, z standardised) of
/// each state and input's excitation part (its projection on the bank). Under a linear plant
/// the residual is independent of any function of the excitation, so the test holds its level
/// on closed-loop, non-Gaussian manoeuvres with noisy regressors; a measured signal's own
/// z^2, z^3 would not (noise in a regressor makes its conditional mean nonlinear in the
/// measurement when the manoeuvre is not Gaussian). Wald test with the coloured covariance,
/// Bonferroni over the signals tested, significant at alpha.
/// The thresholds of a location test: its level (the workflow's p_critical), the batch means'
/// shortest block, and the confirmation above the gust band that every candidate passes too.
struct LocationRule {
  double alpha = 0.0;
  Index min_block = 1;
  double gust_band_hz = 2.0, gust_band_alpha = 0.01;
  Folds folds;                  ///< the held-out rule's folds (the workflow's)
  double heldout_sigmas = 1.0;  ///< DiscrepancyOptions::heldout_sigmas
};

/// Wald test that the frame's residual does not depend on the columns C (partialled on the
/// frame's span), batch-means covariance, Hotelling's reference: the p-value; `partial_r` (if
/// given) the square root of the share of the residual's sum of squares they explain.
double frame_wald(const LocationFrame& frame, const MatrixXd& C, Index min_block, double* partial_r);

/// An instrumented (two-stage least squares) test of the columns C beside the design X: the
/// regressors [X, C] replaced by their projections on the instruments' span (`instruments`, the
/// excitation's bank), the coefficients of C tested with the sandwich covariance of the
/// projected regressors' scores (batch means, blocks as score_block). Under the model the
/// equation error is process and measurement noise, independent of the excitation, so the test
/// holds its level however the error correlates with the measured regressors: the closed loop's
/// feedback of the noise into the states, and the derivative's window, which spreads noise the
/// states already answered over the samples around them. Unlike frame_wald the excitation's
/// span is the instruments, not regressors: a linear column (a missing derivative) stays
/// testable. The p-value; `coefficient` and `sigma` (if given) the last column's.
double instrumented_wald(const MatrixXd& X, const VectorXd& y, const MatrixXd& C, const Span& instruments,
                         Index min_block, double* coefficient, double* sigma);

void state_findings(const LocationFrame& frame, const MatrixXd& X, const std::string& output, const UniformData& d,
                    const LocationRule& rule, std::vector<StateFinding>& out);

/// A periodic component of the frame's residual: the frequency in [f_lo, f_hi] where its
/// periodogram is largest, and the Wald test of sin and cos at it (frame_wald), Bonferroni over
/// the band's independent frequencies ((f_hi - f_lo) T). Against a residual whose spectrum
/// is not flat (a lightly damped loop driven by process noise has a resonance) the score's
/// batch means carry the residual's own power at that frequency, so a resonance is not a line;
/// a periodic force is. Reported (ratio: periodogram / local median, for the reader) at alpha.
void frequency_peaks(const LocationFrame& frame, const std::string& output, double scale, double rate, double f_lo,
                     double f_hi, const LocationRule& rule, std::vector<FrequencyFinding>& out);

void time_findings(const std::string& output, const VectorXd& r, const UniformData& d, const Segments& seg,
                   double window_s, std::vector<TimeFinding>& out);

}  // namespace nimble::ident::discrepancy_parts
