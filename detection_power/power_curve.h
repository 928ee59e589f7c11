#pragma once
/// The statistics of a power curve: a proportion with its Wilson score interval, and where a
/// curve of proportions crosses a target.
///
/// crossing(): the estimates along x are first made non-decreasing (pool-adjacent-violators,
/// weighted by their counts: the probability of naming an effect does not fall as the record
/// grows or the effect does); then between the two values of x that bracket the target, the
/// probit of the probability, Phi^-1(P), is interpolated linearly in sqrt(x) for a record length
/// and in |x| for a size. The reason: the workflow's Wald statistic grows with the information
/// in the record, in proportion to its length, and its root with the effect's size, so its
/// normal approximation gives P = Phi(c sqrt(L) - z) and P = Phi(c' |size| - z), straight lines
/// in those coordinates. An estimate of 0 or 1 is taken as 0.5 / n from its end. With three or
/// more estimates strictly between 0 and 1 (the refined cells of a steep transition), the line
/// is instead the weighted least-squares fit of their probits (weights the inverse of each
/// probit's binomial variance, n phi(z)^2 / (p (1 - p)); Berkson's minimum chi-square), its
/// crossing kept within the bracket: the end of a bracket above the target is the cell whose
/// estimate reached it, biased upward by that choice, and the fit pools it with its neighbours.
/// Below the first x or beyond the last the answer says so instead of extrapolating.

#include <string>
#include <vector>

#include "core/proportion.h"

namespace nimble::detection_power {

using nimble::Proportion;  // a count with its Wilson score interval (core/proportion.h)
using nimble::wilson;

/// The standard normal quantile Phi^-1(q), q in (0, 1).
double normal_quantile(double q);

/// Where a curve reaches a target.
struct Crossing {
  bool reached = false;           ///< the target lies at or below the last x
  bool bracketed = false;         ///< and above the first: lo_x < value <= hi_x
  double value = 0.0;             ///< the x that reaches it; NaN if not reached
  double lo_x = 0.0, hi_x = 0.0;  ///< the bracket (bracketed only)
  std::string note;  ///< "interpolated between 12 and 24", "at or below 6, ...", "not reached by 48 (there 85 %)"
};

/// The target crossing of `p` along `x` (increasing in |x|), as above: probit against sqrt|x|
/// (sqrt_x) or |x|; the sign of x is kept.
Crossing crossing(const std::vector<double>& x, const std::vector<Proportion>& p, double target, bool sqrt_x);

}  // namespace nimble::detection_power
