// The discrepancy workflow's JSON report (discrepancy/discrepancy.h, discrepancy_json()): each
// result type with its to_json (nlohmann::ordered_json: keys in the order written, numbers as the
// shortest text that reads back to the same double, a non-finite number as null). The keys and
// their order are the report's format (docs/discrepancy.md, "JSON").

#include "discrepancy/discrepancy.h"
#include "discrepancy/discrepancy_parts.h"
#include "discrepancy/report_parts.h"
#include "core/json_line.h"

namespace nimble::ident {

namespace {

/// A found term's name in the effects and candidates ("term": its equation and expression follow).
bool is_term(const std::string& name) { return name == "term"; }

OrderedJson interval_json(const double (&x)[2]) { return OrderedJson::array({x[0], x[1]}); }

/// Each named effect with its parameters; a term also with its equation, interval and the forms it
/// beat; a sensor error with its channel, value and interval.
OrderedJson effect_json(const NamedEffect& e) {
  OrderedJson j;
  j["name"] = e.name;
  if (!e.channel.empty()) {
    j["channel"] = e.channel;
    if (!e.against.empty()) j["against"] = e.against;
    j["value"] = e.coefficient;
    j["unit"] = e.unit;
    j["interval"] = interval_json(e.interval);
    j["flight"] = e.flight;
  }
  if (!e.contradicts.empty()) j["contradicts"] = e.contradicts;
  if (is_term(e.name)) {
    j["equation"] = e.equation;
    j["expression"] = e.expression;
    j["coefficient"] = e.coefficient;
    j["interval"] = interval_json(e.interval);
    j["alternatives"] = e.alternatives;
    j["ruled_out"] = OrderedJson::array();
    for (const auto& [name, reason] : e.ruled_out) j["ruled_out"].push_back({{"name", name}, {"reason", reason}});
  }
  j["parameters"] = e.parameters;
  j["sigma"] = e.sigma;
  return j;
}

/// A candidate tried, with its test statistics where it could be tried.
OrderedJson candidate_json(const CandidateTrial& t) {
  OrderedJson j = {{"name", t.name},     {"round", t.round},     {"available", t.available},
                   {"passed", t.passed}, {"entered", t.entered}, {"reason", t.reason}};
  if (is_term(t.name)) {
    j["equation"] = t.equation;
    j["expression"] = t.expression;
  }
  if (!t.ambiguous_with.empty()) {
    j["ambiguous_with"] = t.ambiguous_with;
    j["tell_apart"] = t.tell_apart;
  }
  if (t.available) {
    j["partial_f"] = t.partial_f;
    j["p_value"] = t.p_value;
    j["p_critical"] = t.p_critical;
    j["highpass_p"] = t.highpass_p;
    j["scan_points"] = t.scan_points;
    j["pse_before"] = t.pse_before;
    j["pse_after"] = t.pse_after;
    j["heldout_drop"] = t.heldout_drop;
    j["heldout_se"] = t.heldout_se;
    j["parameters"] = t.parameters;
    j["sigma"] = t.sigma;
    if (!t.instantaneous_f.empty()) j["instantaneous_f"] = t.instantaneous_f;
  }
  return j;
}

/// Where the residual is: in time, in frequency, in the states and in the candidates' signatures.
OrderedJson located_json(const Located& l) {
  OrderedJson j = {{"excitation", l.excitation}, {"note", l.note}};
  j["time"] = OrderedJson::array();
  for (const auto& f : l.time) {
    j["time"].push_back({{"output", f.output},
                         {"what", f.what},
                         {"start_s", f.start_s},
                         {"end_s", f.end_s},
                         {"energy_share", f.energy_share},
                         {"time_share", f.time_share}});
  }
  j["frequency"] = OrderedJson::array();
  for (const auto& f : l.frequency) {
    j["frequency"].push_back({{"output", f.output}, {"f_hz", f.f_hz}, {"ratio", f.ratio}, {"p_value", f.p_value}});
  }
  j["state"] = OrderedJson::array();
  for (const auto& f : l.state) {
    j["state"].push_back(
        {{"output", f.output}, {"signal", f.signal}, {"partial_r", f.partial_r}, {"p_value", f.p_value}});
  }
  // Only with DiscrepancyOptions::signature_checks can there be one; the key is written when there is.
  for (const auto& f : l.signature) {
    j["signature"].push_back({{"candidate", f.candidate}, {"equations", f.equations}, {"note", f.note}});
  }
  return j;
}

/// The held-out gap before and after the named effects, by output and by band.
OrderedJson gap_json(const DiscrepancyResult& r) {
  OrderedJson j = {{"metric", r.gap_metric}, {"before", r.gap_before}, {"after", r.gap_after}, {"folds", r.folds}};
  j["outputs"] = OrderedJson::array();
  for (const auto& o : r.gap) {
    OrderedJson out = {{"output", o.output},
                       {"unit", o.unit},
                       {"rmse_model", o.rmse_model},
                       {"rmse_before", o.rmse_before},
                       {"rmse_after", o.rmse_after},
                       {"fit_before_pct", o.fit_before_pct},
                       {"fit_after_pct", o.fit_after_pct}};
    // Too short for the lags: null (see notes).
    out["white_before"] = o.white_tested ? OrderedJson(o.white_before) : OrderedJson(nullptr);
    out["white_after"] = o.white_tested ? OrderedJson(o.white_after) : OrderedJson(nullptr);
    out["peak_psd_before"] = o.peak_psd_before;
    out["peak_psd_after"] = o.peak_psd_after;
    j["outputs"].push_back(std::move(out));
  }
  j["bands"] = OrderedJson::array();
  for (const auto& b : r.gap_bands) {
    j["bands"].push_back({{"name", b.name},
                          {"equations", b.equations},
                          {"lo_hz", b.lo_hz},
                          {"hi_hz", b.hi_hz},
                          {"before", b.before},
                          {"after", b.after},
                          {"wideband", b.wideband},
                          {"note", b.note}});
  }
  return j;
}

OrderedJson closed_loop_json(const DiscrepancyResult& r) {
  OrderedJson j = {{"note", r.closed_loop_note}, {"outputs", OrderedJson::array()}};
  for (const auto& c : r.closed_loop) {
    j["outputs"].push_back({{"output", c.output},
                            {"r2_before", c.r2_before},
                            {"r2_after", c.r2_after},
                            {"rmse_before", c.rmse_before},
                            {"rmse_after", c.rmse_after}});
  }
  return j;
}

/// Each pooled flight's own estimate of the named effects.
OrderedJson flight_json(const FlightEstimate& f) {
  return {{"source", f.source}, {"samples", f.samples},       {"start_s", f.start_s}, {"end_s", f.end_s},
          {"noise", f.noise},   {"parameters", f.parameters}, {"sigma", f.sigma}};
}

/// Whether a named effect is the same in all the pooled flights.
OrderedJson consistency_json(const FlightConsistency& c) {
  return {{"effect", c.effect},   {"q", c.q},       {"dof", c.dof},
          {"p_value", c.p_value}, {"same", c.same}, {"differs", c.differs}};
}

/// A model's parameter estimates: each value with its sigma, white and coloured.
OrderedJson parameters_json(const std::map<std::string, ParameterEstimate>& m) {
  OrderedJson j = OrderedJson::object();
  for (const auto& [name, e] : m) {
    j[name] = {{"value", e.value}, {"sigma", e.sigma}, {"sigma_coloured", e.sigma_coloured}};
  }
  return j;
}

/// Every flight's data-compatibility stage, every error tested.
OrderedJson compatibility_json(const CompatibilityResult& c) {
  OrderedJson j = {{"source", c.source}, {"ran", c.ran}};
  if (!c.ran) j["note"] = c.note;
  j["equation"] = c.equation;
  j["samples"] = c.samples;
  j["t_mid_s"] = c.t_mid_s;
  j["blocks"] = c.blocks;
  j["errors"] = OrderedJson::array();
  for (const SensorError& e : c.errors) {
    j["errors"].push_back({{"name", e.name},
                           {"channel", e.channel},
                           {"against", e.against},
                           {"unit", e.unit},
                           {"value", e.value},
                           {"sigma", e.sigma},
                           {"interval", interval_json(e.interval)},
                           {"tolerance", e.tolerance},
                           {"p_value", e.p_value},
                           {"significant", e.significant},
                           {"signature_holds", e.signature_holds},
                           {"signature", e.signature_note},
                           {"named", e.named},
                           {"corrected", e.corrected}});
  }
  j["kinematic_gap"] = {{"before", c.kinematic_gap_before}, {"after", c.kinematic_gap_after}};
  if (!c.rmse_uncorrected.empty()) j["rmse_uncorrected"] = c.rmse_uncorrected;
  j["corrections"] = c.corrections;
  return j;
}

/// A form of DiscrepancyOptions::test_terms, tested once.
OrderedJson term_test_json(const TermTest& t) {
  return {{"equation", t.equation},
          {"expression", t.expression},
          {"coefficient", t.coefficient},
          {"sigma", t.sigma},
          {"wald", t.wald},
          {"p_value", t.p_value},
          {"blocks", t.blocks},
          {"iv_coefficient", t.iv_coefficient},
          {"iv_sigma", t.iv_sigma},
          {"iv_p_value", t.iv_p_value},
          {"note", t.note}};
}

template <typename T, typename F>
OrderedJson array_of(const std::vector<T>& xs, F f) {
  OrderedJson a = OrderedJson::array();
  for (const auto& x : xs) a.push_back(f(x));
  return a;
}

}  // namespace

std::string discrepancy_json(const DiscrepancyResult& r) {
  require_finite_gap(r);
  OrderedJson j = {{"source", r.source},   {"model", r.model_name}, {"verdict", r.verdict}, {"summary", r.summary},
                   {"samples", r.samples}, {"rate_hz", r.rate_hz},  {"notes", r.notes}};
  j["effects"] = array_of(r.effects, effect_json);
  j["compatibility"] = array_of(r.compatibility, compatibility_json);
  j["term_tests"] = array_of(r.term_tests, term_test_json);
  j["ambiguous"] = r.ambiguous;
  j["candidates"] = array_of(r.candidates, candidate_json);
  j["alarm_rule"] = {{"p_critical", r.alarm_rule.p_critical},
                     {"tests", r.alarm_rule.tests},
                     {"family_wise", r.alarm_rule.family_wise}};
  j["located"] = located_json(r.located);
  j["gap"] = gap_json(r);
  j["closed_loop"] = closed_loop_json(r);
  j["flights"] = array_of(r.flights, flight_json);
  j["consistency"] = array_of(r.consistency, consistency_json);
  j["baseline"] = parameters_json(r.baseline);
  j["augmented"] = parameters_json(r.augmented);
  return json_line(j);
}

}  // namespace nimble::ident
