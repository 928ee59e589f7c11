#pragma once
/// Flight records with one hidden form, for measuring the discrepancy workflow against the test
/// that knows the form (tests/ident/bench_discrepancy_oracle.cc). Written from the physics and
/// apart from discrepancy_generator.h, whose records the workflow's own suite was built on; these
/// differ in manoeuvres, controller and noise, so that a rule tuned to those records is not
/// right here by construction.
///
/// Plant: the linear lateral3 model (thesis Eqs 10-17, Eq 21's form) of a DerivativeModel,
///     p_dot   = Izz / Ic * L,   L = Lp p + Lv v + L_df delta_f + L_dt delta_t + L_w + (form)
///     v_dot   = Y / m + w0 p + g phi,   Y = Yp p + Yv v + Y_df delta_f + Y_dt delta_t + Y_w + (form)
///     phi_dot = p,   delta_f_dot = 8.97 cmd - 12.56 delta_f   (the flap actuator, thesis Eq 33)
/// integrated by RK4 at 2048 Hz and recorded at 512 Hz.
///
/// Manoeuvres (per record, by its seed): roll set-point manoeuvres at random times, each a
/// 3-2-1-1 multistep, a single doublet or a step held 0.3-1 s, pulse width 0.05-0.4 s, with hover
/// gaps of 0.5-3 s; amplitudes 5-20 deg except for 2-4 large ones of 25-40 deg, so that the
/// evidence of an effect at large rate or large flap input sits in a few seconds of the record,
/// as in a real flight. Throttle multisteps (3-2-1-1 or doublet, 1-3 %, pulses 0.1-0.5 s) at other
/// random times. Slow forward and vertical speed profiles (u 0-1.5 m/s, w -1..0.5 m/s, two
/// sinusoids of periods 8-30 s each), recorded as u and w; the lateral3 plant does not see them.
///
/// Controller: a digital roll PID at 512 Hz with zero-order hold, on the measured (noisy) states:
///     cmd = k_phi (phi_sp - phi_m) + k_i integral(phi_sp - phi_m) - k_p p_m
/// k_phi 55-95 rad/s per rad, k_p 10-18 rad/s per rad/s, k_i 5-25 rad/s per rad s (about half the
/// rig's fast gains through its roll map). The command computed at a tick reaches the actuator
/// half a period later (computation and link) and is held for one period: with the hold's own
/// half period, on average one controller period after it was issued, the latency
/// DiscrepancyOptions::command_latency_s assumes. The record's delta_f_cmd (every other record) is
/// the command when issued, without noise (it is digital).
///
/// Noise: process noise is a roll moment and a side force, each a first-order low-pass of white
/// noise (a Gauss-Markov process) with its corner drawn in 2-10 Hz and its standard deviation in
/// 0.5-2 x 1e-4 N m and 0.5-2 x 4e-3 N (below a few Hz about the level of the other generator's
/// white forcing). Measurement noise, white, each channel's level drawn as 0.5-3 times p
/// 0.01 rad/s, v 0.005 m/s, phi 0.002 rad, delta_f 0.2 rad/s, u and w 0.005 m/s. v is measured
/// directly (a motion-capture velocity, white noise), not differenced from a position.
///
/// Hidden forms (Hidden; `size` multiplies the reference magnitude, size 1, drawn per seed):
///   cubic_roll_damping   L += Lp3 p^3, Lp3 = -c |Lp| / (3 rad/s)^2, c 0.5-1.5: at 3 rad/s the
///                        cubic adds c times the linear damping (quadratic drag of the flapping
///                        wings' roll-induced velocity)
///   roll_stiffness       L += L_phi phi, L_phi = +-m g h, h 0.5-1.5 mm, sign drawn: a pendulum
///                        moment of the centre of mass h below (restoring) or above the point
///                        the thrust acts at
///   side_stiffness       Y += Y_phi phi, Y_phi = +-k m g, k 0.05-0.15, sign drawn: thrust off the
///                        weight by 5-15 % (climb, descent, a mis-stated mass) tilts a force the
///                        model's g phi does not hold
///   flap_rate_limit      the forces see ratelimit(delta_f, r) of the actuator state (the motors'
///                        rate limit), r = R / (1 + k size), k 0.5-1.5, R the largest
///                        |d delta_f / dt| of the same record flown without it: size 1 limits
///                        the fastest parts to 40-67 % of their rate, slow parts pass
///   flap_saturation      the forces see sat(delta_f, s) = clamp(delta_f, -s, s), s = D / (1 + k
///                        size), k 0.5-1.5, D the largest |delta_f| of the record flown without it
///   effectiveness_falls_with_rate   L_df and Y_df times (1 - c |p|), c = k / (5 rad/s), k 0.2-0.4:
///                        at 5 rad/s the flap input loses 20-40 % (the roll rate changes the
///                        wings' relative velocity); sizes where c |p| stays below 1
///   flap_asymmetry       the flap input 1 + a times as effective for delta_f > 0, a 0.15-0.35
///   flap_dead_zone       the forces see sign(d) max(|d| - z, 0), z 0.5-1.5 rad/s
///   roll_inflow_only     L += L_vo v|v|, L_vo -1e-3 .. -3e-3 N m s^2/m^2, no side force with it
///   inflow_other_arm     the lateral inflow, Y += Y_vv v|v|, L += L_vv v|v|, Y_vv -0.01 .. -0.03
///                        N s^2/m^2 (times size), at an arm L_vv / Y_vv of 0.03-0.05 m (not
///                        scaled): the library's lateral_inflow with its arm 3-5 times the plant
///                        file's 0.01 m
/// The recorded signals stay what a sensor sees: delta_f is the actuator's state, not what the
/// forces see through the form.
///
/// A record whose loop diverges (|phi| > 1.5 rad, |p| > 40 rad/s, |v| > 10 m/s or not finite) is
/// returned with Record::diverged set; the bench refuses it and counts it.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "core/model.h"
#include "core/term_expression.h"
#include "core/terms.h"
#include "core/vehicle.h"
#include "ident/flight_data.h"
#include "model_sets.h"

