/// `rig turbulence`: the Ce500 practical (aircraft responses to atmospheric turbulence)
/// reproduced from its configuration: eigenvalues beside Table 2.1, an exactly discretised
/// seeded simulation, PSDs three ways and variances five ways with their uncertainties, and
/// Table 5.1 beside ours with a reason for each disagreement (turbulence/ce500_analysis.h).

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "cmdline/args.h"
#include "cli/commands.h"
#include "cli/report_files.h"
#include "core/json_line.h"
#include "ident/plots.h"
#include "turbulence/ce500_analysis.h"
#include "turbulence/ce500_config.h"
#include "turbulence/ce500_model.h"
#include "plots/gnuplot.h"

namespace nimble::cli {
namespace {

namespace fs = std::filesystem;
using namespace nimble::turbulence;

constexpr const char* kDescription =
    "The Ce500 lateral model in Dryden turbulence (AE4304 practical), built from the derivatives\n"
    "in the file: eigenvalues of the uncontrolled, roll-damped and reduced systems beside the\n"
    "practical's Table 2.1; a seeded simulation with white-noise gust inputs, exactly\n"
    "discretised; output PSDs (analytical, periodogram, Welch); variances (Lyapunov, analytical\n"
    "PSD integral, periodogram, Welch, sample) with uncertainties; the practical's Table 5.1\n"
    "beside ours with the reason for each difference.";

std::string complex_text(const std::complex<double>& z) {
  if (z.imag() == 0.0) return fmt("%+.4f", z.real());
  return fmt("%+.4f", z.real()) + " " + fmt("%+.4f", z.imag()) + "i";
}

const char* output_unit(const std::string& name) {
  if (name == "beta" || name == "phi") return "deg^2";
  if (name == "a_y") return "(m/s^2)^2";
  return "-";
}

std::string pad(const std::string& s, std::size_t width) {
  return s.size() >= width ? s + " " : s + std::string(width - s.size(), ' ');
}

/// value +- sigma in a fixed width.
std::string with_sigma(const VarianceEstimate& v) {
  return pad(fmt("%.4g", v.value) + " +- " + fmt("%.2g", v.sigma), 22);
}

std::string report_text(const Ce500Analysis& a) {
  std::ostringstream out;
  const auto& names = ce500_output_names();
  const SystemAnalysis& c0 = a.controlled;
  const std::size_t N = static_cast<std::size_t>(a.t_s.size());
  out << "rig turbulence: " << a.config.file << "\n";
  out << "Cessna Ce500 lateral model, Dryden turbulence: L_g " << a.config.turbulence.Lg_m << " m, sigma v_g "
      << a.config.turbulence.sigma_vg_mps << " m/s, w_g " << a.config.turbulence.sigma_wg_mps << " m/s, u_g "
      << (a.config.excitation.u_g ? "on" : "off") << "; V " << a.config.flight.V_mps << " m/s\n";
  out << "PSD convention: S(omega) two-sided in unit^2/(rad/s), sigma^2 = (1/pi) int_0^inf S d omega; white-noise\n"
         "intensity W = 1 means S_ww = 1 (turbulence/spectral_density.h)\n\n";

  out << "Eigenvalues [1/s] beside the practical's Table 2.1 (tolerance " << a.config.published.eigenvalue_tolerance
      << " per eigenvalue)\n";
  for (const auto& col : a.table_2_1) {
    const bool ok = col.max_distance <= a.config.published.eigenvalue_tolerance;
    out << "  " << col.key << (col.key == "reduced" ? " (with the roll damper)" : "")
        << (col.key == "controlled" ? " (roll damper delta_a = -K x, K_phi " + fmt("%g", a.config.K_phi) + ", K_p " +
                                          fmt("%g", a.config.K_p) + ")"
                                    : "")
        << ": max |ours - published| " << fmt("%.1e", col.max_distance) << (ok ? "  ok" : "  FAILED") << "\n";
    out << "    " << pad("ours", 20) << pad("Table 2.1", 20) << pad("|diff|", 10) << "mode\n";
    for (const auto& r : col.rows) {
      out << "    " << pad(complex_text(r.ours.value), 20) << pad(complex_text(r.published), 20)
          << pad(fmt("%.1e", r.distance), 10) << r.ours.mode << "\n";
    }
  }
  out << "  reduced without the roll damper (not in Table 2.1):";
  for (const auto& e : a.reduced_uncontrolled_eigenvalues) {
    if (e.mode.find("gust") == std::string::npos) out << "  " << complex_text(e.value) << " " << e.mode << ";";
  }
  out << "\n";
  const Ce500Coefficients k = ce500_coefficients(a.config);
  out << "  gust filter inputs (B): b_ug1 " << fmt("%.4f", k.u_g.b1) << ", b_ug2 " << fmt("%.4f", k.u_g.b2)
      << ", b_ag1 " << fmt("%.4f", k.alpha_g.b1) << ", b_ag2 " << fmt("%.4f", k.alpha_g.b2) << ", b_bg1 "
      << fmt("%.4f", k.beta_g.b1) << ", b_bg2 " << fmt("%.4f", k.beta_g.b2)
      << "\n  (the practical's Eq 2.7 prints -0.0996 for the beta_g entry: a misprint of b_ag2/b_bg2)\n\n";

  const SpectralEstimate& w = c0.welches.front();
  out << "Simulation: v_g and w_g white noise (intensity " << a.config.excitation.intensity << "), u_g "
      << (a.config.excitation.u_g ? "on" : "off") << "; dt " << a.options.dt_s << " s, " << a.options.duration_s
      << " s (" << N << " samples), seed " << a.options.seed
      << "; exact discretisation (ZOH, Van Loan process noise), stationary start;\n"
         "both systems driven by the same gust record. Outputs beta [deg], phi [deg], pb/2V, rb/2V [-],\n"
         "a_y = V (beta_dot + r) [m/s^2].\n";
  out << "PSD estimates: periodogram (rectangular, zero-padded to " << c0.periodograms.front().segment_length
      << "), Welch (Hann, " << w.segment_length << "-sample segments, 50 % overlap, " << w.segments << " segments, "
      << fmt("%.1f", w.dof) << " degrees of freedom per bin); common grid: the " << w.omega_radps.size()
      << " Welch bins, d omega " << fmt("%.4f", w.d_omega_radps) << " rad/s.\n\n";

  const auto bands = ce500_bands(a.options.dt_s);
  for (const SystemAnalysis* s : {&a.controlled, &a.reduced}) {
    out << "PSD estimate / analytical, mean over each band (" << s->key << "): periodogram | Welch | sampled-process\n";
    out << "    " << pad("output", 8);
    for (const auto& b : bands) out << pad(fmt("%g", b.first) + "-" + fmt("%.3g", b.second) + " rad/s", 25);
    out << "\n";
    for (std::size_t i = 0; i < names.size(); ++i) {
      out << "    " << pad(names[i], 8);
      for (const auto& r : s->band_ratios[i]) {
        const auto ratio = [](double x) { return std::isnan(x) ? std::string("-") : fmt("%.2f", x); };
        out << pad(ratio(r.periodogram) + " | " + ratio(r.welch) + " | " + ratio(r.sampled), 25);
      }
      out << "\n";
    }
  }
  out << "  (sampled-process / analytical > 1 near Nyquist is aliasing: what a record at dt can see. The periodogram\n"
         "  far above the analytical PSD at high frequency is leakage of its rectangular window, which the Hann "
         "window\n"
         "  of Welch removes: the practical's 'fft error at high frequencies'. '-': no bin in the band.)\n\n";

  for (const SystemAnalysis* s : {&a.controlled, &a.reduced}) {
    out << "Variances (" << s->key
        << "), value +- one sigma: Lyapunov is exact; the analytical-PSD sigma is the\n"
           "quadrature error; the others are the statistical spread for this record (turbulence/uncertainty.h)\n";
    out << "    " << pad("output", 8) << pad("unit", 10) << pad("lyapunov", 12) << pad("analytical_psd", 22)
        << pad("periodogram", 22) << pad("welch", 22) << pad("sample", 22) << "sigma(sample) from PSD\n";
    for (std::size_t i = 0; i < names.size(); ++i) {
      const OutputVariances& v = s->variances[i];
      out << "    " << pad(names[i], 8) << pad(output_unit(names[i]), 10) << pad(fmt("%.4g", v.lyapunov.value), 12)
          << with_sigma(v.analytical_psd) << with_sigma(v.periodogram) << with_sigma(v.welch) << with_sigma(v.sample)
          << fmt("%.2g", v.sample_sigma_from_psd) << "\n";
    }
  }
  out << "\n";

  out << "The practical's Table 5.1 beside ours (C controlled, R reduced; ours: Lyapunov | periodogram | Welch | "
         "sample)\n";
  out << "    " << pad("output", 8) << pad("sys", 4) << pad("published: analytical", 24) << pad("fft", 10)
      << pad("pwelch", 10) << pad("var", 10) << "| ours: " << pad("lyapunov", 11) << pad("periodogram", 12)
      << pad("welch", 11) << "sample\n";
  for (std::size_t i = 0; i < names.size(); ++i) {
    for (int sidx = 0; sidx < 2; ++sidx) {
      const SystemAnalysis& s = sidx == 0 ? a.controlled : a.reduced;
      const auto& row = a.config.published.table_5_1.at(names[i]);
      const OutputVariances& v = s.variances[i];
      out << "    " << pad(names[i], 8) << pad(sidx == 0 ? "C" : "R", 4) << pad(fmt("%.4f", row.analytical[sidx]), 24)
          << pad(fmt("%.4f", row.fft[sidx]), 10) << pad(fmt("%.4f", row.pwelch[sidx]), 10)
          << pad(fmt("%.4f", row.var[sidx]), 10) << "|       " << pad(fmt("%.4g", v.lyapunov.value), 11)
          << pad(fmt("%.4g", v.periodogram.value), 12) << pad(fmt("%.4g", v.welch.value), 11)
          << fmt("%.4g", v.sample.value) << "\n";
    }
  }
  out << "  Reasons (each published value against the causes that could produce it; explained = within 10 %,\n"
         "  var.m: within 2 sigma of the sampling spread):\n";
  int explained = 0;
  for (const auto& c : a.table_5_1) {
    explained += c.explained ? 1 : 0;
    out << "    " << pad(c.output + " " + (c.system == "controlled" ? "C" : "R") + " " + c.method, 18)
        << (c.explained ? "explained: " : "open:      ") << c.reason << "\n";
  }
  out << "  " << explained << " of " << a.table_5_1.size() << " published values explained.\n";
  out << "  Exact reference: the Lyapunov column. Periodogram and sample variance agree by construction (Parseval);\n"
         "  the practical's fft is twice its var.m, the one-sided factor 2 counted twice.\n";
  return out.str();
}

/// The variances (or their standard errors, `sigma`) of both systems by output and method.
OrderedJson variances_json(const Ce500Analysis& a, bool sigma) {
  const auto& names = ce500_output_names();
  const auto pick = [sigma](const VarianceEstimate& e) { return sigma ? e.sigma : e.value; };
  OrderedJson j;
  for (const SystemAnalysis* s : {&a.controlled, &a.reduced}) {
    OrderedJson& system = j[s->key];
    for (std::size_t i = 0; i < names.size(); ++i) {
      const OutputVariances& v = s->variances[i];
      system[names[i]] = {{"lyapunov", pick(v.lyapunov)},
                          {"analytical_psd", pick(v.analytical_psd)},
                          {"periodogram", pick(v.periodogram)},
                          {"welch", pick(v.welch)},
                          {"sample", pick(v.sample)}};
    }
  }
  return j;
}

std::vector<double> column(const Eigen::MatrixXd& M, Eigen::Index c) {
  std::vector<double> v(static_cast<std::size_t>(M.rows()));
  for (Eigen::Index k = 0; k < M.rows(); ++k) v[static_cast<std::size_t>(k)] = M(k, c);
  return v;
}

std::string report_json(const Ce500Analysis& a) {
  const auto& names = ce500_output_names();
  OrderedJson j;
  j["config"] = a.config.file;
  const SpectralEstimate& welch = a.controlled.welches.front();
  j["options"] = {
      {"dt_s", a.options.dt_s},  {"duration_s", a.options.duration_s},    {"samples", a.t_s.size()},
      {"seed", a.options.seed},  {"welch_segment", welch.segment_length}, {"welch_segments", welch.segments},
      {"welch_dof", a.welch_dof}};
  OrderedJson& units = j["units"];
  for (const auto& n : names) units[n] = output_unit(n);
  units["psd"] = "output unit^2/(rad/s), two-sided, sigma^2 = (1/pi) int_0^inf S d omega";

  OrderedJson& systems = j["systems"];
  const std::vector<NamedEigenvalue>* eig[3] = {&a.uncontrolled_eigenvalues, &a.controlled.eigenvalues,
                                                &a.reduced.eigenvalues};
  for (int i = 0; i < 3; ++i) {
    const EigenvalueColumn& col = a.table_2_1[static_cast<std::size_t>(i)];
    OrderedJson& system = systems[col.key];
    OrderedJson values = OrderedJson::array(), modes = OrderedJson::array();
    for (const auto& e : *eig[i]) {
      values.push_back(complex_json(e.value));
      modes.push_back(e.mode);
    }
    system["eigenvalues"] = std::move(values);
    system["modes"] = std::move(modes);
    OrderedJson& rows = system["table_2_1"] = OrderedJson::array();
    for (const auto& r : col.rows) {
      rows.push_back({{"ours", complex_json(r.ours.value)},
                      {"published", complex_json(r.published)},
                      {"distance", r.distance},
                      {"mode", r.ours.mode}});
    }
    system["max_distance"] = col.max_distance;
    system["within_tolerance"] = col.max_distance <= a.config.published.eigenvalue_tolerance;
  }

  j["variances"] = variances_json(a, false);
  j["variance_sigmas"] = variances_json(a, true);
  OrderedJson& diagnostics = j["variance_diagnostics"];
  for (const SystemAnalysis* s : {&a.controlled, &a.reduced}) {
    OrderedJson& system = diagnostics[s->key];
    for (std::size_t i = 0; i < names.size(); ++i) {
      const OutputVariances& v = s->variances[i];
      system[names[i]] = {{"analytical_psd_to_nyquist", v.analytical_psd_to_nyquist},
                          {"sample_sigma_from_psd", v.sample_sigma_from_psd},
                          {"coherent_sum", v.coherent_sum},
                          {"held_noise", v.held_noise}};
    }
  }

  OrderedJson& psd = j["psd"];
  psd["omega_radps"] = std::vector<double>(a.controlled.omega_radps.data(),
                                           a.controlled.omega_radps.data() + a.controlled.omega_radps.size());
  for (const SystemAnalysis* s : {&a.controlled, &a.reduced}) {
    OrderedJson& system = psd[s->key];
    for (std::size_t i = 0; i < names.size(); ++i) {
      const Eigen::Index c = static_cast<Eigen::Index>(i);
      system[names[i]] = {{"analytical", column(s->psd_analytical, c)},
                          {"periodogram", column(s->psd_periodogram, c)},
                          {"welch", column(s->psd_welch, c)},
                          {"sampled", column(s->psd_sampled, c)}};
    }
  }

  OrderedJson& table = j["table_5_1"] = OrderedJson::array();
  for (const auto& c : a.table_5_1) {
    table.push_back({{"output", c.output},
                     {"system", c.system},
                     {"method", c.method},
                     {"published", c.published},
                     {"ours", c.ours},
                     {"explanation", c.explanation_name},
                     {"predicted", c.explanation_value},
                     {"explained", c.explained},
                     {"reason", c.reason}});
  }
  return json_line(j);
}

// --- plots -------------------------------------------------------------------------------

/// The 5 x 3 PSD matrix: rows outputs, columns analytical / periodogram / Welch, both systems per panel.
std::string plot_psd_matrix(const fs::path& dir, const Ce500Analysis& a) {
  const auto& names = ce500_output_names();
  std::ostringstream data;
  data
      << "# omega_radps, then per output: C analytical, R analytical, C periodogram, R periodogram, C welch, R welch\n";
  const SystemAnalysis& c = a.controlled;
  const SystemAnalysis& r = a.reduced;
  for (Eigen::Index k = 1; k < c.omega_radps.size(); ++k) {
    data << fmt("%.9g", c.omega_radps[k]);
    for (Eigen::Index i = 0; i < static_cast<Eigen::Index>(names.size()); ++i) {
      for (const Eigen::MatrixXd* m :
           {&c.psd_analytical, &r.psd_analytical, &c.psd_periodogram, &r.psd_periodogram, &c.psd_welch, &r.psd_welch}) {
        const Eigen::MatrixXd& M = *m;
        data << " " << fmt("%.9g", M(k, i));
      }
    }
    data << "\n";
  }
  const fs::path dat = dir / "psd_matrix.dat";
  write_file(dat, data.str());
  const fs::path png = dir / "psd_matrix.png";
  const char* units[] = {"deg^2/(rad/s)", "deg^2/(rad/s)", "1/(rad/s)", "1/(rad/s)", "(m/s^2)^2/(rad/s)"};
  const char* methods[] = {"analytical", "periodogram", "Welch"};
  std::ostringstream s;
  s << "set terminal pngcairo size 1500,1700 font 'sans,9'\nset termoption noenhanced\n";
  s << "set output " << gp_quote(png.string()) << "\n";
  s << "set multiplot layout 5,3 title " << gp_quote("Ce500 output PSDs, controlled (blue) and reduced (red)") << "\n";
  s << "set logscale xy\nset grid\nset format y '%.0e'\nset key bottom left\n";
  for (std::size_t i = 0; i < names.size(); ++i) {
    for (int m = 0; m < 3; ++m) {
      const int col = 2 + static_cast<int>(i) * 6 + 2 * m;
      s << "set title " << gp_quote(names[i] + ", " + methods[m]) << "\n";
      s << "set xlabel 'omega [rad/s]'\nset ylabel " << gp_quote(units[i]) << "\n";
      s << "plot " << gp_quote(dat.string()) << " using 1:" << col
        << " with lines lc rgb '#1f77b4' title 'C', '' using 1:" << col + 1
        << " with lines lc rgb '#d62728' title 'R'\n";
    }
  }
  s << "unset multiplot\n";
  run_gnuplot(dir, "psd_matrix", s.str());
  return png.string();
}

/// Poles of the three systems in the complex plane.
std::string plot_pole_map(const fs::path& dir, const Ce500Analysis& a) {
  std::ostringstream data;
  const std::vector<NamedEigenvalue>* eig[3] = {&a.uncontrolled_eigenvalues, &a.controlled.eigenvalues,
                                                &a.reduced.eigenvalues};
  for (int i = 0; i < 3; ++i) {
    data << "# " << a.table_2_1[static_cast<std::size_t>(i)].key << "\n";
    for (const auto& e : *eig[i]) data << fmt("%.9g", e.value.real()) << " " << fmt("%.9g", e.value.imag()) << "\n";
    data << "\n\n";
  }
  const fs::path dat = dir / "pole_map.dat";
  write_file(dat, data.str());
  const fs::path png = dir / "pole_map.png";
  std::ostringstream s;
  s << "set terminal pngcairo size 1000,700 font 'sans,10'\nset termoption noenhanced\n";
  s << "set output " << gp_quote(png.string()) << "\n";
  s << "set title 'Ce500 poles: uncontrolled, roll-damped, reduced (gust poles on the real axis)'\n";
  s << "set xlabel 'real [1/s]'\nset ylabel 'imaginary [rad/s]'\nset grid\nset xzeroaxis\nset yzeroaxis\n";
  // The legend below the axes: its markers inside them would read as poles.
  s << "set key outside below center horizontal\n";
  s << "plot " << gp_quote(dat.string())
    << " index 0 using 1:2 with points pt 2 ps 2 lc rgb '#2ca02c' title 'uncontrolled', "
       "'' index 1 using 1:2 with points pt 1 ps 2 lc rgb '#1f77b4' title 'controlled', "
       "'' index 2 using 1:2 with points pt 6 ps 2 lc rgb '#d62728' title 'reduced'\n";
  run_gnuplot(dir, "pole_map", s.str());
  return png.string();
}

/// The first two minutes of the five outputs of both systems.
std::string plot_time(const std::string& dir, const Ce500Analysis& a) {
  const auto& names = ce500_output_names();
  const char* labels[] = {"beta [deg]", "phi [deg]", "pb/2V [-]", "rb/2V [-]", "a_y [m/s^2]"};
  const Eigen::Index n =
      std::min<Eigen::Index>(a.t_s.size(), static_cast<Eigen::Index>(std::llround(120.0 / a.options.dt_s)) + 1);
  std::vector<plots::TimePanel> panels;
  for (std::size_t i = 0; i < names.size(); ++i) {
    const Eigen::Index c = static_cast<Eigen::Index>(i);
    plots::TimePanel p;
    p.name = names[i];
    p.title = names[i];
    p.ylabel = labels[i];
    p.series.push_back({"controlled", a.controlled.y.col(c).head(n), "#1f77b4", false});
    p.series.push_back({"reduced", a.reduced.y.col(c).head(n), "#d62728", true});
    panels.push_back(p);
  }
  return plots::plot_time_histories(dir, "time_histories", "Ce500 responses to the same v_g, w_g turbulence record",
                                    a.t_s.head(n), panels);
}

}  // namespace

int run_turbulence_command(const std::vector<std::string>& args) {
  std::string file, json, plots;
  std::optional<double> duration, dt;
  std::optional<std::uint64_t> seed;
  std::optional<std::size_t> segment;
  cmdline::CommandLine cl("rig turbulence", kDescription);
  cl->footer(
      "Exit code: 0, or 1 if an eigenvalue differs from Table 2.1 by more than the file's tolerance;\n"
      "2 bad usage or input.");
  cl->add_option("practical", file, "the practical's file (rig_configs/turbulence/ce500_practical.yaml)")->required();
  cl->add_option("--duration", duration, "record length [s] (default: the file's simulation.duration_s)")
      ->check(cmdline::kFinite & CLI::PositiveNumber)
      ->type_name("S");
  cl->add_option("--dt", dt, "time step [s] (default: the file's simulation.dt_s, 0.05 as the practical)")
      ->check(cmdline::kFinite & CLI::Range(1e-9, 1.0))
      ->type_name("S");
  cl->add_option("--seed", seed, "noise seed (default: the file's simulation.seed)")
      ->check(cmdline::kWholeNumber)
      ->type_name("N");
  cl->add_option("--welch-segment", segment,
                 "Welch segment length [samples], a power of two >= 8 (default N/8 rounded down)")
      ->check(cmdline::kPowerOfTwo)
      ->type_name("M");
  cl.add_json(json, "the report");
  cl.add_plots(plots, "psd_matrix.png, time_histories.png, pole_map.png");
  if (const auto done = cl.parse(args)) return *done;
  if (!plots.empty()) plots::require_gnuplot();

  const Ce500Config config = load_ce500_config(file);
  Ce500Options options = ce500_default_options(config);
  if (duration) options.duration_s = *duration;
  if (dt) options.dt_s = *dt;
  if (seed) options.seed = *seed;
  if (segment) options.welch_segment = *segment;
  const Ce500Analysis a = analyse_ce500(config, options);

  if (json != "-") std::cout << report_text(a);
  if (!json.empty()) cmdline::write_json(json, report_json(a));
  if (!plots.empty()) {
    const fs::path dir(plots);
    fs::create_directories(dir);
    for (const auto& p : {plot_psd_matrix(dir, a), plot_time(plots, a), plot_pole_map(dir, a)}) {
      if (json != "-") std::cout << "plot " << p << "\n";
    }
  }
  bool ok = true;
  for (const auto& col : a.table_2_1) ok = ok && col.max_distance <= config.published.eigenvalue_tolerance;
  return ok ? 0 : 1;
}

}  // namespace nimble::cli
