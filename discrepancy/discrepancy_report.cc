/// JSON, text and Markdown reports of the discrepancy workflow (discrepancy/discrepancy.h); the
/// Markdown report draws its figures with gnuplot (ident/plots.h).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

#include "core/output_file.h"
#include "discrepancy/discrepancy.h"
#include "discrepancy/discrepancy_compat_parts.h"
#include "discrepancy/discrepancy_parts.h"
#include "discrepancy/report_parts.h"

namespace nimble::ident {

std::string trial_name(const CandidateTrial& t, const std::string& quote) {
  return t.name == "term" ? t.name + " " + t.equation + " " + quote + t.expression + quote : t.name;
}

std::string report_number(double x, const char* format) {
  char buf[48];
  std::snprintf(buf, sizeof buf, format, x);
  return buf;
}

/// The gap's numbers, each finite: a gap of nan (a record without excitation that reached the
/// workflow) is an error here, never a printed "nan" or a JSON null.
void require_finite_gap(const DiscrepancyResult& r) {
  const auto need = [&r](double x, const std::string& what) {
    if (!std::isfinite(x)) {
      throw std::logic_error("discrepancy of " + r.source + ": " + what + " is " + report_number(x, "%.4g") +
                             ", not a finite number: no gap is reported from it");
    }
  };
  need(r.gap_before, "the held-out gap before");
  need(r.gap_after, "the held-out gap after");
  for (const auto& o : r.gap) {
    for (const auto& [x, what] : {std::pair{o.rmse_model, "RMSE of the model"},
                                  {o.rmse_before, "RMSE before"},
                                  {o.rmse_after, "RMSE after"},
                                  {o.fit_before_pct, "fit before"},
                                  {o.fit_after_pct, "fit after"}}) {
      need(x, std::string(what) + " of " + o.output);
    }
  }
  for (const auto& b : r.gap_bands) {
    need(b.before, "the gap before in band " + b.name);
    need(b.after, "the gap after in band " + b.name);
  }
}

namespace {

std::string g(double x, const char* f = "%.4g") { return report_number(x, f); }

/// The named effects in words: a term as its equation, a drift or a change as what it does.
void print_effects(std::ostream& o, const DiscrepancyResult& r) {
  if (!r.effects.empty()) {
    o << "named effects (parameters refit with the baseline derivatives; sigma allows coloured residuals)\n";
    for (const auto& e : r.effects) {
      o << "  " << e.name << (e.contradicts.empty() ? "" : ": " + e.contradicts) << "\n";
      if (!e.channel.empty()) {
        discrepancy_parts::print_sensor_effect(o, e);
        continue;
      }
      if (e.name == "term") {
        o << "    " << e.equation << " += " << g(e.coefficient) << " * " << e.expression << "  (95 % interval "
          << g(e.interval[0]) << " .. " << g(e.interval[1]) << ")\n";
        if (!e.alternatives.empty()) {
          o << "    forms that fit as well:";
          for (const auto& a : e.alternatives) o << " " << a;
          o << "\n";
        }
        o << "    library effects ruled out:\n";
        for (const auto& [name, reason] : e.ruled_out) o << "      " << name << ": " << reason << "\n";
        o << "\n";
        continue;
      }
      const auto& q = e.parameters;
      if (q.count("rate_per_min")) {
        o << "    drift of the flap input's effectiveness: " << g(100.0 * q.at("rate_per_min"))
          << " %/min (95 % interval " << g(100.0 * q.at("rate_per_min_lo")) << " .. "
          << g(100.0 * q.at("rate_per_min_hi")) << ") of its value at t = " << g(q.at("t_mid_s")) << " s\n";
      }
      if (q.count("t_change_s")) {
        o << "    change at t = " << g(q.at("t_change_s")) << " s (95 % interval " << g(q.at("t_change_lo_s")) << " .. "
          << g(q.at("t_change_hi_s")) << " s)";
        if (q.count("fraction")) {
          o << ", the flap input's effectiveness by " << g(100.0 * q.at("fraction")) << " % ("
            << g(100.0 * q.at("fraction_lo")) << " .. " << g(100.0 * q.at("fraction_hi")) << ")";
        }
        o << "\n";
      }
      for (const auto& [k, v] : e.parameters) {
        const auto s = e.sigma.find(k);
        o << "    " << k << " = " << g(v);
        if (s != e.sigma.end()) o << "  (sigma " << g(s->second) << ")";
        o << "\n";
      }
    }
    o << "\n";
  }
}

/// Each pooled flight's noise and estimates, and whether the effects agree across flights.
void print_flights(std::ostream& o, const DiscrepancyResult& r) {
  if (!r.flights.empty()) {
    o << "pooled flights (each its own folds and noise level; each flight's own estimate of the named effects)\n";
    for (const auto& f : r.flights) {
      o << "  " << f.source << ": " << f.samples << " samples, noise";
      for (const auto& [eq, v] : f.noise) o << " " << eq << " " << g(v);
      o << "\n";
      for (const auto& [k, v] : f.parameters) {
        const auto sg = f.sigma.find(k);
        o << "    " << k << " = " << g(v);
        if (sg != f.sigma.end()) o << "  (sigma " << g(sg->second) << ")";
        o << "\n";
      }
    }
    for (const auto& c : r.consistency) {
      o << "  " << c.effect << " in all flights: Q " << g(c.q) << " on " << g(c.dof) << " dof, p " << g(c.p_value)
        << (c.same ? ": the same in all flights" : ": not the same; " + c.differs + " differs most") << "\n";
    }
    o << "\n";
  }
}

/// The held-out gap table by output, the notes, and the gap by band.
void print_gap(std::ostream& o, const DiscrepancyResult& r) {
  o << "gap on held-out data: " << g(r.gap_before) << " -> " << g(r.gap_after)
    << "  (1 - R^2 of the equation error, mean over the equations)\n";
  o << "  output        unit      RMSE model  RMSE before  RMSE after  fit% before  fit% after  white before/after\n";
  for (const auto& x : r.gap) {
    char line[200];
    std::snprintf(line, sizeof line, "  %-12s  %-8s  %10.4g  %11.4g  %10.4g  %11.1f  %10.1f  %s/%s\n", x.output.c_str(),
                  x.unit.c_str(), x.rmse_model, x.rmse_before, x.rmse_after, x.fit_before_pct, x.fit_after_pct,
                  !x.white_tested  ? "-"
                  : x.white_before ? "yes"
                                   : "no",
                  !x.white_tested ? "-"
                  : x.white_after ? "yes"
                                  : "no");
    o << line;
  }
  for (const auto& note : r.notes) o << "  " << note << "\n";
  o << "gap by band (where the evidence lives; each band's share of the gap, mean over its equations)\n";
  for (const auto& b : r.gap_bands) {
    std::string eqs;
    for (const auto& e : b.equations) eqs += (eqs.empty() ? "" : ",") + e;
    char line[240];
    std::snprintf(line, sizeof line, "  %-32s %-7s %7.3g-%-7.3g Hz  %10.4g -> %10.4g  (%+.0f %%)%s\n", b.name.c_str(),
                  eqs.c_str(), b.lo_hz, b.hi_hz, b.before, b.after,
                  b.before > 0.0 ? 100.0 * (b.after / b.before - 1.0) : 0.0, b.wideband ? "  wideband data" : "");
    o << line;
    if (!b.note.empty()) o << "    " << b.note << "\n";
  }
}

void print_closed_loop(std::ostream& o, const DiscrepancyResult& r) {
  if (!r.closed_loop.empty()) {
    o << "\nclosed loop (model flown by the controller copy on phi_sp";
    if (!r.closed_loop_note.empty()) o << ", " << r.closed_loop_note;
    o << "): the model as given -> the augmented model\n";
    for (const auto& c : r.closed_loop) {
      char line[160];
      std::snprintf(line, sizeof line, "  %-8s R^2 %7.3f -> %7.3f   RMSE %10.4g -> %10.4g\n", c.output.c_str(),
                    c.r2_before, c.r2_after, c.rmse_before, c.rmse_after);
      o << line;
    }
  } else if (!r.closed_loop_note.empty()) {
    o << "\nclosed loop: " << r.closed_loop_note << "\n";
  }
}

void print_candidates(std::ostream& o, const DiscrepancyResult& r) {
  o << "\ncandidates (p_critical = P(chi2_1 >= F) of the partial-F rule)\n";
  for (const auto& t : r.candidates) {
    o << "  round " << t.round << "  " << trial_name(t, "") << ": ";
    if (!t.available) {
      o << "not tried: " << t.reason << "\n";
      continue;
    }
    o << t.reason;
    if (t.parameters.count("t_change_s")) {
      o << "  [change at " << g(t.parameters.at("t_change_s")) << " s of " << t.scan_points << " scanned]";
    } else if (t.name == "term" && t.scan_points > 1) {
      o << "  [the best of " << t.scan_points << " scanned]";
    } else if (t.scan_points > 1 && t.parameters.count("flapping_hz") == 0) {
      o << "  [delay " << g(1e3 * t.delay_s) << " ms of " << t.scan_points << " scanned]";
    }
    o << "\n";
  }
}

/// The located findings: the tests' alarms first, then where the residual's energy is.
void print_located(std::ostream& o, const DiscrepancyResult& r) {
  o << "\nlocated (baseline structure's residual, beside the linear response to the excitation";
  for (const auto& x : r.located.excitation) o << " " << x;
  o << "; each test at p_critical " << g(r.alarm_rule.p_critical) << ", " << r.alarm_rule.tests
    << " alarm tests in all: any alarm on a record with nothing missing <= " << g(r.alarm_rule.family_wise) << ")\n";
  if (!r.located.note.empty()) o << "  " << r.located.note << "\n";
  for (const auto& f : r.located.frequency) {
    o << "  frequency: " << f.output << " peak at " << g(f.f_hz) << " Hz, " << g(f.ratio) << " x local background (p "
      << g(f.p_value) << ")\n";
  }
  for (const auto& f : r.located.state) {
    o << "  state: " << f.output << " depends nonlinearly on " << f.signal << " (partial r " << g(f.partial_r) << ", p "
      << g(f.p_value) << ")\n";
  }
  for (const auto& f : r.located.signature) {
    o << "  signature: " << f.note << "\n";
  }
  if (r.located.frequency.empty() && r.located.state.empty() && r.located.signature.empty()) {
    o << "  no periodic component or state dependence\n";
  }
  o << "  where the residual's energy is (descriptive, not tests):\n";
  for (const auto& f : r.located.time) {
    o << "  time: " << f.output << " " << f.what << " " << g(f.start_s, "%.2f") << "-" << g(f.end_s, "%.2f")
      << " s carries " << g(100.0 * f.energy_share, "%.1f") << " % of the residual energy in "
      << g(100.0 * f.time_share, "%.1f") << " % of the time\n";
  }
}

}  // namespace

std::string discrepancy_text(const DiscrepancyResult& r) {
  require_finite_gap(r);
  std::ostringstream o;
  o << "discrepancy of " << r.model_name << " on " << r.source << " (" << r.samples << " samples at " << g(r.rate_hz)
    << " Hz, " << r.folds << "-fold held-out)\n";
  o << "verdict: " << r.verdict << ": " << r.summary << "\n\n";
  discrepancy_parts::print_compatibility(o, r);
  print_effects(o, r);
  print_flights(o, r);
  print_gap(o, r);
  print_closed_loop(o, r);
  print_candidates(o, r);
  print_located(o, r);
  discrepancy_parts::print_term_tests(o, r);
  return o.str();
}

}  // namespace nimble::ident
