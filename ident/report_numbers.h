#pragma once
/// Numbers the identification's text and JSON reports (report.cc, report_json.cc) both derive;
/// internal to ident/.

#include <cmath>
#include <complex>

namespace nimble::ident {

/// sigma as a percentage of |value|; infinite for a value of 0 (JSON: null).
inline double pct(double sigma, double value) { return value != 0.0 ? 100.0 * sigma / std::fabs(value) : INFINITY; }

/// The phase of `z` in (-180, 180] degrees.
inline double phase_deg(const std::complex<double>& z) {
  const double deg = std::arg(z) * 180.0 / M_PI;
  return deg <= -180.0 + 1e-6 ? deg + 360.0 : deg;
}

}  // namespace nimble::ident
