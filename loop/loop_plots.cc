// `rig loop --plots`: Bode and Nyquist of the return ratio with the margins marked, the
// closed-loop step of phi, and the pole-zero map (loop/loop_report.h plot_loops).

#include <cmath>
#include <complex>
#include <filesystem>
#include <sstream>

#include <Eigen/Eigenvalues>

#include "core/config.h"
#include "core/constants.h"
#include "core/output_file.h"
#include "ident/plots.h"
#include "loop/loop_report.h"
#include "plots/gnuplot.h"

namespace nimble::loop {
namespace {

namespace fs = std::filesystem;
using plots::gp_quote;
using plots::run_gnuplot;

const char* const kColours[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b"};

std::string colour(std::size_t i) { return kColours[i % (sizeof kColours / sizeof kColours[0])]; }

std::string title_of(const LoopRow& r) {
  return r.model + " " + r.gains + (r.where == LoopBreak::kActuator ? "" : " (break " + to_string(r.where) + ")");
}

/// Zeros of the return ratio: the finite generalised eigenvalues of ([A B; C D], [I 0; 0 0]),
/// as continuous equivalents ln(z) / dt.
std::vector<std::complex<double>> loop_zeros(const BrokenLoop& b) {
  const Eigen::Index n = b.A.rows();
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n + 1, n + 1), N = Eigen::MatrixXd::Zero(n + 1, n + 1);
  M.topLeftCorner(n, n) = b.A;
  M.topRightCorner(n, 1) = b.B;
  M.bottomLeftCorner(1, n) = b.C;
  M(n, n) = b.D;
  N.topLeftCorner(n, n).setIdentity();
  Eigen::GeneralizedEigenSolver<Eigen::MatrixXd> ges(M, N, false);
  std::vector<std::complex<double>> zeros;
  for (Eigen::Index i = 0; i < ges.betas().size(); ++i) {
    if (std::abs(ges.betas()(i)) < 1e-12) continue;
    const std::complex<double> z = ges.alphas()(i) / ges.betas()(i);
    if (std::abs(z) > 1e-9) zeros.push_back(std::log(z) / b.dt_s);
  }
  return zeros;
}

std::string plot_bode(const fs::path& dir, const std::vector<LoopRow>& rows,
                      const std::vector<RollLoopResponse>& resp) {
  std::ostringstream data, script;
  const std::vector<double>& w = resp.front().omega_radps;
  for (std::size_t i = 0; i < w.size(); ++i) {
    data << w[i] / (2 * kPi);
    for (const auto& x : resp) {
      data << " " << 20 * std::log10(std::abs(x.ratio[i])) << " " << std::arg(x.ratio[i]) * 180 / kPi;
    }
    data << "\n";
  }
  write_file(dir / "loop_bode.dat", data.str());
  script << "set terminal pngcairo noenhanced size 1100,800\nset output " << gp_quote((dir / "loop_bode.png").string())
         << "\n"
         << "set multiplot layout 2,1 title 'Return ratio L at the break (margins marked)'\nset logscale x\n"
         << "set xrange [" << w.front() / (2 * kPi) << ":" << w.back() / (2 * kPi) << "]\nset yrange [-80:40]\n"
         << "set grid\nset ylabel '|L| [dB]'\nset arrow from graph 0, first 0 to graph 1, first 0 nohead dt 2\n";
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const LoopMargins& m = rows[k].analysis.margins;
    if (std::isfinite(m.gain_margin_hz)) {
      script << "set arrow from " << m.gain_margin_hz << ", first " << -m.gain_margin_db() << " to " << m.gain_margin_hz
             << ", first 0 lc rgb '" << colour(k) << "' lw 2\n"
             << "set label 'GM " << fmt("%.1f dB", m.gain_margin_db()) << "' at " << m.gain_margin_hz << ", first "
             << -m.gain_margin_db() - 3 << " tc rgb '" << colour(k) << "'\n";
    }
  }
  script << "plot ";
  for (std::size_t k = 0; k < rows.size(); ++k) {
    script << (k ? ", " : "") << gp_quote((dir / "loop_bode.dat").string()) << " using 1:" << 2 + 2 * k
           << " with lines lw 2 lc rgb '" << colour(k) << "' title " << gp_quote(title_of(rows[k]));
  }
  script << "\nunset arrow\nunset label\nset yrange [-200:200]\nset ylabel 'phase of L [deg]'\nset xlabel 'frequency "
            "[Hz]'\n"
         << "set arrow from graph 0, first -180 to graph 1, first -180 nohead dt 2\n";
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const LoopMargins& m = rows[k].analysis.margins;
    if (std::isfinite(m.crossover_hz)) {
      script << "set arrow from " << m.crossover_hz << ", first -180 to " << m.crossover_hz << ", first "
             << -180 + m.phase_margin_deg << " lc rgb '" << colour(k) << "' lw 2\n"
             << "set label 'PM " << fmt("%.1f deg", m.phase_margin_deg) << "' at " << m.crossover_hz << ", first "
             << -180 + m.phase_margin_deg + 10 << " tc rgb '" << colour(k) << "'\n";
    }
  }
  script << "plot ";
  for (std::size_t k = 0; k < rows.size(); ++k) {
    script << (k ? ", " : "") << gp_quote((dir / "loop_bode.dat").string()) << " using 1:" << 3 + 2 * k
           << " with lines lw 2 lc rgb '" << colour(k) << "' notitle";
  }
  script << "\nunset multiplot\n";
  run_gnuplot(dir, "loop_bode", script.str());
  return (dir / "loop_bode.png").string();
}

