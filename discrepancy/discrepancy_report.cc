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

#include "core/json_writer.h"
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

namespace {

std::string g(double x, const char* f = "%.4g") { return report_number(x, f); }

void number_map(JsonWriter& j, const std::map<std::string, double>& m) {
  j.begin_object();
  for (const auto& [k, v] : m) j.key(k).value(v);
  j.end_object();
}

/// The gap's numbers, each finite: a gap of nan (a record without excitation that reached the
/// workflow) is an error here, never a printed "nan" or a JSON null.
void require_finite_gap(const DiscrepancyResult& r) {
  const auto need = [&r](double x, const std::string& what) {
    if (!std::isfinite(x)) {
      throw std::logic_error("discrepancy of " + r.source + ": " + what + " is " + g(x) +
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

/// Each named effect with its parameters; a term also with its equation, interval and the forms it beat.
void write_effects(JsonWriter& j, const DiscrepancyResult& r) {
  j.key("effects").begin_array();
  for (const auto& e : r.effects) {
    j.begin_object();
    j.key("name").value(e.name);
    if (!e.channel.empty()) discrepancy_parts::write_sensor_effect(j, e);
    if (!e.contradicts.empty()) j.key("contradicts").value(e.contradicts);
    if (e.name == "term") {
      j.key("equation").value(e.equation);
      j.key("expression").value(e.expression);
      j.key("coefficient").value(e.coefficient);
      j.key("interval").begin_array().value(e.interval[0]).value(e.interval[1]).end_array();
      j.key("alternatives").array(e.alternatives);
      j.key("ruled_out").begin_array();
      for (const auto& [name, reason] : e.ruled_out) {
        j.begin_object();
        j.key("name").value(name);
        j.key("reason").value(reason);
        j.end_object();
      }
      j.end_array();
    }
    j.key("parameters");
    number_map(j, e.parameters);
    j.key("sigma");
    number_map(j, e.sigma);
    j.end_object();
  }
  j.end_array();
}

/// Every candidate tried, round by round, with its test statistics where it could be tried.
void write_candidates(JsonWriter& j, const DiscrepancyResult& r) {
  j.key("candidates").begin_array();
  for (const auto& t : r.candidates) {
    j.begin_object();
    j.key("name").value(t.name);
    j.key("round").value(static_cast<long long>(t.round));
    j.key("available").value(t.available);
    j.key("passed").value(t.passed);
    j.key("entered").value(t.entered);
    j.key("reason").value(t.reason);
    if (t.name == "term") {
      j.key("equation").value(t.equation);
      j.key("expression").value(t.expression);
    }
    if (!t.ambiguous_with.empty()) {
      j.key("ambiguous_with").value(t.ambiguous_with);
      j.key("tell_apart").value(t.tell_apart);
    }
    if (t.available) {
      j.key("partial_f");
      number_map(j, t.partial_f);
      j.key("p_value").value(t.p_value);
      j.key("p_critical").value(t.p_critical);
      j.key("highpass_p").value(t.highpass_p);
      j.key("scan_points").value(static_cast<long long>(t.scan_points));
      j.key("pse_before");
      number_map(j, t.pse_before);
      j.key("pse_after");
      number_map(j, t.pse_after);
      j.key("heldout_drop").value(t.heldout_drop);
      j.key("heldout_se").value(t.heldout_se);
      j.key("parameters");
      number_map(j, t.parameters);
      j.key("sigma");
      number_map(j, t.sigma);
      if (!t.instantaneous_f.empty()) {
        j.key("instantaneous_f");
        number_map(j, t.instantaneous_f);
      }
    }
    j.end_object();
  }
  j.end_array();
}

/// Where the residual is: in time, in frequency, in the states and in the candidates' signatures.
void write_located(JsonWriter& j, const DiscrepancyResult& r) {
  j.key("located").begin_object();
  j.key("excitation").begin_array();
  for (const auto& x : r.located.excitation) j.value(x);
  j.end_array();
  j.key("note").value(r.located.note);
  j.key("time").begin_array();
  for (const auto& f : r.located.time) {
    j.begin_object();
    j.key("output").value(f.output);
    j.key("what").value(f.what);
    j.key("start_s").value(f.start_s);
    j.key("end_s").value(f.end_s);
    j.key("energy_share").value(f.energy_share);
    j.key("time_share").value(f.time_share);
    j.end_object();
  }
  j.end_array();
  j.key("frequency").begin_array();
  for (const auto& f : r.located.frequency) {
    j.begin_object();
    j.key("output").value(f.output);
    j.key("f_hz").value(f.f_hz);
    j.key("ratio").value(f.ratio);
    j.key("p_value").value(f.p_value);
    j.end_object();
  }
  j.end_array();
  j.key("state").begin_array();
  for (const auto& f : r.located.state) {
    j.begin_object();
    j.key("output").value(f.output);
    j.key("signal").value(f.signal);
    j.key("partial_r").value(f.partial_r);
    j.key("p_value").value(f.p_value);
    j.end_object();
  }
  j.end_array();
  // Only with DiscrepancyOptions::signature_checks can there be one; the key is written when there is.
  if (!r.located.signature.empty()) j.key("signature").begin_array();
  for (const auto& f : r.located.signature) {
    j.begin_object();
    j.key("candidate").value(f.candidate);
    j.key("equations").begin_array();
    for (const auto& e : f.equations) j.value(e);
    j.end_array();
    j.key("note").value(f.note);
    j.end_object();
  }
  if (!r.located.signature.empty()) j.end_array();
  j.end_object();
}

/// The held-out gap before and after the named effects, by output and by band.
void write_gap(JsonWriter& j, const DiscrepancyResult& r) {
  j.key("gap").begin_object();
  j.key("metric").value(r.gap_metric);
  j.key("before").value(r.gap_before);
  j.key("after").value(r.gap_after);
  j.key("folds").value(static_cast<long long>(r.folds));
  j.key("outputs").begin_array();
  for (const auto& o : r.gap) {
    j.begin_object();
    j.key("output").value(o.output);
    j.key("unit").value(o.unit);
    j.key("rmse_model").value(o.rmse_model);
    j.key("rmse_before").value(o.rmse_before);
    j.key("rmse_after").value(o.rmse_after);
    j.key("fit_before_pct").value(o.fit_before_pct);
    j.key("fit_after_pct").value(o.fit_after_pct);
    if (o.white_tested) {
      j.key("white_before").value(o.white_before);
      j.key("white_after").value(o.white_after);
    } else {  // too short for the lags: see notes
      j.key("white_before").null();
      j.key("white_after").null();
    }
    j.key("peak_psd_before").value(o.peak_psd_before);
    j.key("peak_psd_after").value(o.peak_psd_after);
    j.end_object();
  }
  j.end_array();
  j.key("bands").begin_array();
  for (const auto& b : r.gap_bands) {
    j.begin_object();
    j.key("name").value(b.name);
    j.key("equations").begin_array();
    for (const auto& e : b.equations) j.value(e);
    j.end_array();
    j.key("lo_hz").value(b.lo_hz);
    j.key("hi_hz").value(b.hi_hz);
    j.key("before").value(b.before);
    j.key("after").value(b.after);
    j.key("wideband").value(b.wideband);
    j.key("note").value(b.note);
    j.end_object();
  }
  j.end_array();
  j.end_object();
}

void write_closed_loop(JsonWriter& j, const DiscrepancyResult& r) {
  j.key("closed_loop").begin_object();
  j.key("note").value(r.closed_loop_note);
  j.key("outputs").begin_array();
  for (const auto& c : r.closed_loop) {
    j.begin_object();
    j.key("output").value(c.output);
    j.key("r2_before").value(c.r2_before);
    j.key("r2_after").value(c.r2_after);
    j.key("rmse_before").value(c.rmse_before);
    j.key("rmse_after").value(c.rmse_after);
    j.end_object();
  }
  j.end_array();
  j.end_object();
}

/// Each pooled flight's own estimate of the named effects.
void write_flights(JsonWriter& j, const DiscrepancyResult& r) {
  j.key("flights").begin_array();
  for (const auto& f : r.flights) {
    j.begin_object();
    j.key("source").value(f.source);
    j.key("samples").value(static_cast<long long>(f.samples));
    j.key("start_s").value(f.start_s);
    j.key("end_s").value(f.end_s);
    j.key("noise");
    number_map(j, f.noise);
    j.key("parameters");
    number_map(j, f.parameters);
    j.key("sigma");
    number_map(j, f.sigma);
    j.end_object();
  }
  j.end_array();
}

/// Whether each named effect is the same in all the pooled flights.
void write_consistency(JsonWriter& j, const DiscrepancyResult& r) {
  j.key("consistency").begin_array();
  for (const auto& c : r.consistency) {
    j.begin_object();
    j.key("effect").value(c.effect);
    j.key("q").value(c.q);
    j.key("dof").value(c.dof);
    j.key("p_value").value(c.p_value);
    j.key("same").value(c.same);
    j.key("differs").value(c.differs);
    j.end_object();
  }
  j.end_array();
}

/// A model's parameter estimates under `key`: each value with its sigma, white and coloured.
void write_parameters(JsonWriter& j, const char* key, const std::map<std::string, ParameterEstimate>& m) {
  j.key(key).begin_object();
  for (const auto& [name, e] : m) {
    j.key(name).begin_object();
    j.key("value").value(e.value);
    j.key("sigma").value(e.sigma);
    j.key("sigma_coloured").value(e.sigma_coloured);
    j.end_object();
  }
  j.end_object();
}

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

std::string discrepancy_json(const DiscrepancyResult& r) {
  require_finite_gap(r);
  JsonWriter j;
  j.begin_object();
  j.key("source").value(r.source);
  j.key("model").value(r.model_name);
  j.key("verdict").value(r.verdict);
  j.key("summary").value(r.summary);
  j.key("samples").value(static_cast<long long>(r.samples));
  j.key("rate_hz").value(r.rate_hz);
  j.key("notes").array(r.notes);
  write_effects(j, r);
  discrepancy_parts::write_compatibility(j, r);
  discrepancy_parts::write_term_tests(j, r);
  j.key("ambiguous").begin_array();
  for (const auto& pair : r.ambiguous) j.array(pair);
  j.end_array();
  write_candidates(j, r);
  j.key("alarm_rule").begin_object();
  j.key("p_critical").value(r.alarm_rule.p_critical);
  j.key("tests").value(static_cast<long long>(r.alarm_rule.tests));
  j.key("family_wise").value(r.alarm_rule.family_wise);
  j.end_object();
  write_located(j, r);
  write_gap(j, r);
  write_closed_loop(j, r);
  write_flights(j, r);
  write_consistency(j, r);
  write_parameters(j, "baseline", r.baseline);
  write_parameters(j, "augmented", r.augmented);
  j.end_object();
  return j.str();
}

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