namespace nimble::ident::test_open {

/// A piecewise-constant signal: value v[k] from t[k] on (t increasing), 0 before t[0].
struct Schedule {
  std::vector<double> t, v;
  void add(double t0, double value) {
    t.push_back(t0);
    v.push_back(value);
  }
  double at(double time) const {
    const auto it = std::upper_bound(t.begin(), t.end(), time);
    return it == t.begin() ? 0.0 : v[static_cast<std::size_t>(it - t.begin()) - 1];
  }
};

/// Pulses of `widths` [s] from t0, alternating sign from `amplitude`, then back to 0; returns the end.
inline double add_pulses(Schedule& s, double t0, const std::vector<double>& widths, double amplitude) {
  double t = t0, sign = 1.0;
  for (double w : widths) {
    s.add(t, sign * amplitude);
    t += w;
    sign = -sign;
  }
  s.add(t, 0.0);
  return t;
}

/// Everything about a record except the hidden form, drawn from its seed.
struct Scenario {
  std::uint64_t seed = 0;
  double duration_s = 30.0;
  double rate_hz = 512.0;
  double k_phi = 75.0, k_p = 14.0, k_i = 15.0;
  double noise_p = 0.01, noise_v = 0.005, noise_phi = 0.002, noise_df = 0.2, noise_u = 0.005, noise_w = 0.005;
  double sigma_L = 1e-4, sigma_Y = 4e-3, corner_L_hz = 5.0, corner_Y_hz = 5.0;
  bool record_command = false;
  Schedule roll, throttle;
  int manoeuvres = 0, large_manoeuvres = 0;
  double u_period[2] = {10.0, 20.0}, u_phase[2] = {0.0, 0.0}, w_period[2] = {10.0, 20.0}, w_phase[2] = {0.0, 0.0};
  double u_at(double t) const {
    return 0.75 + 0.75 * (0.6 * std::sin(2.0 * M_PI * t / u_period[0] + u_phase[0]) +
                          0.4 * std::sin(2.0 * M_PI * t / u_period[1] + u_phase[1]));
  }
  double w_at(double t) const {
    return -0.25 + 0.75 * (0.6 * std::sin(2.0 * M_PI * t / w_period[0] + w_phase[0]) +
                           0.4 * std::sin(2.0 * M_PI * t / w_period[1] + w_phase[1]));
  }
};

/// The widths of one manoeuvre: kind 0 a 3-2-1-1, 1 a doublet, 2 a step held `hold` s.
inline std::vector<double> manoeuvre_widths(int kind, double width, double hold) {
  if (kind == 0) return {3.0 * width, 2.0 * width, width, width};
  if (kind == 1) return {width, width};
  return {hold};
}

/// Roll set-point manoeuvres at random times with hover gaps (see the file comment).
inline void draw_roll_manoeuvres(Scenario& sc, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  struct Plan {
    double t0, width, hold, sign;
    int kind;
  };
  std::vector<Plan> plans;
  double t = 1.0 + 1.5 * u01(rng);
  for (;;) {
    const double pick = u01(rng);
    Plan p{t, 0.05 + 0.35 * u01(rng), 0.3 + 0.7 * u01(rng), u01(rng) < 0.5 ? -1.0 : 1.0,
           pick < 0.35 ? 0 : (pick < 0.7 ? 1 : 2)};
    double length = 0.0;
    for (double w : manoeuvre_widths(p.kind, p.width, p.hold)) length += w;
    if (t + length > sc.duration_s - 1.5) break;
    plans.push_back(p);
    t += length + 0.5 + 2.5 * u01(rng);  // the hover gap after it
  }
  // A few large manoeuvres, the rest small.
  std::vector<std::size_t> order(plans.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::shuffle(order.begin(), order.end(), rng);
  const std::size_t large = std::min<std::size_t>(plans.size(), 2 + static_cast<std::size_t>(3.0 * u01(rng)));
  std::vector<char> is_large(plans.size(), 0);
  for (std::size_t i = 0; i < large; ++i) is_large[order[i]] = 1;
  for (std::size_t i = 0; i < plans.size(); ++i) {
    const double deg = is_large[i] ? 25.0 + 15.0 * u01(rng) : 5.0 + 15.0 * u01(rng);
    add_pulses(sc.roll, plans[i].t0, manoeuvre_widths(plans[i].kind, plans[i].width, plans[i].hold),
               plans[i].sign * deg * M_PI / 180.0);
  }
  sc.manoeuvres = static_cast<int>(plans.size());
  sc.large_manoeuvres = static_cast<int>(large);
}

/// Throttle multisteps [%] at random times (see the file comment).
inline void draw_throttle(Scenario& sc, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  double t = 0.5 + 3.0 * u01(rng);
  for (;;) {
    const double width = 0.1 + 0.4 * u01(rng), amplitude = (1.0 + 2.0 * u01(rng)) * (u01(rng) < 0.5 ? -1.0 : 1.0);
    const std::vector<double> widths = manoeuvre_widths(u01(rng) < 0.5 ? 0 : 1, width, 0.0);
    double length = 0.0;
    for (double w : widths) length += w;
    if (t + length > sc.duration_s - 1.0) break;
    t = add_pulses(sc.throttle, t, widths, amplitude) + 1.0 + 4.0 * u01(rng);
  }
}

/// Draws a record's manoeuvres, gains and noise from `seed`.
inline Scenario draw_scenario(std::uint64_t seed, double duration_s, bool record_command) {
  Scenario sc;
  sc.seed = seed;
  sc.duration_s = duration_s;
  sc.record_command = record_command;
  std::mt19937_64 rng(seed * 6364136223846793005ull + 1442695040888963407ull);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  sc.k_phi = 55.0 + 40.0 * u01(rng);
  sc.k_p = 10.0 + 8.0 * u01(rng);
  sc.k_i = 5.0 + 20.0 * u01(rng);
  auto level = [&](double base) { return base * (0.5 + 2.5 * u01(rng)); };
  sc.noise_p = level(0.01);
  sc.noise_v = level(0.005);
  sc.noise_phi = level(0.002);
  sc.noise_df = level(0.2);
  sc.noise_u = level(0.005);
  sc.noise_w = level(0.005);
  sc.sigma_L = 1e-4 * (0.5 + 1.5 * u01(rng));
  sc.sigma_Y = 4e-3 * (0.5 + 1.5 * u01(rng));
  sc.corner_L_hz = 2.0 + 8.0 * u01(rng);
  sc.corner_Y_hz = 2.0 + 8.0 * u01(rng);
  for (int k = 0; k < 2; ++k) {
    sc.u_period[k] = 8.0 + 22.0 * u01(rng);
    sc.w_period[k] = 8.0 + 22.0 * u01(rng);
    sc.u_phase[k] = 2.0 * M_PI * u01(rng);
    sc.w_phase[k] = 2.0 * M_PI * u01(rng);
  }
  draw_roll_manoeuvres(sc, rng);
  draw_throttle(sc, rng);
  return sc;
}

/// The hidden forms, each with the oracle's equation and expression (a number, where there is
/// one, written as %s), and the default size grid of the benchmark (placed by a pilot of the
/// oracle alone so that its power runs from under 50 % to 100 %).
struct FormSpec {
  const char* name;
  const char* equation;
  const char* expression;
  std::vector<double> sizes;
};

inline const std::vector<FormSpec>& form_specs() {
  static const std::vector<FormSpec> forms{
      {"cubic_roll_damping", "L", "p^3", {0.01, 0.03, 0.1, 0.3}},
      {"roll_stiffness", "L", "phi", {0.3, 1.0, 2.0, 4.0}},
      {"side_stiffness", "Y", "phi", {0.2, 0.5, 1.0, 2.0}},
      {"flap_rate_limit", "L", "ratelimit(delta_f, %s)", {0.3, 0.5, 1.0, 1.5}},
      {"flap_saturation", "L", "sat(delta_f, %s)", {0.03, 0.1, 0.3, 1.0}},
      {"effectiveness_falls_with_rate", "L", "abs(p)*delta_f", {0.2, 0.5, 1.0, 1.5}},
      {"flap_asymmetry", "L", "pos(delta_f)", {0.1, 0.2, 0.3, 1.0}},
      {"flap_dead_zone", "L", "deadzone(delta_f, %s)", {0.03, 0.1, 0.3, 1.0}},
      {"roll_inflow_only", "L", "v*abs(v)", {0.03, 0.1, 0.3, 1.0}},
      {"inflow_other_arm", "Y", "v*abs(v)", {0.2, 0.5, 1.0, 2.0}},
  };
  return forms;
}

inline const FormSpec* find_form(const std::string& name) {
  for (const FormSpec& f : form_specs())
    if (name == f.name) return &f;
  return nullptr;
}

/// One hidden form and its magnitudes (see the file comment); form empty: none.
struct Hidden {
  std::string form;
  double size = 1.0;
  double Lp3 = 0.0, L_phi = 0.0, Y_phi = 0.0, c_rate = 0.0, asym = 0.0, dead_zone = 0.0, L_vo = 0.0;
  double Y_vv = 0.0, L_vv = 0.0;
  double k_rate = 1.0, k_sat = 1.0;           ///< the rate limit's and saturation's factors k
  double rate_limit = 0.0, saturation = 0.0;  ///< r [rad/s per s], s [rad/s], from the record's references
};

/// Draws every form's magnitudes from `seed` (all of them, in a fixed order, so that a seed's
/// magnitudes do not depend on the form), times `size` where the file comment says so.
inline Hidden draw_hidden(const std::string& form, double size, std::uint64_t seed, const DerivativeModel& model,
                          const Vehicle& veh) {
  Hidden h;
  h.form = form;
  h.size = size;
  std::mt19937_64 rng(seed * 2862933555777941757ull + 3037000493ull);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  auto sign = [&]() { return u01(rng) < 0.5 ? -1.0 : 1.0; };
  const double mg = veh.mass_kg * veh.gravity_mps2;
  h.Lp3 = -(0.5 + u01(rng)) * std::fabs(model.at("Lp")) / 9.0 * size;
  h.L_phi = sign() * mg * (0.5e-3 + 1.0e-3 * u01(rng)) * size;
  h.Y_phi = sign() * mg * (0.05 + 0.10 * u01(rng)) * size;
  h.k_rate = 0.5 + u01(rng);
  h.k_sat = 0.5 + u01(rng);
  h.c_rate = (0.2 + 0.2 * u01(rng)) / 5.0 * size;
  h.asym = (0.15 + 0.20 * u01(rng)) * size;
  h.dead_zone = (0.5 + u01(rng)) * size;
  h.L_vo = -(1.0e-3 + 2.0e-3 * u01(rng)) * size;
  h.Y_vv = -(0.01 + 0.02 * u01(rng)) * size;
  h.L_vv = h.Y_vv * (0.03 + 0.02 * u01(rng));
  return h;
}

/// What a record flown without a form shows of the flap input: the references of the rate
/// limit and the saturation.
struct FlapReference {
  double max_rate = 0.0;  ///< largest |d delta_f / dt| of the actuator state [rad/s per s]
  double max_df = 0.0;    ///< largest |delta_f| [rad/s]
};

inline void resolve_references(Hidden& h, const FlapReference& ref) {
  h.rate_limit = ref.max_rate / (1.0 + h.k_rate * h.size);
  h.saturation = ref.max_df / (1.0 + h.k_sat * h.size);
}

/// Three significant digits, without an exponent (the grammar's numbers).
inline std::string three_digits(double x) {
  if (x == 0.0) return "0";
  const int mag = static_cast<int>(std::floor(std::log10(std::fabs(x))));
  const double q = std::pow(10.0, mag - 2);
  const double r = std::round(x / q) * q;
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", std::max(0, 2 - mag), r);
  return buf;
}

/// The oracle's equation and expression text for `h` (its number from h's magnitudes).
inline std::pair<std::string, std::string> oracle_text(const Hidden& h) {
  const FormSpec* f = find_form(h.form);
  if (!f) return {"", ""};
  std::string number;
  if (h.form == "flap_rate_limit") number = three_digits(h.rate_limit);
  if (h.form == "flap_saturation") number = three_digits(h.saturation);
  if (h.form == "flap_dead_zone") number = three_digits(h.dead_zone);
  std::string text = f->expression;
  const auto at = text.find("%s");
  if (at != std::string::npos) text.replace(at, 2, number);
  return {f->equation, text};
}

/// The oracle: the true form as a term to test (coefficient 0: the test estimates it).
/// @throws TermParseError if the grammar lacks the form's operator.
inline Term oracle_term(const Hidden& h) {
  const auto [eq, text] = oracle_text(h);
  return Term{eq, TermExpression::parse(text), 0.0, ""};
}

/// The lateral3 plant with a hidden form.
struct Plant {
  double Lp = 0, Lv = 0, L_df = 0, L_dt = 0, Yp = 0, Yv = 0, Y_df = 0, Y_dt = 0;
  double w0 = 0, m = 1, g = 9.81, Izz_Ic = 1;
  Hidden h;

  Plant(const DerivativeModel& model, const Vehicle& veh, Hidden hidden) : h(std::move(hidden)) {
    Lp = model.at("Lp"), Lv = model.at("Lv"), L_df = model.at("L_df"), Yp = model.at("Yp"), Yv = model.at("Yv");
    Y_df = model.at("Y_df");
    L_dt = model.derivatives.count("L_dt") ? model.at("L_dt") : 0.0;
    Y_dt = model.derivatives.count("Y_dt") ? model.at("Y_dt") : 0.0;
    w0 = model.trim.w0_mps;
    m = veh.mass_kg, g = veh.gravity_mps2, Izz_Ic = veh.Izz_kgm2 / veh.Ic();
  }
  bool is(const char* form) const { return h.form == form; }

  /// The flap input the forces see, from the actuator state df (and the rate limiter's output).
  double flap_input(double df, double df_limited) const {
    if (is("flap_rate_limit")) return df_limited;
    if (is("flap_saturation")) return std::clamp(df, -h.saturation, h.saturation);
    if (is("flap_asymmetry") && df > 0.0) return (1.0 + h.asym) * df;
    if (is("flap_dead_zone")) return std::copysign(std::max(std::fabs(df) - h.dead_zone, 0.0), df);
    return df;
  }

  /// State x = (p, v, phi, delta_f); the command, throttle and disturbances held over the step.
  void deriv(const double* x, double cmd, double dt_pct, double Lw, double Yw, double df_limited, double* dx) const {
    const double P = x[0], V = x[1], PHI = x[2], DF = x[3];
    const double din = flap_input(DF, df_limited);
    const double eff = is("effectiveness_falls_with_rate") ? 1.0 - h.c_rate * std::fabs(P) : 1.0;
    double L = Lp * P + Lv * V + eff * L_df * din + L_dt * dt_pct + Lw;
    double Y = Yp * P + Yv * V + eff * Y_df * din + Y_dt * dt_pct + Yw;
    if (is("cubic_roll_damping")) L += h.Lp3 * P * P * P;
    if (is("roll_stiffness")) L += h.L_phi * PHI;
    if (is("side_stiffness")) Y += h.Y_phi * PHI;
    if (is("roll_inflow_only")) L += h.L_vo * V * std::fabs(V);
    if (is("inflow_other_arm")) {
      L += h.L_vv * V * std::fabs(V);
      Y += h.Y_vv * V * std::fabs(V);
    }
    dx[0] = Izz_Ic * L;
    dx[1] = Y / m + w0 * P + g * PHI;
    dx[2] = P;
    dx[3] = 8.97 * cmd - 12.56 * DF;
  }
};

/// A generated record.
struct Record {
  FlightData data;
  Hidden hidden;
  Scenario scenario;
  FlapReference reference;  ///< of this flight (with its form)
  double max_p = 0.0;       ///< largest |p| [rad/s]
  bool diverged = false;
};

/// Appends one sample of every recorded channel at t.
struct Recorder {
  FlightData& d;
  double t;
  void operator()(const char* channel, double value) const {
    Channel& c = d.channels[channel];
    c.t_s.push_back(t);
    c.values.push_back(value);
  }
};

/// Flies `sc` with `plant` (see the file comment).
inline Record fly(const Plant& plant, const Scenario& sc) {
  Record rec;
  rec.hidden = plant.h;
  rec.scenario = sc;
  FlightData& d = rec.data;
  d.source = "generated (open suite, seed " + std::to_string(sc.seed) + ")";
  for (const char* c : {"p", "v", "phi", "u", "w", "delta_f", "delta_t", "phi_sp"}) d.channels[c];
  if (sc.record_command) d.channels["delta_f_cmd"];
  const int sub = 4;
  const double dtc = 1.0 / sc.rate_hz, dt = dtc / sub;
  // Separate streams: the measurement and process noise are the same for a seed whatever the form.
  std::mt19937_64 meas(sc.seed * 0x9E3779B97F4A7C15ull + 11u), proc(sc.seed * 0xBF58476D1CE4E5B9ull + 29u);
  std::normal_distribution<double> n01(0.0, 1.0);
  const double aL = std::exp(-2.0 * M_PI * sc.corner_L_hz * dt), aY = std::exp(-2.0 * M_PI * sc.corner_Y_hz * dt);
  double Lw = sc.sigma_L * n01(proc), Yw = sc.sigma_Y * n01(proc);
  double x[4] = {0.0, 0.0, 0.0, 0.0};
  double df_limited = 0.0, integral = 0.0, cmd_held = 0.0, cmd_next = 0.0;
  const long ticks = static_cast<long>(std::lround(sc.duration_s * sc.rate_hz));
  for (long k = 0; k <= ticks; ++k) {
    const double tk = static_cast<double>(k) * dtc;
    // Measure, record, and run the controller on the measurements.
    const double p_m = x[0] + sc.noise_p * n01(meas), v_m = x[1] + sc.noise_v * n01(meas);
    const double phi_m = x[2] + sc.noise_phi * n01(meas), df_m = x[3] + sc.noise_df * n01(meas);
    const double u_m = sc.u_at(tk) + sc.noise_u * n01(meas), w_m = sc.w_at(tk) + sc.noise_w * n01(meas);
    const double sp = sc.roll.at(tk), e = sp - phi_m;
    integral += e * dtc;
    cmd_held = cmd_next;  // issued at the previous tick, held until half this period is over
    cmd_next = sc.k_phi * e + sc.k_i * integral - sc.k_p * p_m;
    const Recorder r{d, tk};
    r("p", p_m);
    r("v", v_m);
    r("phi", phi_m);
    r("u", u_m);
    r("w", w_m);
    r("delta_f", df_m);
    r("delta_t", sc.throttle.at(tk));
    r("phi_sp", sp);
    if (sc.record_command) r("delta_f_cmd", cmd_next);
    if (k == ticks) break;
    for (int j = 0; j < sub; ++j) {
      const double t = tk + j * dt, thr = sc.throttle.at(t);
      const double cmd_applied = 2 * j < sub ? cmd_held : cmd_next;
      // The rate limiter at the step's start: the actuator state clamped to r dt of its last output.
      if (plant.is("flap_rate_limit")) {
        const double step = plant.h.rate_limit * dt;
        df_limited = std::clamp(x[3], df_limited - step, df_limited + step);
      }
      double k1[4], k2[4], k3[4], k4[4], tmp[4];
      plant.deriv(x, cmd_applied, thr, Lw, Yw, df_limited, k1);
      for (int i = 0; i < 4; ++i) tmp[i] = x[i] + 0.5 * dt * k1[i];
      plant.deriv(tmp, cmd_applied, thr, Lw, Yw, df_limited, k2);
      for (int i = 0; i < 4; ++i) tmp[i] = x[i] + 0.5 * dt * k2[i];
      plant.deriv(tmp, cmd_applied, thr, Lw, Yw, df_limited, k3);
      for (int i = 0; i < 4; ++i) tmp[i] = x[i] + dt * k3[i];
      plant.deriv(tmp, cmd_applied, thr, Lw, Yw, df_limited, k4);
      for (int i = 0; i < 4; ++i) x[i] += dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
      rec.reference.max_rate = std::max(rec.reference.max_rate, std::fabs(k1[3]));
      rec.reference.max_df = std::max(rec.reference.max_df, std::fabs(x[3]));
      rec.max_p = std::max(rec.max_p, std::fabs(x[0]));
      // The disturbances: first-order Gauss-Markov, stationary from the start.
      Lw = aL * Lw + sc.sigma_L * std::sqrt(1.0 - aL * aL) * n01(proc);
      Yw = aY * Yw + sc.sigma_Y * std::sqrt(1.0 - aY * aY) * n01(proc);
    }
    const bool finite = std::isfinite(x[0]) && std::isfinite(x[1]) && std::isfinite(x[2]) && std::isfinite(x[3]);
    if (!finite || std::fabs(x[2]) > 1.5 || std::fabs(x[0]) > 40.0 || std::fabs(x[1]) > 10.0) {
      rec.diverged = true;
      return rec;
    }
  }
  return rec;
}

/// Generates a record of `form` (empty: none) at `size` from `seed`: the scenario, the form's
/// magnitudes, and for the rate limit and saturation their references from the same record
/// flown without the form (the same manoeuvres and noise). `change`, if given, edits the drawn
/// scenario first (a diagnostic: another noise, say).
inline Record generate(const std::string& form, double size, std::uint64_t seed, double duration_s, bool record_command,
                       const DerivativeModel& model, const Vehicle& veh,
                       const std::function<void(Scenario&)>& change = nullptr) {
  Scenario sc = draw_scenario(seed, duration_s, record_command);
  if (change) change(sc);
  Hidden h = draw_hidden(form, size, seed, model, veh);
  if (form == "flap_rate_limit" || form == "flap_saturation") {
    const Record nominal = fly(Plant(model, veh, Hidden{}), sc);
    if (nominal.diverged) return nominal;
    resolve_references(h, nominal.reference);
  }
  return fly(Plant(model, veh, h), sc);
}

/// The model sets the records are flown with (tests/ident/model_sets.h).
using test::model_set;
using test::ModelSet;

}  // namespace nimble::ident::test_open
