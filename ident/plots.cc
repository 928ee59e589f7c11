#include "ident/plots.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "core/output_file.h"
#include "plots/gnuplot.h"

namespace nimble::ident {
namespace {

using plots::gp_number;
using plots::gp_quote;
using plots::png_terminal;
using plots::run_gnuplot;

namespace fs = std::filesystem;

/// Measured outputs over time against the model's: `model_label` says what the model's are
/// ("estimated" by the regression, "predicted" by a model under validation). One panel per output.
std::string plot_derivatives(const fs::path& dir, const Eigen::VectorXd& t, const std::vector<OutputFit>& fits,
                             const std::string& title, const std::string& model_label) {
  std::ostringstream data;
  data << "# t_s";
  for (const auto& f : fits) data << " " << f.output << "_measured " << f.output << "_" << model_label;
  data << "\n";
  for (Eigen::Index k = 0; k < t.size(); ++k) {
    data << gp_number(t[k]);
    for (const auto& f : fits) data << " " << gp_number(f.measured[k]) << " " << gp_number(f.estimated[k]);
    data << "\n";
  }
  const fs::path dat = dir / "derivatives.dat";
  write_file(dat, data.str());
  const fs::path png = dir / "derivatives.png";
  const int n = static_cast<int>(fits.size());
  std::ostringstream s;
  s << png_terminal(1400, 320 * n) << "set output " << gp_quote(png.string()) << "\n";
  s << "set multiplot layout " << n << ",1 title " << gp_quote(title) << "\n";
  s << "set grid\nset key top right\nset xlabel 'time [s]'\n";
  for (int i = 0; i < n; ++i) {
    const OutputFit& f = fits[static_cast<std::size_t>(i)];
    char sub[160];
    std::snprintf(sub, sizeof sub, "%s   r_xy %.3f  R^2 %.3f  RMSE %.3g %s (%.2f %% of range)", f.output.c_str(),
                  f.metrics.rxy, f.metrics.r2, f.metrics.rmse, f.unit.c_str(), f.metrics.rmse_pct_range);
    s << "set title " << gp_quote(sub) << " noenhanced\n";
    s << "set ylabel " << gp_quote(f.output + " [" + f.unit + "]") << " noenhanced\n";
    s << "plot " << gp_quote(dat.string()) << " using 1:" << 2 + 2 * i
      << " with lines lw 1.2 lc rgb '#1f77b4' title 'measured', \\\n"
      << "     '' using 1:" << 3 + 2 * i << " with lines lw 1.2 lc rgb '#d62728' title " << gp_quote(model_label)
      << "\n";
  }
  s << "unset multiplot\n";
  run_gnuplot(dir, "derivatives", s.str());
  return png.string();
}

}  // namespace

std::string plot_autocorrelation(const fs::path& dir, const std::vector<OutputFit>& fits, const std::string& title) {
  const fs::path dat = dir / "autocorrelation.dat";
  std::ostringstream data;
  data << "# lag_s rho (one block per output, separated by two blank lines)\n";
  for (const auto& f : fits) {
    data << "# " << f.output << "\n";
    for (Eigen::Index k = 0; k < f.whiteness.rho.size(); ++k) {
      data << gp_number(static_cast<double>(k) * f.whiteness.lag_step_s) << " " << gp_number(f.whiteness.rho[k])
           << "\n";
    }
    data << "\n\n";
  }
  write_file(dat, data.str());
  const fs::path png = dir / "autocorrelation.png";
  const int n = static_cast<int>(fits.size());
  std::ostringstream s;
  s << png_terminal(1000, 300 * n) << "set output " << gp_quote(png.string()) << "\n";
  s << "set multiplot layout " << n << ",1 title " << gp_quote(title) << "\n";
  double max_lag_s = 0.0;
  for (const auto& f : fits)
    max_lag_s = std::max(max_lag_s, static_cast<double>(f.whiteness.lags) * f.whiteness.lag_step_s);
  s << "set grid\nset yrange [-1.05:1.05]\nset xrange [0:" << gp_number(max_lag_s) << "]\n";
  s << "set xlabel 'lag [s]'\nset ylabel 'autocorrelation'\nset key top right\n";
  for (int i = 0; i < n; ++i) {
    const OutputFit& f = fits[static_cast<std::size_t>(i)];
    if (!f.whiteness.tested) {  // a record too short for the lags: the panel says so, in two lines
      const std::string& note = f.whiteness.note;
      const std::size_t cut = note.find(", the record has");
      s << "set title " << gp_quote("residual of " + f.output + ": whiteness not tested") << " noenhanced\n";
      s << "set label 1 " << gp_quote(note.substr(0, cut)) << " at graph 0.5, 0.6 center noenhanced\n";
      if (cut != std::string::npos) {
        s << "set label 2 " << gp_quote(note.substr(cut + 2)) << " at graph 0.5, 0.4 center noenhanced\n";
      }
      s << "plot 0 with lines lc rgb '#bbbbbb' title 'not tested'\nunset label 1\nunset label 2\n";
      continue;
    }
    char sub[200];
    std::snprintf(sub, sizeof sub, "residual of %s: %zu of %zu lags outside +-%.3f (%.0f %%, allowed %.0f %%): %s",
                  f.output.c_str(), f.whiteness.outside, f.whiteness.lags, f.whiteness.bound,
                  100.0 * f.whiteness.fraction_outside, 100.0 * f.whiteness.allowed_fraction,
                  f.whiteness.white ? "white" : "COLOURED");
    s << "set title " << gp_quote(sub) << " noenhanced\n";
    s << "plot " << gp_quote(dat.string()) << " index " << i
      << " using 1:2 with impulses lw 3 lc rgb '#1f77b4' title 'autocorrelation', \\\n"
      << "     " << gp_number(f.whiteness.bound) << " with lines dt 2 lc rgb '#d62728' title '95 % bounds', \\\n"
      << "     " << gp_number(-f.whiteness.bound) << " with lines dt 2 lc rgb '#d62728' notitle\n";
  }
  s << "unset multiplot\n";
  run_gnuplot(dir, "autocorrelation", s.str());
  return png.string();
}

namespace {

std::string plot_psd(const fs::path& dir, const IdentResult& r) {
  const fs::path dat = dir / "psd.dat";
  std::ostringstream data;
  data << "# f_hz psd (blocks: for each state hover then manoeuvre, separated by two blank lines)\n";
  for (const auto& p : r.psd) {
    for (const Psd* psd : {&p.hover, &p.manoeuvre}) {
      const bool have = (psd == &p.hover) ? p.has_hover : p.has_manoeuvre;
      data << "# " << p.state << (psd == &p.hover ? " hover" : " manoeuvre") << "\n";
      if (have) {
        for (Eigen::Index k = 1; k < psd->psd.size(); ++k)
          data << gp_number(psd->f_hz[k]) << " " << gp_number(psd->psd[k]) << "\n";
      } else {
        data << "NaN NaN\n";
      }
      data << "\n\n";
    }
  }
  write_file(dat, data.str());
  const fs::path png = dir / "psd.png";
  const int n = static_cast<int>(r.psd.size());
  const double cutoff = r.options.processing.cutoff_hz;
  const double fmax = std::max(20.0, 3.0 * cutoff);
  std::ostringstream s;
  s << png_terminal(1000, 300 * n) << "set output " << gp_quote(png.string()) << "\n";
  s << "set multiplot layout " << n << ",1 title "
    << gp_quote("state PSDs (Welch, Hann, 50 % overlap; unfiltered), hover vs manoeuvre; segments by " + r.segments.how)
    << "\n";
  s << "set grid\nset logscale y\nset format y '%.0e'\nset xrange [0:" << gp_number(fmax)
    << "]\nset xlabel 'frequency [Hz]'\n";
  if (r.options.processing.filter_order > 0) {
    s << "set arrow 1 from " << gp_number(cutoff) << ", graph 0 to " << gp_number(cutoff)
      << ", graph 1 nohead dt 2 lc rgb '#2ca02c'\n";
    s << "set label 1 'cut-off " << gp_number(cutoff) << " Hz' at " << gp_number(cutoff)
      << ", graph 0.92 offset 0.5,0 tc rgb '#2ca02c'\n";
  }
  for (int i = 0; i < n; ++i) {
    const StatePsd& p = r.psd[static_cast<std::size_t>(i)];
    s << "set title " << gp_quote(p.state) << " noenhanced\n";
    s << "set ylabel " << gp_quote("PSD [(" + p.unit + ")^2/Hz]") << " noenhanced\n";
    s << "plot " << gp_quote(dat.string()) << " index " << 2 * i
      << " using 1:2 with lines lw 1.5 lc rgb '#7f7f7f' title 'hover', \\\n"
      << "     '' index " << 2 * i + 1 << " using 1:2 with lines lw 1.5 lc rgb '#d62728' title 'manoeuvre'\n";
  }
  s << "unset multiplot\n";
  run_gnuplot(dir, "psd", s.str());
  return png.string();
}

std::string plot_eigenvalues(const fs::path& dir, const IdentResult& r) {
  const fs::path dat = dir / "eigenvalues.dat";
  std::ostringstream data;
  data << "# re im [1/s]\n";
  double extent = 1.0;
  for (const auto& z : r.eigenvalues) {
    data << gp_number(z.real()) << " " << gp_number(z.imag()) << "\n";
    extent = std::max({extent, std::fabs(z.real()), std::fabs(z.imag())});
  }
  write_file(dat, data.str());
  const fs::path png = dir / "eigenvalues.png";
  const double lim = 1.2 * extent;
  std::ostringstream s;
  s << png_terminal(700, 600) << "set output " << gp_quote(png.string()) << "\n";
  s << "set title " << gp_quote("eigenvalues of the identified model (" + r.model.name + ")") << " noenhanced\n";
  s << "set grid\nset xlabel 'real [1/s]'\nset ylabel 'imaginary [rad/s]'\n";
  s << "set xrange [" << gp_number(-lim) << ":" << gp_number(lim) << "]\nset yrange [" << gp_number(-lim) << ":"
    << gp_number(lim) << "]\n";
  s << "set size ratio -1\nset xzeroaxis lt -1\nset yzeroaxis lt -1\n";
  // The legend below the axes: a cross inside them would read as one more pole.
  s << "set key outside below center\n";
  s << "plot " << gp_quote(dat.string())
    << " using 1:2 with points pt 2 ps 2.5 lw 2 lc rgb '#d62728' title 'identified eigenvalue'\n";
  run_gnuplot(dir, "eigenvalues", s.str());
  return png.string();
}

}  // namespace

std::vector<std::string> plot_identification(const IdentResult& result, const std::string& dir) {
  const fs::path d = plots::plot_dir(dir);
  const std::string what =
      result.source + ": " + to_string(result.options.structure) + ", " + to_string(result.options.method);
  return {plot_derivatives(d, result.data.filtered.t_s, result.fits, "identification " + what, "estimated"),
          plot_autocorrelation(d, result.fits, "residual autocorrelation, " + what), plot_psd(d, result),
          plot_eigenvalues(d, result)};
}

std::vector<std::string> plot_validation(const ValidationResult& result, const std::string& dir) {
  const fs::path d = plots::plot_dir(dir);
  const std::string what = result.source + " with model " + result.model.name;
  return {plot_derivatives(d, result.data.t_s, result.fits, "open-loop validation " + what, "predicted"),
          plot_autocorrelation(d, result.fits, "residual autocorrelation, " + what)};
}

}  // namespace nimble::ident
