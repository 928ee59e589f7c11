// The discrepancy workflow (discrepancy/discrepancy.h), part: the data-compatibility stage in the JSON, text
// and Markdown reports (discrepancy/data_compatibility.h), and the forms tested as given (term_tests).

#include <cstdio>
#include <ostream>
#include <sstream>

#include "discrepancy/discrepancy_compat_parts.h"
#include "discrepancy/discrepancy_parts.h"

namespace nimble::ident::discrepancy_parts {

namespace {

std::string num(double x) { return fmt(x, 4); }

std::string sensor_words(const NamedEffect& e) {
  std::string s = e.name + " of " + e.channel;
  if (!e.against.empty()) s += " against " + e.against;
  s += ": " + num(e.coefficient) + " " + e.unit + " (95 % interval " + num(e.interval[0]) + " .. " +
       num(e.interval[1]) + ")";
  if (e.name == kTimeOffsetError) s += e.coefficient > 0.0 ? ", its stamps late" : ", its stamps early";
  return s;
}

/// The baseline's held-out RMSE as recorded, and (one flight) corrected: the gap table's rmse_before.
std::string uncorrected_words(const CompatibilityResult& c, const DiscrepancyResult& r) {
  std::string s = "baseline held-out RMSE as recorded";
  if (r.compatibility.size() == 1) s += " -> corrected";
  for (const auto& [out, v] : c.rmse_uncorrected) {
    s += ", " + out + " " + num(v);
    for (const OutputGap& g : r.gap) {
      if (g.output == out && r.compatibility.size() == 1) s += " -> " + num(g.rmse_before);
    }
  }
  return s;
}

}  // namespace

void print_compatibility(std::ostream& o, const DiscrepancyResult& r) {
  if (r.compatibility.empty()) return;
  o << "data compatibility (the sensors against the kinematics, before any aerodynamic term)\n";
  for (const CompatibilityResult& c : r.compatibility) {
    if (r.compatibility.size() > 1) o << "  " << c.source << "\n";
    if (!c.ran) {
      o << "  not checked: " << c.note << "\n";
      continue;
    }
    o << "  " << c.equation << ", " << c.samples << " samples, " << num(c.blocks) << " blocks\n";
    for (const SensorError& e : c.errors) {
      char line[256];
      std::snprintf(line, sizeof line, "  %-13s %-3s %11.4g %-5s [%.4g, %.4g]  p %.3g (beyond %.3g)  %s\n",
                    e.name.c_str(), e.channel.c_str(), e.value, e.unit.c_str(), e.interval[0], e.interval[1], e.p_value,
                    e.tolerance, e.named ? "named" : (e.significant ? "significant, signature absent: unnamed" : "-"));
      o << line;
      if (e.significant) o << "      signature: " << e.signature_note << "\n";
    }
    o << "  kinematic gap (held-out) " << num(c.kinematic_gap_before) << " -> " << num(c.kinematic_gap_after) << "\n";
    if (!c.rmse_uncorrected.empty()) o << "  " << uncorrected_words(c, r) << "\n";
    for (const auto& s : c.corrections) o << "  corrected: " << s << "\n";
  }
  o << "\n";
}

void print_sensor_effect(std::ostream& o, const NamedEffect& e) { o << "    " << sensor_words(e) << "\n"; }

std::string compatibility_markdown(const DiscrepancyResult& r) {
  if (r.compatibility.empty()) return "";
  std::ostringstream md;
  md << "## Data compatibility\n\nThe sensors against the kinematics, before any aerodynamic term "
        "(a significant error is corrected in the record; named when its signature holds).\n\n"
        "| flight | error | channel | value | 95 % interval | p | verdict |\n|---|---|---|---|---|---|---|\n";
  for (const CompatibilityResult& c : r.compatibility) {
    if (!c.ran) {
      md << "| " << c.source << " | not checked | | | | | " << c.note << " |\n";
      continue;
    }
    for (const SensorError& e : c.errors) {
      md << "| " << c.source << " | " << e.name << " | " << e.channel << " | " << num(e.value) << " " << e.unit << " | "
         << num(e.interval[0]) << " .. " << num(e.interval[1]) << " | " << num(e.p_value) << " | "
         << (e.named ? "named" : (e.significant ? "unnamed: signature absent" : "-")) << " |\n";
    }
  }
  md << "\n";
  for (const CompatibilityResult& c : r.compatibility) {
    if (!c.ran) continue;
    md << "Kinematic gap of " << c.source << " (" << c.equation << ", held-out): " << num(c.kinematic_gap_before)
       << " -> " << num(c.kinematic_gap_after);
    md << ".";
    if (!c.rmse_uncorrected.empty()) md << " " << uncorrected_words(c, r) << ".";
    md << "\n\n";
  }
  return md.str();
}

void print_term_tests(std::ostream& o, const DiscrepancyResult& r) {
  if (r.term_tests.empty()) return;
  o << "forms tested as given (one test each on the model as given, not an alarm):\n";
  for (const TermTest& t : r.term_tests) {
    o << "  " << t.equation << " += c " << t.expression << ": ";
    if (!t.note.empty()) {
      o << "not tested: " << t.note << "\n";
      continue;
    }
    o << "c = " << num(t.coefficient) << " (sigma " << num(t.sigma) << "), Wald " << num(t.wald) << ", p "
      << num(t.p_value) << " (" << num(t.blocks)
      << " batches); instrumented by the excitation: c = " << num(t.iv_coefficient) << " (sigma " << num(t.iv_sigma)
      << "), p " << num(t.iv_p_value) << "\n";
  }
  o << "\n";
}

}  // namespace nimble::ident::discrepancy_parts
