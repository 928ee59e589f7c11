// The JSON report of `rig loop` (loop/loop_report.h, loop_json()): each part with its function
// over nlohmann::ordered_json (keys in the order written, numbers as the shortest text that reads
// back to the same double, a non-finite number as null). The keys and their order are the
// report's format (docs/loop.md).

#include "loop/loop_report.h"
#include "core/json_line.h"

namespace nimble::loop {
namespace {

OrderedJson pole_json(const LoopPole& p) {
  return {{"re", p.s.real()}, {"im", p.s.imag()}, {"damping", p.damping}, {"natural_hz", p.natural_hz}};
}

/// A loop's margins, bandwidths and closed-loop poles, into `j`.
void add_margins(OrderedJson& j, const RollLoopAnalysis& a) {
  const LoopMargins& m = a.margins;
  j["closed_loop_stable"] = m.closed_loop_stable;
  j["open_loop_stable"] = m.open_loop_stable;
  j["gain_margin_db"] = m.gain_margin_db();
  j["gain_margin_hz"] = m.gain_margin_hz;
  j["gain_reduction_margin_db"] = m.gain_reduction_margin_db();
  j["gain_reduction_margin_hz"] = m.gain_reduction_margin_hz;
  j["phase_margin_deg"] = m.phase_margin_deg;
  j["crossover_hz"] = m.crossover_hz;
  j["crossovers_hz"] = m.crossovers_hz;
  j["delay_margin_ms"] = 1e3 * m.delay_margin_s;
  j["sensitivity_peak"] = m.sensitivity_peak;
  j["sensitivity_peak_hz"] = m.sensitivity_peak_hz;
  j["bandwidth_hz"] = a.bandwidth_hz;
  j["setpoint_bandwidth_hz"] = a.setpoint_bandwidth_hz;
  j["dc_gain"] = a.dc_gain;
  j["dominant_pair"] = a.has_dominant_pair ? pole_json(a.dominant) : OrderedJson(nullptr);
  j["closed_loop_poles"] = OrderedJson::array();
  for (const LoopPole& p : a.poles) j["closed_loop_poles"].push_back(pole_json(p));
  j["poles_at_origin"] = a.poles_at_origin;
}

OrderedJson worst_json(const WorstMargins& x) {
  return {{"gains", x.gains},
          {"over", x.over},
          {"loops", x.loops},
          {"unstable", x.unstable},
          {"unstable_at", x.unstable_at},
          {"gain_margin_db", x.gain_margin_db},
          {"gain_margin_at", x.gain_margin_at},
          {"gain_reduction_margin_db", x.gain_reduction_margin_db},
          {"gain_reduction_margin_at", x.gain_reduction_margin_at},
          {"phase_margin_deg", x.phase_margin_deg},
          {"phase_margin_at", x.phase_margin_at},
          {"delay_margin_ms", x.delay_margin_ms},
          {"delay_margin_at", x.delay_margin_at},
          {"sensitivity_peak", x.sensitivity_peak},
          {"sensitivity_peak_at", x.sensitivity_peak_at},
          {"unstable_alone", x.unstable_alone}};
}

OrderedJson design_json(const DesignOutcome& d) {
  OrderedJson j = {{"model", d.model},
                   {"name", d.name},
                   {"phase_margin_deg_requested", d.request.phase_margin_deg},
                   {"crossover_hz_requested", d.request.crossover_hz},
                   {"feasible", d.design.feasible},
                   {"note", d.design.note},
                   {"kp_per_rad", d.design.gains.kp_per_rad},
                   {"kd_per_radps", d.design.gains.kd_per_radps},
                   {"lowpass_cutoff_hz", d.design.lowpass_cutoff_hz}};
  if (d.design.feasible) add_margins(j, d.design.analysis);
  if (!d.flight.empty()) {
    j["flight"] = d.flight;
    j["flight_exit_code"] = d.flight_exit;
  }
  return j;
}

}  // namespace

std::string loop_json(const LoopSetup& s, const std::vector<LoopRow>& rows, const std::vector<WorstMargins>& worst,
                      const DesignOutcome* design) {
  OrderedJson j = {{"scenario", s.scenario_file},
                   {"input", s.input},
                   {"clock", s.clock},
                   {"latency_s", s.latency_s()},
                   {"actuator_delay_s", s.actuator_delay_s},
                   {"rate_hz", s.controller.rate_hz},
                   {"lowpass_cutoff_hz", s.controller.roll_lowpass_cutoff_hz}};
  j["loops"] = OrderedJson::array();
  for (const LoopRow& r : rows) {
    OrderedJson loop = {{"model", r.model},
                        {"gains", r.gains},
                        {"break", to_string(r.where)},
                        {"kp_per_rad", r.gain_values.kp_per_rad},
                        {"kd_per_radps", r.gain_values.kd_per_radps}};
    add_margins(loop, r.analysis);
    j["loops"].push_back(std::move(loop));
  }
  j["robustness"] = OrderedJson::array();
  for (const WorstMargins& x : worst) j["robustness"].push_back(worst_json(x));
  if (design) j["design"] = design_json(*design);
  return json_line(j);
}

}  // namespace nimble::loop