std::string plot_nyquist(const fs::path& dir, const std::vector<LoopRow>& rows,
                         const std::vector<RollLoopResponse>& resp) {
  std::ostringstream data, script;
  for (const RollLoopResponse& x : resp) {
    for (const auto& l : x.ratio) data << l.real() << " " << l.imag() << "\n";
    for (auto it = x.ratio.rbegin(); it != x.ratio.rend(); ++it) data << it->real() << " " << -it->imag() << "\n";
    data << "\n\n";
  }
  write_file(dir / "loop_nyquist.dat", data.str());
  script << "set terminal pngcairo noenhanced size 900,800\nset output "
         << gp_quote((dir / "loop_nyquist.png").string()) << "\n"
         << "set title 'Nyquist of L (unit circle, -1 marked)'\nset grid\nset size ratio -1\n"
         << "set xrange [-3:2]\nset yrange [-2.5:2.5]\nset xlabel 'Re L'\nset ylabel 'Im L'\n"
         << "set object 1 circle at 0,0 size 1 fs empty border lc rgb '#888888'\n"
         << "set label 'Ms circle' at -1,-0.2\nplot ";
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const double ms = rows[k].analysis.margins.sensitivity_peak;
    script << gp_quote((dir / "loop_nyquist.dat").string()) << " index " << k << " with lines lw 2 lc rgb '"
           << colour(k) << "' title " << gp_quote(title_of(rows[k]) + fmt(", Ms %.2f", ms)) << ", ";
    // The circle |1 + L| = 1/Ms, which L touches.
    script << "'+' using (-1 + cos(2*pi*$0/100)/" << ms << "):(sin(2*pi*$0/100)/" << ms
           << ") every ::0::100 with lines dt 3 lc rgb '" << colour(k) << "' notitle, ";
  }
  script << "'-' with points pt 2 ps 2 lc rgb 'black' title '-1'\n-1 0\ne\n";
  run_gnuplot(dir, "loop_nyquist", script.str());
  return (dir / "loop_nyquist.png").string();
}

