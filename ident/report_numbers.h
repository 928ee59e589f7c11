#pragma once
/// Numbers the identification's text and JSON reports (report.cc, report_json.cc) both derive;
/// internal to ident/.

#include <cmath>
#include <complex>
#include <stdexcept>

#include "ident/identify.h"

namespace nimble::ident {

/// sigma as a percentage of |value|; infinite for a value of 0 (JSON: null).
inline double pct(double sigma, double value) { return value != 0.0 ? 100.0 * sigma / std::fabs(value) : INFINITY; }

/// Checks that `ols` and `wls` are an OLS and a WLS identification of the same parameters
/// (methods_comparison_text(), methods_comparison_json()). @throws std::invalid_argument.
inline void require_comparable(const IdentResult& ols, const IdentResult& wls) {
  if (ols.options.method != Method::kOls || wls.options.method != Method::kWls ||
      ols.parameter_order != wls.parameter_order) {
    throw std::invalid_argument("OLS beside WLS: needs an OLS and a WLS identification of the same parameters");
  }
}

/// The phase of `z` in (-180, 180] degrees.
inline double phase_deg(const std::complex<double>& z) {
  const double deg = std::arg(z) * 180.0 / M_PI;
  return deg <= -180.0 + 1e-6 ? deg + 360.0 : deg;
}

}  // namespace nimble::ident
