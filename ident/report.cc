#include "ident/report.h"
#include "ident/report_numbers.h"

#include <cmath>
#include <cstdarg>
#include <cstdio>

namespace nimble::ident {
namespace {

/// printf into a std::string.
std::string fmt(const char* format, ...) __attribute__((format(printf, 1, 2)));
std::string fmt(const char* format, ...) {
  char buf[512];
  va_list args;
  va_start(args, format);
  std::vsnprintf(buf, sizeof buf, format, args);
  va_end(args);
  return buf;
}

std::string complex_text(const std::complex<double>& z) {
  if (std::fabs(z.imag()) < 1e-12) return fmt("%.4f", z.real());
  return fmt("%.4f %c %.4fi", z.real(), z.imag() < 0 ? '-' : '+', std::fabs(z.imag()));
}

std::string metrics_text(const std::vector<OutputFit>& fits) {
  std::string out =
      fmt("  %-12s %8s %8s %12s %-8s %10s %10s\n", "output", "r_xy", "R2", "RMSE", "unit", "range", "RMSE[%rng]");
  for (const auto& f : fits) {
    out += fmt("  %-12s %8.4f %8.4f %12.4g %-8s %10.4g %10.2f\n", f.output.c_str(), f.metrics.rxy, f.metrics.r2,
               f.metrics.rmse, f.unit.c_str(), f.metrics.range, f.metrics.rmse_pct_range);
  }
  return out;
}

std::string whiteness_text(const std::vector<OutputFit>& fits) {
  std::string out;
  // A record too short for the lags: the test was skipped (one note; every output has the same length).
  if (!fits.empty() && !fits.front().whiteness.tested) return "  " + fits.front().whiteness.note + "\n";
  if (!fits.empty()) {
    const Whiteness& w = fits.front().whiteness;
    out +=
        fmt("  (residual decimated to lags of %zu samples = %.4f s; %zu lags; 95 %% bounds +-1.96/sqrt(N);"
            " white if at most %.0f %% of the lags lie outside)\n",
            w.lag_step, w.lag_step_s, w.lags, 100.0 * w.allowed_fraction);
  }
  out += fmt("  %-12s %8s %8s %10s  %s\n", "output", "bound", "outside", "fraction", "verdict");
  for (const auto& f : fits) {
    const Whiteness& w = f.whiteness;
    out += fmt("  %-12s %8.4f %8zu %9.1f%%  %s\n", f.output.c_str(), w.bound, w.outside, 100.0 * w.fraction_outside,
               w.white ? "white" : "COLOURED");
  }
  return out;
}

/// Each equation's parameter correlation matrix as the thesis prints it (Appendix H): |rho| in the
/// upper triangle, the lower left blank.
std::string correlation_matrices_text(const IdentResult& r) {
  std::string out = "\nparameter correlation matrices (|rho|, per equation; thesis Appendix H)\n";
  for (const auto& eq : r.regression.equations) {
    const auto& names = eq.equation.parameters;
    out += fmt("  %s\n  %-12s", eq.equation.name.c_str(), "");
    for (const auto& n : names) out += fmt(" %10s", n.c_str());
    out += "\n";
    for (Eigen::Index i = 0; i < eq.correlation.rows(); ++i) {
      out += fmt("  %-12s", names[static_cast<std::size_t>(i)].c_str());
      for (Eigen::Index k = 0; k < eq.correlation.cols(); ++k) {
        out += k < i ? fmt(" %10s", "-") : fmt(" %10.4f", std::fabs(eq.correlation(i, k)));
      }
      out += "\n";
    }
  }
  return out;
}

}  // namespace

std::string identification_text(const IdentResult& r) {
  const IdentOptions& o = r.options;
  const UniformData& d = r.data.filtered;
  std::string out;
  out += fmt("identify   %s\n", r.source.c_str());
  out += fmt("data       %ld samples at %.6g Hz (%.3f s)\n", static_cast<long>(d.size()), d.rate_hz,
             d.size() > 0 ? d.t_s[d.size() - 1] - d.t_s[0] : 0.0);
  const std::string interpolation = to_string(o.processing.interpolation);
  if (o.processing.filter_order > 0) {
    out +=
        fmt("processing %s resampling; zero-phase Butterworth low-pass, order %d, cut-off %.4g Hz;"
            " 4th-order central differences\n",
            interpolation.c_str(), o.processing.filter_order, o.processing.cutoff_hz);
  } else {
    out += fmt("processing %s resampling, no low-pass; 4th-order central differences\n", interpolation.c_str());
  }
  std::string inputs;
  for (const auto& in : r.inputs) inputs += (inputs.empty() ? "" : ", ") + in;
  for (const auto& note : r.inputs_left_out) out += "note       " + note + "\n";
  out += fmt("model      %s, inputs %s, %s\n", to_string(o.structure).c_str(), inputs.c_str(),
             o.method == Method::kOls ? "ordinary least squares"
             : o.method == Method::kWls
                 ? fmt("weighted least squares (residual covariance over %.3g s%s)", o.wls_window_s,
                       o.wls_cross_equation ? ", across equations" : "")
                       .c_str()
                 : fmt("output error (the states simulated from the recorded inputs in segments of %.3g s, "
                       "from the weighted least squares' values)",
                       o.output_error.segment_s)
                       .c_str());
  out +=
      fmt("vehicle    %s (%s): m = %.2f g, Ixx %.3g, Izz %.3g, Ixz %.3g kg m^2\n", r.vehicle.name.c_str(),
          r.vehicle.file.c_str(), 1e3 * r.vehicle.mass_kg, r.vehicle.Ixx_kgm2, r.vehicle.Izz_kgm2, r.vehicle.Ixz_kgm2);
  out += fmt("trim       u0 %.4g m/s, w0 %.4g m/s, theta0 %.4g rad, phi0 %.4g rad\n\n", r.model.trim.u0_mps,
             r.model.trim.w0_mps, r.model.trim.theta0_rad, r.model.trim.phi0_rad);

  out += is_blackbox(r.model.structure)
             ? "parameters (entries of A and B: a_<row>_<column>, b_<row>_<input>, in the state space's units)\n"
             : "parameters (dimensional: L, N in N m, Y in N per unit of the regressor)\n";
  out += "  sigma: residuals taken as white (thesis formula); sigma_c: allowing coloured residuals (Newey-West)\n";
  out += fmt("  %-12s %13s %12s %10s %12s %10s\n", "name", "value", "sigma", "100s/|v|", "sigma_c", "100s_c/|v|");
  for (const auto& name : r.parameter_order) {
    const ParameterEstimate& e = r.parameters.at(name);
    out += fmt("  %-12s %13.4e %12.3e %10.3g %12.3e %10.3g\n", name.c_str(), e.value, e.sigma, pct(e.sigma, e.value),
               e.sigma_coloured, pct(e.sigma_coloured, e.value));
  }
  out += fmt("\ncorrelated parameters (|rho| > %.2g, within an equation)\n", o.correlation_threshold);
  if (r.correlated.empty()) out += "  none\n";
  for (const auto& c : r.correlated) {
    out += fmt("  %s: %s and %s, rho = %.3f\n", c.equation.c_str(), c.a.c_str(), c.b.c_str(), c.rho);
  }
  out += correlation_matrices_text(r);
  out += "\naccuracy (measured vs estimated state derivatives)\n" + metrics_text(r.fits);
  out += "\nresidual whiteness\n" + whiteness_text(r.fits);

  out += "\neigenvalues of the identified model [1/s]\n";
  for (const auto& z : r.eigenvalues) out += "  " + complex_text(z) + "\n";
  out += "\nmodes\n";
  out += fmt("  %-3s %-22s %-12s %-9s %10s %7s\n", "#", "eigenvalue", "type", "stability", "wn[rad/s]", "zeta");
  for (std::size_t k = 0; k < r.modes.size(); ++k) {
    const Mode& m = r.modes[k];
    out += fmt("  %-3zu %-22s %-12s %-9s %10.3f %7.3f\n", k + 1, complex_text(m.eigenvalue).c_str(),
               m.oscillatory ? "oscillatory" : "aperiodic", m.stable ? "stable" : "UNSTABLE", m.natural_frequency_radps,
               m.damping_ratio);
  }
  out += "non-dimensional eigenvectors (normalised on the roll angle)\n";
  out += fmt("  %-8s", "state");
  for (std::size_t k = 0; k < r.modes.size(); ++k) out += fmt(" %20s", ("mode " + std::to_string(k + 1)).c_str());
  out += "\n";
  for (std::size_t i = 0; i < r.state_space.states.size(); ++i) {
    out += fmt("  %-8s", (r.state_space.states[i] + "+").c_str());
    for (const auto& m : r.modes) {
      const auto c = m.eigenvector_nondim[static_cast<Eigen::Index>(i)];
      out += fmt(" %20s", fmt("%.3f (%.1f deg)", std::abs(c), phase_deg(c)).c_str());
    }
    out += "\n";
  }

  out += fmt("\nstate PSDs (Welch, unfiltered): hover vs manoeuvre, segments by %s\n", r.segments.how.c_str());
  out +=
      fmt("  hover %zu segment(s), manoeuvre %zu segment(s)\n", r.segments.hover.size(), r.segments.manoeuvre.size());
  const double fc = o.processing.cutoff_hz;
  out += fmt("  %-8s %-10s %18s %18s %12s\n", "state", "unit", "hover var<=fc", "manoeuvre var<=fc", "ratio");
  for (const auto& p : r.psd) {
    const double h = p.has_hover ? p.hover.integral_up_to(fc) : NAN;
    const double m = p.has_manoeuvre ? p.manoeuvre.integral_up_to(fc) : NAN;
    out += fmt("  %-8s %-10s %18.4g %18.4g %12.3g\n", p.state.c_str(), ("(" + p.unit + ")^2").c_str(), h, m, m / h);
  }
  for (const auto& note : r.notes) {
    if (note.find(" PSD skipped") != std::string::npos) out += "  " + note + "\n";
  }
  return out;
}

std::string methods_comparison_text(const IdentResult& ols, const IdentResult& wls) {
  require_comparable(ols, wls);
  std::string out = "OLS beside WLS (thesis Appendix D; sigma by the white-residual formula)\n";
  out += fmt("  %-12s %12s %10s %12s   %12s %10s %12s\n", "name", "OLS", "|sigma|", "100|s/v|", "WLS", "|sigma|",
             "100|s/v|");
  for (const auto& name : ols.parameter_order) {
    const ParameterEstimate& a = ols.parameters.at(name);
    const ParameterEstimate& b = wls.parameters.at(name);
    out += fmt("  %-12s %12.4e %10.3e %12.3g   %12.4e %10.3e %12.3g\n", name.c_str(), a.value, std::fabs(a.sigma),
               pct(std::fabs(a.sigma), a.value), b.value, std::fabs(b.sigma), pct(std::fabs(b.sigma), b.value));
  }
  return out;
}

std::string validation_text(const ValidationResult& r) {
  std::string out;
  out += fmt("validate   %s (open loop: state derivatives from the measured states and inputs)\n", r.source.c_str());
  out +=
      fmt("model      %s (%s), %s\n", r.model.name.c_str(), r.model.file.c_str(), to_string(r.model.structure).c_str());
  out += fmt("vehicle    %s\n", r.vehicle.name.c_str());
  out += fmt("data       %ld samples at %.6g Hz\n\n", static_cast<long>(r.data.size()), r.data.rate_hz);
  out += "accuracy (measured vs predicted state derivatives; R2 with P = 1)\n" + metrics_text(r.fits);
  out += "\nresidual whiteness\n" + whiteness_text(r.fits);
  return out;
}

}  // namespace nimble::ident
