#include "loop/loop_report.h"

#include <cmath>
#include <filesystem>
#include <sstream>

#include "core/config.h"
#include "core/constants.h"

namespace nimble::loop {
namespace {

namespace fs = std::filesystem;

std::string or_none(const char* format, double x, const char* none = "none") {
  return std::isfinite(x) ? fmt(format, x) : std::string(none);
}

std::string pole_text(const LoopPole& p) {
  std::string s = fmt("%9.3f", p.s.real());
  if (std::abs(p.s.imag()) > 1e-9)
    s += fmt(" %+9.3fj", p.s.imag());
  else
    s += "           ";
  return s + fmt("   zeta %6.3f", p.damping) + fmt("   f_n %7.3f Hz", p.natural_hz);
}

}  // namespace

void WorstMargins::add(const std::string& name, const RollLoopAnalysis& a) {
  ++loops;
  const LoopMargins& m = a.margins;
  if (!m.closed_loop_stable) {
    if (unstable++ == 0) unstable_at = name;
    gain_margin_db = phase_margin_deg = delay_margin_ms = -INFINITY;
    gain_margin_at = phase_margin_at = delay_margin_at = unstable_at;
    return;
  }
  if (m.gain_margin_db() < gain_margin_db) gain_margin_db = m.gain_margin_db(), gain_margin_at = name;
  if (m.gain_reduction_margin_db() > gain_reduction_margin_db) {
    gain_reduction_margin_db = m.gain_reduction_margin_db();
    gain_reduction_margin_at = name;
  }
  if (std::isfinite(m.phase_margin_deg) && m.phase_margin_deg < phase_margin_deg) {
    phase_margin_deg = m.phase_margin_deg;
    phase_margin_at = name;
  }
  if (1e3 * m.delay_margin_s < delay_margin_ms) delay_margin_ms = 1e3 * m.delay_margin_s, delay_margin_at = name;
  if (m.sensitivity_peak > sensitivity_peak) sensitivity_peak = m.sensitivity_peak, sensitivity_peak_at = name;
}

std::string loop_header_text(const LoopSetup& s, const std::string& scenario) {
  std::ostringstream out;
  out << "rig loop  " << scenario << "\n";
  out << "  model   " << s.model.name << " (" << s.model.source << ")\n";
  out << fmt("  loop    roll at %g Hz with zero-order hold; ", s.controller.rate_hz)
      << fmt("latency %.3f ms", 1e3 * s.latency_s()) << " (" << s.clock << ", controller on the " << s.input
      << (s.clock == "realtime"
              ? (s.trigger == "state" ? ": each cycle started by its state, within the plant step"
                                      : ": on its own timer, up to one control period")
              : (s.input == "estimate" ? ": IMU -> estimator -> controller, one tick each" : ": none"))
      << (s.actuator_delay_s > 0.0 ? fmt("; plant actuator_delay %.3f ms", 1e3 * s.actuator_delay_s) : "") << ")\n";
  out << fmt("          PD -> %g Hz Butterworth -> ", s.controller.roll_lowpass_cutoff_hz)
      << fmt("delta_f_cmd = %g rad/s x cmd -> ", s.controller.roll_cmd_to_delta_f_radps)
      << fmt("flap %g/(s + ", s.flap_gain_per_s) << fmt("%g) -> lateral3\n", s.flap_pole_radps);
  out << "  linear: not in it the clip |cmd| <= 1 (|delta_f_cmd| <= "
      << fmt("%g", s.controller.roll_cmd_to_delta_f_radps) << " rad/s), the flapping-frequency limits "
      << fmt("%g", s.controller.flap_freq_min_radps) << ".." << fmt("%g", s.controller.flap_freq_max_radps)
      << " rad/s, sin(phi)";
  if (!s.nonlinear_effects.empty()) {
    out << "; plant effects on:";
    for (const auto& e : s.nonlinear_effects) out << " " << e;
  }
  out << "\n";
  return out.str();
}

std::string loop_text(const LoopRow& r) {
  const RollLoopAnalysis& a = r.analysis;
  const LoopMargins& m = a.margins;
  std::ostringstream out;
  out << "\n"
      << r.model << ", gains " << r.gains << fmt(" (kp %g 1/rad, ", r.gain_values.kp_per_rad)
      << fmt("kd %g s/rad), broken at ", r.gain_values.kd_per_radps)
      << (r.where == LoopBreak::kActuator ? "the actuator command" : "the measured " + to_string(r.where)) << "\n";
  out << fmt("  an angle error of %.1f deg alone saturates the command\n", a.saturation_error_rad * 180.0 / kPi);
  if (!m.closed_loop_stable) out << "  CLOSED LOOP UNSTABLE: no margins\n";
  out << "  gain margin        " << or_none("%+.2f dB", m.gain_margin_db())
      << or_none(" at %.3f Hz", m.gain_margin_hz, "") << ";  gain reduction margin "
      << or_none("%.2f dB", m.gain_reduction_margin_db(), "none (any lower gain is stable)")
      << or_none(" at %.3f Hz", m.gain_reduction_margin_hz, "") << "\n";
  out << "  phase margin       " << or_none("%.2f deg", m.phase_margin_deg)
      << or_none(" at %.3f Hz", m.crossover_hz, "") << "\n";
  out << "  delay margin       " << or_none("%.2f ms", 1e3 * m.delay_margin_s) << "\n";
  out << "  sensitivity peak   " << fmt("Ms %.3f", m.sensitivity_peak) << fmt(" at %.3f Hz", m.sensitivity_peak_hz)
      << "\n";
  out << fmt("  bandwidth          %.3f Hz phi/phi_ref", a.bandwidth_hz) << fmt(" (at 0 Hz %.3f), ", a.dc_gain)
      << fmt("%.3f Hz phi/set-point\n", a.setpoint_bandwidth_hz);
  out << "  closed-loop poles  s [1/s]\n";
  for (const LoopPole& p : a.poles) {
    if (p.s.imag() < -1e-9) continue;  // one line per pair
    out << "    " << pole_text(p);
    if (a.has_dominant_pair && p.z == a.dominant.z) out << "   dominant pair";
    out << "\n";
  }
  if (a.poles_at_origin > 0) out << "    (and " << a.poles_at_origin << " at z = 0: pure delays)\n";
  return out.str();
}

std::string loop_table_text(const std::vector<LoopRow>& rows) {
  std::ostringstream out;
  out << "\nmodel                 gains   break     GM[dB]  @[Hz]  GRM[dB]  PM[deg]  fc[Hz]  DM[ms]    Ms   BW[Hz]"
         "  dominant zeta  f_n[Hz]\n";
  for (const LoopRow& r : rows) {
    const RollLoopAnalysis& a = r.analysis;
    const LoopMargins& m = a.margins;
    std::string name = r.model;
    name.resize(22, ' ');
    std::string gains = r.gains;
    gains.resize(8, ' ');
    std::string brk = to_string(r.where);
    brk.resize(8, ' ');
    out << name << gains << brk;
    if (!m.closed_loop_stable) {
      out << "  CLOSED LOOP UNSTABLE\n";
      continue;
    }
    out << or_none("%8.2f", m.gain_margin_db(), "     inf") << or_none("%7.2f", m.gain_margin_hz, "      -")
        << or_none("%9.2f", m.gain_reduction_margin_db(), "     -inf")
        << or_none("%9.2f", m.phase_margin_deg, "        -") << or_none("%8.2f", m.crossover_hz, "       -")
        << or_none("%8.2f", 1e3 * m.delay_margin_s, "     inf") << fmt("%6.2f", m.sensitivity_peak)
        << fmt("%9.2f", a.bandwidth_hz);
    if (a.has_dominant_pair) out << fmt("  %13.3f", a.dominant.damping) << fmt("%9.3f", a.dominant.natural_hz);
    out << "\n";
  }
  return out.str();
}

std::string worst_text(const WorstMargins& w) {
  std::ostringstream out;
  out << "robustness " << w.gains << " over " << w.over << " (" << w.loops << " loops): ";
  if (w.unstable > 0) {
    out << w.unstable << " UNSTABLE (first: " << w.unstable_at << ")";
    std::string always;
    for (const auto& [key, count] : w.unstable_by_sign) {
      if (count == w.unstable && count <= w.loops / 2) always += " " + key;
    }
    if (!always.empty()) out << "; every unstable corner has" << always;
    out << "\n";
  } else {
    out << "all stable; worst GM " << or_none("%.2f dB", w.gain_margin_db, "inf") << " (" << w.gain_margin_at << "), "
        << "GRM " << or_none("%.2f dB", w.gain_reduction_margin_db, "-inf") << " (" << w.gain_reduction_margin_at
        << "), PM " << or_none("%.2f deg", w.phase_margin_deg) << " (" << w.phase_margin_at << "), "
        << "DM " << or_none("%.2f ms", w.delay_margin_ms, "inf") << " (" << w.delay_margin_at << "), "
        << fmt("Ms %.3f", w.sensitivity_peak) << " (" << w.sensitivity_peak_at << ")\n";
  }
  if (w.loops > 5) {
    out << "  one derivative at +-2 sigma, the others at the centre: ";
    if (w.unstable_alone.empty()) out << "all stable";
    for (std::size_t i = 0; i < w.unstable_alone.size(); ++i) out << (i ? ", " : "") << w.unstable_alone[i];
    out << (w.unstable_alone.empty() ? "\n" : " unstable\n");
  }
  return out.str();
}

std::string design_text(const DesignOutcome& d) {
  std::ostringstream out;
  out << "\ndesign on " << d.model << fmt(": phase margin %g deg", d.request.phase_margin_deg)
      << fmt(" at a %g Hz crossover\n", d.request.crossover_hz);
  if (!d.design.feasible) {
    out << "  NOT FEASIBLE: " << d.design.note << "\n";
    return out.str();
  }
  const LoopMargins& m = d.design.analysis.margins;
  out << "  gain set '" << d.name << fmt("': kp %.4f 1/rad, ", d.design.gains.kp_per_rad)
      << fmt("kd %.4f s/rad", d.design.gains.kd_per_radps) << fmt(", low-pass %g Hz", d.design.lowpass_cutoff_hz)
      << " (" << d.design.note << ")\n";
  out << "  reaches GM " << or_none("%.2f dB", m.gain_margin_db(), "inf") << ", PM "
      << or_none("%.2f deg", m.phase_margin_deg) << or_none(" at %.3f Hz", m.crossover_hz, "") << ", DM "
      << or_none("%.2f ms", 1e3 * m.delay_margin_s, "inf") << fmt(", Ms %.3f", m.sensitivity_peak)
      << fmt(", bandwidth %.3f Hz\n", d.design.analysis.bandwidth_hz);
  if (!d.flight.empty()) out << "  flown: " << d.flight << "\n";
  return out.str();
}

std::string design_yaml(const DesignOutcome& d, const std::string& command) {
  const LoopMargins& m = d.design.analysis.margins;
  std::ostringstream out;
  out << "# Roll gain set designed by: " << command << "\n";
  out << "# on model " << d.model << fmt(": phase margin %g deg", d.request.phase_margin_deg)
      << fmt(" at %g Hz asked; ", d.request.crossover_hz) << "reached GM "
      << or_none("%.2f dB", m.gain_margin_db(), "inf") << ", PM " << or_none("%.2f deg", m.phase_margin_deg)
      << or_none(" at %.3f Hz", m.crossover_hz, "") << ", DM " << or_none("%.2f ms", 1e3 * m.delay_margin_s, "inf")
      << fmt(", Ms %.3f", m.sensitivity_peak) << "\n";
  out << "# Keys of a controller file (rig_configs/controller/nimble_attitude.yaml): copy them into one, or\n"
      << "# fly them with --set controller.roll_gain_sets." << d.name << ".kp_per_rad=... (and kd_per_radps,\n"
      << "# lowpass.roll_cutoff_hz) and a manoeuvre that names the set.\n";
  out << "lowpass:\n" << fmt("  roll_cutoff_hz: %.6g\n", d.design.lowpass_cutoff_hz);
  out << "roll_gain_sets:\n  " << d.name << ":\n";
  out << fmt("    kp_per_rad: %.6g\n", d.design.gains.kp_per_rad);
  out << fmt("    kd_per_radps: %.6g\n", d.design.gains.kd_per_radps);
  return out.str();
}

}  // namespace nimble::loop
