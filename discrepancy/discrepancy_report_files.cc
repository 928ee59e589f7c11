/// The report's text and files (discrepancy/discrepancy.h, write_discrepancy_report): the
/// figures drawn by gnuplot and report.md.

#include <algorithm>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "core/output_file.h"
#include "discrepancy/discrepancy.h"
#include "discrepancy/discrepancy_compat_parts.h"
#include "discrepancy/report_parts.h"
#include "ident/spectrum.h"
#include "plots/gnuplot.h"

namespace nimble::ident {
namespace {

std::string num(double x, const char* f = "%.4g") { return report_number(x, f); }

/// outputs.png, residuals.png and residual_psd.png in `dir`: the held-out outputs and residuals
/// before and after, and the residuals' spectra.
std::vector<std::string> report_figures(const DiscrepancyResult& r, const std::string& dir) {
  std::vector<std::string> files;
  std::vector<plots::TimePanel> outputs, residuals, psds;
  Eigen::VectorXd f_hz;
  const std::size_t segment = std::max<std::size_t>(64, static_cast<std::size_t>(2.0 * r.rate_hz));
  for (const auto& o : r.gap) {
    outputs.push_back({o.output,
                       o.output + " [" + o.unit + "]",
                       o.unit,
                       {{"measured", o.measured, "#000000", false},
                        {"model structure refit (held-out)", o.predicted_before, "#d62728", true},
                        {"with the named effects (held-out)", o.predicted_after, "#1f77b4", false}}});
    const Eigen::VectorXd rb = o.measured - o.predicted_before, ra = o.measured - o.predicted_after;
    residuals.push_back({o.output + "_residual",
                         o.output + " residual [" + o.unit + "]",
                         o.unit,
                         {{"before", rb, "#d62728", false}, {"after", ra, "#1f77b4", false}}});
    const Psd pb = welch(rb, r.rate_hz, segment), pa = welch(ra, r.rate_hz, segment);
    f_hz = pb.f_hz;
    psds.push_back(
        {o.output + "_psd",
         o.output + " residual PSD [(" + o.unit + ")^2/Hz]",
         "PSD",
         {{"before", pb.psd.cwiseMax(1e-30), "#d62728", false}, {"after", pa.psd.cwiseMax(1e-30), "#1f77b4", false}}});
  }
  const std::string what = r.model_name + " on " + r.source;
  files.push_back(plots::plot_time_histories(dir, "outputs", "discrepancy: " + what, r.t_s, outputs));
  files.push_back(
      plots::plot_time_histories(dir, "residuals", "held-out residuals before and after: " + what, r.t_s, residuals));
  plots::PlotAxes axes;
  axes.xlabel = "frequency [Hz]";
  axes.log_y = true;
  axes.x_max = r.cutoff_hz > 0.0 ? 2.0 * r.cutoff_hz : 0.5 * r.rate_hz;
  files.push_back(plots::plot_panels(dir, "residual_psd", "residual PSDs (Welch, 2 s): " + what, f_hz, psds, axes));

  return files;
}

/// report.md: the verdict, the named effects, the gap, the candidates, the bands, where it is.
std::string report_markdown(const DiscrepancyResult& r) {
  std::ostringstream md;
  md << "# Discrepancy: " << r.model_name << "\n\n";
  md << "Data: `" << r.source << "`, " << r.samples << " samples at " << num(r.rate_hz) << " Hz; held-out figures from "
     << r.folds << "-fold cross-validation over contiguous blocks.\n\n";
  md << "**Verdict: " << r.verdict << "**: " << r.summary << "\n\n";
  md << discrepancy_parts::compatibility_markdown(r);
  if (!r.effects.empty()) {
    md << "## Named effects\n\n| effect | parameter | value | sigma (coloured) |\n|---|---|---|---|\n";
    for (const auto& e : r.effects) {
      for (const auto& [k, v] : e.parameters) {
        const auto s = e.sigma.find(k);
        md << "| " << e.name << " | " << k << " | " << num(v) << " | " << (s == e.sigma.end() ? "" : num(s->second))
           << " |\n";
      }
    }
    md << "\n";
  }
  md << "## Gap on held-out data\n\n"
     << r.gap_metric << ": **" << num(r.gap_before) << " -> " << num(r.gap_after) << "**\n\n";
  md << "| output | unit | RMSE model | RMSE before | RMSE after | fit % before | fit % after | white before | white "
        "after "
        "|\n|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& o : r.gap) {
    md << "| " << o.output << " | " << o.unit << " | " << num(o.rmse_model) << " | " << num(o.rmse_before) << " | "
       << num(o.rmse_after) << " | " << num(o.fit_before_pct, "%.1f") << " | " << num(o.fit_after_pct, "%.1f") << " | "
       << (!o.white_tested  ? "-"
           : o.white_before ? "yes"
                            : "no")
       << " | "
       << (!o.white_tested ? "-"
           : o.white_after ? "yes"
                           : "no")
       << " |\n";
  }
  for (const auto& note : r.notes) md << "\n" << note << "\n";
  if (!r.closed_loop.empty()) {
    md << "\nClosed loop (the model flown by the controller copy on the data's phi_sp), the model as given -> "
          "the augmented model:\n\n| signal | R^2 before | R^2 after | RMSE before | RMSE after "
          "|\n|---|---|---|---|---|\n";
    for (const auto& c : r.closed_loop) {
      md << "| " << c.output << " | " << num(c.r2_before, "%.3f") << " | " << num(c.r2_after, "%.3f") << " | "
         << num(c.rmse_before) << " | " << num(c.rmse_after) << " |\n";
    }
  }
  md << "\n![outputs](outputs.png)\n\n![residuals](residuals.png)\n\n![residual PSDs](residual_psd.png)\n\n";
  md << "## Candidates\n\n| round | candidate | partial F | p (adjusted) | held-out drop | result "
        "|\n|---|---|---|---|---|---|\n";
  for (const auto& t : r.candidates) {
    std::string f;
    for (const auto& [eq, v] : t.partial_f) f += (f.empty() ? "" : ", ") + eq + " " + num(v);
    md << "| " << t.round << " | " << trial_name(t, "`") << " | " << f << " | " << (t.available ? num(t.p_value) : "")
       << " | "
       << (t.available ? num(100.0 * t.heldout_drop, "%.1f") + " % +- " + num(100.0 * t.heldout_se, "%.1f") + " %" : "")
       << " | " << t.reason << " |\n";
  }
  md << "\n## Gap by band\n\n| band | equations | Hz | before | after |\n|---|---|---|---|---|\n";
  for (const auto& b : r.gap_bands) {
    std::string eqs;
    for (const auto& e : b.equations) eqs += (eqs.empty() ? "" : ", ") + e;
    md << "| " << b.name << (b.wideband ? " (wideband data)" : "") << " | " << eqs << " | " << num(b.lo_hz) << "-"
       << num(b.hi_hz) << " | " << num(b.before) << " | " << num(b.after) << " |\n";
  }
  for (const auto& b : r.gap_bands) {
    if (!b.note.empty()) md << "\n" << b.name << ": " << b.note << "\n";
  }
  md << "\n## Located\n\n";
  for (const auto& f : r.located.frequency) {
    md << "- frequency: " << f.output << " peak at " << num(f.f_hz) << " Hz, " << num(f.ratio)
       << " x the local background (p " << num(f.p_value) << ")\n";
  }
  for (const auto& f : r.located.state) {
    md << "- state: " << f.output << " depends nonlinearly on " << f.signal << " (partial r " << num(f.partial_r)
       << ", p " << num(f.p_value) << ")\n";
  }
  for (const auto& f : r.located.time) {
    md << "- time: " << f.output << " " << f.what << " " << num(f.start_s, "%.2f") << "-" << num(f.end_s, "%.2f")
       << " s: " << num(100.0 * f.energy_share, "%.1f") << " % of the residual energy in "
       << num(100.0 * f.time_share, "%.1f") << " % of the time\n";
  }
  return md.str();
}

}  // namespace

std::vector<std::string> write_discrepancy_report(const DiscrepancyResult& r, const std::string& dir) {
  plots::require_gnuplot();
  std::filesystem::create_directories(dir);
  std::vector<std::string> files = report_figures(r, dir);
  const std::string report = (std::filesystem::path(dir) / "report.md").string();
  write_file(report, report_markdown(r));
  files.insert(files.begin(), report);
  return files;
}

}  // namespace nimble::ident