std::string plot_step(const fs::path& dir, const std::vector<LoopRow>& rows) {
  std::ostringstream data, script;
  const double step = 10.0 * kPi / 180.0;
  std::vector<StepResponse> resp;
  for (const LoopRow& r : rows) resp.push_back(roll_step_response(roll_setpoint_loop(r.lateral, r.config), step, 2.0));
  for (std::size_t i = 0; i < resp.front().t_s.size(); ++i) {
    data << resp.front().t_s[i];
    for (const auto& x : resp) data << " " << x.phi_rad[i] * 180 / kPi << " " << x.phi_ref_rad[i] * 180 / kPi;
    data << "\n";
  }
  write_file(dir / "loop_step.dat", data.str());
  script << "set terminal pngcairo noenhanced size 1000,600\nset output " << gp_quote((dir / "loop_step.png").string())
         << "\n"
         << "set title 'Closed loop: phi after a 10 deg roll set-point step (dashed: the reference phi_ref)'\n"
         << "set grid\nset xlabel 'time [s]'\nset ylabel 'phi [deg]'\nplot ";
  for (std::size_t k = 0; k < rows.size(); ++k) {
    script << (k ? ", " : "") << gp_quote((dir / "loop_step.dat").string()) << " using 1:" << 2 + 2 * k
           << " with lines lw 2 lc rgb '" << colour(k) << "' title " << gp_quote(title_of(rows[k])) << ", "
           << gp_quote((dir / "loop_step.dat").string()) << " using 1:" << 3 + 2 * k << " with lines dt 2 lc rgb '"
           << colour(k) << "' notitle";
  }
  script << "\n";
  run_gnuplot(dir, "loop_step", script.str());
  return (dir / "loop_step.png").string();
}

std::string plot_poles(const fs::path& dir, const std::vector<LoopRow>& rows) {
  std::ostringstream data, script;
  for (const LoopRow& r : rows) {
    for (const LoopPole& p : r.analysis.poles) data << p.s.real() << " " << p.s.imag() << "\n";
    data << "\n\n";
    const BrokenLoop b = roll_broken_loop(r.lateral, r.config, r.where);
    for (const LoopPole& p : loop_poles(b.A, b.dt_s)) data << p.s.real() << " " << p.s.imag() << "\n";
    data << "\n\n";
    for (const auto& z : loop_zeros(b)) data << z.real() << " " << z.imag() << "\n";
    data << "\n\n";
  }
  write_file(dir / "loop_poles.dat", data.str());
  script
      << "set terminal pngcairo noenhanced size 900,800\nset output " << gp_quote((dir / "loop_poles.png").string())
      << "\n"
      << "set title 'Pole-zero map (s = ln z / T): closed-loop poles x, open-loop poles +, zeros of L o'\n"
      << "set grid\nset xlabel 'Re s [1/s]'\nset ylabel 'Im s [rad/s]'\nset xrange [-150:20]\nset yrange [-120:120]\n"
      << "set arrow from 0, graph 0 to 0, graph 1 nohead dt 2\nplot ";
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const std::string f = gp_quote((dir / "loop_poles.dat").string());
    script << (k ? ", " : "") << f << " index " << 3 * k << " with points pt 2 ps 2 lw 2 lc rgb '" << colour(k)
           << "' title " << gp_quote(title_of(rows[k])) << ", " << f << " index " << 3 * k + 1
           << " with points pt 1 ps 1.5 lc rgb '" << colour(k) << "' notitle, " << f << " index " << 3 * k + 2
           << " with points pt 6 ps 1.5 lc rgb '" << colour(k) << "' notitle";
  }
  script << "\n";
  run_gnuplot(dir, "loop_poles", script.str());
  return (dir / "loop_poles.png").string();
}

}  // namespace

std::vector<double> response_grid_radps(double rate_hz) {
  std::vector<double> w;
  const double nyquist = kPi * rate_hz;
  for (int i = 0; i < 800; ++i) w.push_back(2 * kPi * 0.01 * std::pow(nyquist / (2 * kPi * 0.01), i / 799.0));
  return w;
}

RollLoopResponse row_response(const LoopRow& row, const std::vector<double>& omega_radps) {
  return roll_loop_response(row.lateral, row.config, row.where, omega_radps);
}

RollLoopResponse row_response(const LoopRow& row) { return row_response(row, response_grid_radps(row.config.rate_hz)); }

std::vector<std::string> plot_loops(const std::string& dir_name, const std::vector<LoopRow>& rows) {
  const fs::path dir(dir_name);
  fs::create_directories(dir);
  if (rows.empty()) return {};
  // One frequency response per loop, on one grid, for the Bode and the Nyquist plot.
  const std::vector<double> w = response_grid_radps(rows.front().config.rate_hz);
  std::vector<RollLoopResponse> resp;
  for (const LoopRow& r : rows) resp.push_back(row_response(r, w));
  return {plot_bode(dir, rows, resp), plot_nyquist(dir, rows, resp), plot_step(dir, rows), plot_poles(dir, rows)};
}

}  // namespace nimble::loop
