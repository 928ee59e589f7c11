#pragma once
/// Flight records with a hidden effect, for the discrepancy workflow's tests and benchmark.
/// Independent of the plant code: the linear lateral3 model (thesis Eqs 10-17) written out
/// here, flown by a roll PD law through the Eq 33 flap actuator on a doublet train, with
/// throttle doublets, a vertical and a forward velocity that the record carries (w, u), and
/// at most a few effects added to the model's forces and moments. RK4 at 2048 Hz, recorded
/// at 512 Hz with measurement noise; process noise enters as white force and moment.
///
/// Effects and the physical ranges their magnitudes are drawn from (by the seed):
///   lateral_inflow        Y += Y_vv v|v|, L += L_vv v|v|; Y_vv in [-0.03, -0.01] N s^2/m^2,
///                         L_vv = Y_vv * 0.01 m (the plant file's ratio)
///   kinematic_coupling    m v_dot += m p (w - w0) (the exact kinematics instead of Eq 21's w0 p)
///   forward_speed_coupling  Lp, Lv, Yp, Yv scale with (1 + k (u - u0)), k in [0.3, 0.7] per m/s
///   actuator_delay        the flap input acts tau later than recorded, tau in [12, 40] ms
///   sensor_bias           the recorded p carries a constant bias b in [0.02, 0.06] rad/s
///   constant_load         L += L0, Y += Y0: a constant roll moment and side force (an offset
///                         trim), L0 in [1, 3] x 1e-5 N m, Y0 = 50 m^-1 L0; p is not biased
///   flapping_forcing      L += A_L (sin(2 pi f t + a) + 0.5 sin(4 pi f t + b)), Y likewise with A_Y;
///                         f in [14, 20] Hz, A_L in [1, 3] mN m, A_Y = 5 m^-1 A_L (the plant
///                         file's 2 mN m and 10 mN)
///   dihedral_coupling     a dihedral input delta_d (a smooth random signal, 0.05 rad) acts with
///                         L_dd, Y_dd of thesis Table B.2; recorded as channel delta_d
///   yaw_alias             (with dihedral_coupling) the record also carries a yaw rate r that
///                         follows delta_d (r = 2 delta_d + 1 % noise): two candidates that
///                         explain the same thing
///   lateral_gust          the aerodynamics see v - v_g, v_g first-order Gauss-Markov,
///                         sigma 0.1 m/s, tau 0.5 s (stochastic: no deterministic name)
///   command_delay         the flap actuator receives the controller's command tau late (a link
///                         or motor-driver delay: the plant's actuator_delay), tau in [12, 40] ms;
///                         the recorded delta_f is the actuator's output, so only the recorded
///                         command (GeneratorOptions::record_command) shows it
///   effectiveness_drift   L_df and Y_df scale with 1 + r t / 60 (t from the record's start):
///                         battery sag, r in [-0.08, -0.02] per minute (a one-cell LiPo sags
///                         about 17 % over a flight of a few minutes)
///   effectiveness_step    L_df and Y_df change by the fraction f from t* on: a damaged wing,
///                         f in [-0.40, -0.15], t* in the middle 60 % of the record
///
/// The sensors' own errors (the data-compatibility stage, discrepancy/data_compatibility.h): the
/// dynamics are untouched, only the recorded gyro channel p differs from the truth:
///   sensor_scale          p recorded as (1 + k) p, |k| in [0.05, 0.15], either sign
///   time_offset           p recorded tau late (its sample of t - tau stamped t; tau < 0: early),
///                         |tau| in [10, 50] ms, either sign: the IMU's clock against the motion capture
///   clock_drift           the IMU's clock runs fast or slow: p recorded tau(t) = d (t - T/2) late
///                         (T the record's length; with time_offset, tau + d (t - T/2)), |d| in
///                         [100, 500] ppm, either sign (assumption: separate devices' crystals)
///
/// Forms that are NOT library effects (the out-of-library suite, test_discrepancy_outside.cc): no
/// candidate of discrepancy/discrepancy.h has their signature, so a library name given to them is a
/// wrong name. Magnitudes drawn by the seed from the ranges below:
///   flap_asymmetry        the flap input is 1 + a times as effective for delta_f > 0 as for
///                         delta_f < 0 (L and Y alike), a in [0.25, 0.45]
///   cubic_roll_damping    L += Lp3 p^3, Lp3 = -c |Lp| / (2 rad/s)^2, c in [0.5, 1.5]: at
///                         2 rad/s the cubic term adds c times the linear damping
///   flap_dead_zone        the flap input acts as sign(d) max(|d| - z, 0), z in [1, 3] rad/s (the
///                         flap input's RMS on these records is about 9 rad/s)
///   flap_backlash         the flap input acts through a backlash (play) of total width b in
///                         [2, 6] rad/s: the acting value follows d only once |d - acting| > b / 2
///   flap_lag              the flap input acts through a first-order lag 1 / (tau s + 1), tau in
///                         [10, 40] ms (a lag, not a pure delay)
///   roll_inflow_only      L += L_vo v|v| with no side-force counterpart, L_vo in [-4e-3,
///                         -1e-3] N m s^2/m^2 (lateral_inflow predicts Y_vv as well)
///
/// With GeneratorOptions::record_command the record carries the controller's command as
/// channel delta_f_cmd, sampled when it is issued (no measurement noise: it is digital).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <deque>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "core/model.h"
#include "core/vehicle.h"
#include "ident/flight_data.h"
#include "model_sets.h"

namespace nimble::ident::test {

struct HiddenEffects {
  std::set<std::string> on;  ///< effect names (see the file comment)
  double scale = 1.0;        ///< multiplies every drawn magnitude (small effects: << 1)
  double Y_vv = 0.0, L_vv = 0.0, k_speed = 0.0, delay_s = 0.0, bias_p = 0.0;
  double flap_hz = 17.0, flap_L = 0.0, flap_Y = 0.0, flap_phase1 = 0.0, flap_phase2 = 0.0;
  double drift_per_min = 0.0;  ///< effectiveness_drift: r [1/min]
  double step_fraction = 0.0;  ///< effectiveness_step: f
  double step_at = 0.5;        ///< effectiveness_step: t* as a fraction of the record's length
  // Out-of-library forms (see the file comment).
  double asym = 0.0;                  ///< flap_asymmetry: a
  double cubic_c = 0.0;               ///< cubic_roll_damping: c
  double dead_zone = 0.0;             ///< flap_dead_zone: z [rad/s]
  double backlash = 0.0;              ///< flap_backlash: b [rad/s]
  double lag_s = 0.0;                 ///< flap_lag: tau [s]
  double L_vv_only = 0.0;             ///< roll_inflow_only: L_vo [N m s^2/m^2]
  double load_L = 0.0, load_Y = 0.0;  ///< constant_load: L0 [N m], Y0 [N]
  double scale_k = 0.0;               ///< sensor_scale: k
  double offset_s = 0.0;              ///< time_offset: tau [s]
  double drift_ppm = 0.0;             ///< clock_drift: d [ppm]
};

struct GeneratorOptions {
  double duration_s = 40.0;
  double rate_hz = 512.0;
  double doublet_amplitude_rad = 0.6;  ///< 34 deg, the rig's identification doublet (35 deg)
  /// PD on the roll error [rad/s per rad, per rad/s]: half the rig's fast gains through the
  /// roll map (1.406 and 0.2 per unit times 125 rad/s), so that the loop stays stable with the
  /// 40 ms delays the generator hides.
  double k_phi = 80.0, k_p = 15.0;
  double throttle_amplitude_pct = 2.0;
  double moment_noise_Nm = 1e-3, force_noise_N = 0.04;  ///< per 2048 Hz step, white
  double noise_p = 0.01, noise_v = 0.005, noise_phi = 0.002, noise_df = 0.2, noise_w = 0.005;
  std::uint64_t seed = 1;
  bool record_command = false;  ///< record delta_f_cmd (the actuator's input as commanded)
};

/// Draws the magnitudes of `h.on` from their ranges (see the file comment) with `seed`.
inline void draw_magnitudes(HiddenEffects& h, std::uint64_t seed) {
  std::mt19937_64 rng(seed * 7919 + 17);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  h.Y_vv = -(0.01 + 0.02 * u01(rng)) * h.scale;
  h.L_vv = h.Y_vv * 0.01;
  h.k_speed = (0.3 + 0.4 * u01(rng)) * h.scale;
  h.delay_s = (0.012 + 0.028 * u01(rng)) * h.scale;
  h.bias_p = (0.02 + 0.04 * u01(rng)) * h.scale;
  h.flap_hz = 14.0 + 6.0 * u01(rng);
  h.flap_L = (1e-3 + 2e-3 * u01(rng)) * h.scale;
  h.flap_Y = 5.0 * h.flap_L;
  h.flap_phase1 = 2.0 * M_PI * u01(rng);
  h.flap_phase2 = 2.0 * M_PI * u01(rng);
  h.drift_per_min = -(0.02 + 0.06 * u01(rng)) * h.scale;
  h.step_fraction = -(0.15 + 0.25 * u01(rng)) * h.scale;
  h.step_at = 0.2 + 0.6 * u01(rng);
  // Drawn after the library effects' magnitudes, so that those stay what they were for a seed.
  h.asym = (0.25 + 0.20 * u01(rng)) * h.scale;
  h.cubic_c = (0.5 + 1.0 * u01(rng)) * h.scale;
  h.dead_zone = (1.0 + 2.0 * u01(rng)) * h.scale;
  h.backlash = (2.0 + 4.0 * u01(rng)) * h.scale;
  h.lag_s = (0.010 + 0.030 * u01(rng)) * h.scale;
  h.L_vv_only = -(1.0e-3 + 3.0e-3 * u01(rng)) * h.scale;
  h.load_L = (1.0e-5 + 2.0e-5 * u01(rng)) * h.scale;
  h.load_Y = 50.0 * h.load_L;
  // The sensors' errors, drawn last for the same reason.
  h.scale_k = (u01(rng) < 0.5 ? -1.0 : 1.0) * (0.05 + 0.10 * u01(rng)) * h.scale;
  h.offset_s = (u01(rng) < 0.5 ? -1.0 : 1.0) * (0.010 + 0.040 * u01(rng)) * h.scale;
  h.drift_ppm = (u01(rng) < 0.5 ? -1.0 : 1.0) * (100.0 + 400.0 * u01(rng)) * h.scale;
}

/// Simulates the record. Channels: t, p, v, phi, u, w, delta_f, delta_t, phi_sp.
inline FlightData generate_flight(const DerivativeModel& model, const Vehicle& veh, const HiddenEffects& h,
                                  const GeneratorOptions& o) {
  const double m = veh.mass_kg, g = veh.gravity_mps2, Ic = veh.Ic(), Izz = veh.Izz_kgm2;
  const double Lp = model.at("Lp"), Lv = model.at("Lv"), Yp = model.at("Yp"), Yv = model.at("Yv");
  const double L_df = model.at("L_df"), Y_df = model.at("Y_df");
  const double L_dt = model.derivatives.count("L_dt") ? model.at("L_dt") : 0.0;
  const double Y_dt = model.derivatives.count("Y_dt") ? model.at("Y_dt") : 0.0;
  const double w0 = model.trim.w0_mps;
  const bool inflow = h.on.count("lateral_inflow") > 0, kin = h.on.count("kinematic_coupling") > 0;
  const bool speed = h.on.count("forward_speed_coupling") > 0, delay = h.on.count("actuator_delay") > 0;
  const bool bias = h.on.count("sensor_bias") > 0, gust = h.on.count("lateral_gust") > 0;
  const bool flap = h.on.count("flapping_forcing") > 0;
  const bool dihedral = h.on.count("dihedral_coupling") > 0, yaw_alias = h.on.count("yaw_alias") > 0;
  const bool cmd_delay = h.on.count("command_delay") > 0;
  const bool drift = h.on.count("effectiveness_drift") > 0, step = h.on.count("effectiveness_step") > 0;
  const bool asym = h.on.count("flap_asymmetry") > 0, cubic = h.on.count("cubic_roll_damping") > 0;
  const bool dead_zone = h.on.count("flap_dead_zone") > 0, backlash = h.on.count("flap_backlash") > 0;
  const bool lag = h.on.count("flap_lag") > 0, roll_inflow_only = h.on.count("roll_inflow_only") > 0;
  const bool load = h.on.count("constant_load") > 0;
  const bool scale_err = h.on.count("sensor_scale") > 0, drift_err = h.on.count("clock_drift") > 0;
  const bool offset_err = h.on.count("time_offset") > 0 || drift_err;
  std::vector<double> p_true;  // every step's p, for a recorded p off in time (time_offset)
  const double Lp3 = -h.cubic_c * std::fabs(Lp) / 4.0;
  // The flap input's effectiveness at time t (effectiveness_drift, effectiveness_step).
  auto effectiveness = [&](double t) {
    double k = 1.0;
    if (drift) k *= 1.0 + h.drift_per_min * t / 60.0;
    if (step && t >= h.step_at * o.duration_s) k *= 1.0 + h.step_fraction;
    return k;
  };
  const double L_dd = 1.20e-3, Y_dd = -5.41e-2;  // thesis Table B.2
  double ph_d = 0.0;  // drawn below (only when the dihedral acts, so other records keep their noise)
  auto dd_of = [&](double t) {
    return 0.05 * (0.6 * std::sin(2.0 * M_PI * 0.7 * t + ph_d) + 0.4 * std::sin(2.0 * M_PI * 2.3 * t + 2.0 * ph_d));
  };

  const int sub = 4;
  const double dt = 1.0 / (o.rate_hz * sub);
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  if (dihedral) ph_d = 2.0 * M_PI * std::uniform_real_distribution<double>(0.0, 1.0)(rng);

  // Manoeuvres: roll doublets of 7, 4 and 2 Hz every 2.5 s; throttle doublets at 1.5 Hz
  // every 3.7 s; w and u follow slow smooth profiles (climb/descent, forward flight).
  auto phi_sp = [&](double t) {
    const double period = 2.5, start = 1.0;
    if (t < start || t > o.duration_s - 2.0) return 0.0;
    const double k = std::floor((t - start) / period);
    const double f = (static_cast<int>(k) % 3 == 0) ? 7.0 : (static_cast<int>(k) % 3 == 1 ? 4.0 : 2.0);
    const double tau = t - start - k * period;
    const double a = o.doublet_amplitude_rad * ((static_cast<int>(k) % 2) ? -1.0 : 1.0);
    if (tau < 0.5 / f) return a;
    if (tau < 1.0 / f) return -a;
    return 0.0;
  };
  auto throttle = [&](double t) {
    const double tau = std::fmod(t + 0.8, 3.7);
    if (tau < 1.0 / 3.0) return o.throttle_amplitude_pct;
    if (tau < 2.0 / 3.0) return -o.throttle_amplitude_pct;
    return 0.0;
  };
  const double ph_w = 2.0 * M_PI * std::uniform_real_distribution<double>(0.0, 1.0)(rng);
  auto w_of = [&](double t) {
    return w0 - 0.6 * std::sin(2.0 * M_PI * t / 13.0 + ph_w) - 0.3 * std::sin(2.0 * M_PI * t / 5.3);
  };
  auto u_of = [&](double t) { return 0.6 + 0.6 * std::sin(2.0 * M_PI * t / 11.0 + ph_w); };

  // State: p, v, phi, delta_f, v_gust.
  double p = 0, v = 0, phi = 0, df = 0, vg = 0;
  double df_play = 0.0, df_lagged = 0.0;  // flap_backlash's acting value, flap_lag's state
  const double a_lag = lag ? 1.0 - std::exp(-dt / h.lag_s) : 1.0;
  std::deque<std::pair<double, double>> df_hist;  // (t, df) for the delayed input
  auto df_at = [&](double t) {
    if (!delay) return df;
    const double td = t - h.delay_s;
    double val = 0.0;
    for (const auto& [ti, di] : df_hist) {
      if (ti <= td)
        val = di;
      else
        break;
    }
    return val;
  };
  auto command = [&](double t, double P, double PHI) { return o.k_phi * (phi_sp(t) - PHI) - o.k_p * P; };
  // With a command delay the actuator gets the command issued at the start of each step, held
  // over it (2048 Hz) and tau late; otherwise the command acts continuously.
  std::deque<std::pair<double, double>> cmd_hist;
  double cmd_held = 0.0;
  auto deriv = [&](double t, const double* x, double dfin, double Lw, double Yw, double* dx) {
    const double P = x[0], V = x[1], PHI = x[2], DF = x[3];
    const double cmd = cmd_delay ? cmd_held : command(t, P, PHI);
    const double dtp = throttle(t);
    const double vrel = V - (gust ? vg : 0.0);
    const double ks = speed ? 1.0 + h.k_speed * (u_of(t) - 0.0) : 1.0;
    const double ke = effectiveness(t);
    double L = ks * (Lp * P + Lv * vrel) + ke * L_df * dfin + L_dt * dtp + Lw;
    double Y = ks * (Yp * P + Yv * vrel) + ke * Y_df * dfin + Y_dt * dtp + Yw;
    if (cubic) L += Lp3 * P * P * P;
    if (load) {
      L += h.load_L;
      Y += h.load_Y;
    }
    if (roll_inflow_only) L += h.L_vv_only * vrel * std::fabs(vrel);
    if (dihedral) {
      L += L_dd * dd_of(t);
      Y += Y_dd * dd_of(t);
    }
    if (flap) {
      const double a1 = 2.0 * M_PI * h.flap_hz * t + h.flap_phase1, a2 = 4.0 * M_PI * h.flap_hz * t + h.flap_phase2;
      L += h.flap_L * (std::sin(a1) + 0.5 * std::sin(a2));
      Y += h.flap_Y * (std::sin(a1) + 0.5 * std::sin(a2));
    }
    if (inflow) {
      L += h.L_vv * vrel * std::fabs(vrel);
      Y += h.Y_vv * vrel * std::fabs(vrel);
    }
    dx[0] = Izz / Ic * L;
    dx[1] = Y / m + w0 * P + g * PHI + (kin ? (w_of(t) - w0) * P : 0.0);
    dx[2] = P;
    dx[3] = 8.97 * cmd - 12.56 * DF;
    (void)DF;
  };

  FlightData d;
  d.source = "generated";
  for (const char* c : {"p", "v", "phi", "u", "w", "delta_f", "delta_t", "phi_sp"}) d.channels[c];
  if (dihedral) d.channels["delta_d"];
  if (yaw_alias) d.channels["r"];
  if (o.record_command) d.channels["delta_f_cmd"];
  const long steps = static_cast<long>(std::lround(o.duration_s * o.rate_hz)) * sub;
  const double a_g = std::exp(-dt / 0.5);
  for (long i = 0; i <= steps; ++i) {
    const double t = static_cast<double>(i) * dt;
    if (i % sub == 0) {
      auto rec = [&](const char* c, double val) {
        d.channels[c].t_s.push_back(t);
        d.channels[c].values.push_back(val);
      };
      rec("p", (scale_err ? 1.0 + h.scale_k : 1.0) * p + (bias ? h.bias_p : 0.0) + o.noise_p * n01(rng));
      rec("v", v + o.noise_v * n01(rng));
      rec("phi", phi + o.noise_phi * n01(rng));
      rec("u", u_of(t) + o.noise_w * n01(rng));
      rec("w", w_of(t) + o.noise_w * n01(rng));
      rec("delta_f", df + o.noise_df * n01(rng));
      rec("delta_t", throttle(t));
      rec("phi_sp", phi_sp(t));
      if (dihedral) rec("delta_d", dd_of(t));
      if (yaw_alias) rec("r", 2.0 * dd_of(t) * (1.0 + 0.01 * n01(rng)));
      if (o.record_command) rec("delta_f_cmd", command(t, p, phi));
    }
    if (offset_err) p_true.push_back(p);
    if (i == steps) break;
    if (delay) {
      df_hist.emplace_back(t, df);
      while (df_hist.size() > 2 && df_hist[1].first <= t - h.delay_s - 1e-12) df_hist.pop_front();
    }
    if (cmd_delay) {
      cmd_hist.emplace_back(t, command(t, p, phi));
      while (cmd_hist.size() > 2 && cmd_hist[1].first <= t - h.delay_s + 1e-12) cmd_hist.pop_front();
      cmd_held = cmd_hist.front().first <= t - h.delay_s + 1e-12 ? cmd_hist.front().second : 0.0;
    }
    const double Lw = o.moment_noise_Nm * n01(rng), Yw = o.force_noise_N * n01(rng);
    double dfin = df_at(t);
    // Out-of-library forms of the flap input (held over the step, as the delayed input).
    if (asym && dfin > 0.0) dfin *= 1.0 + h.asym;
    if (dead_zone) dfin = std::copysign(std::max(std::fabs(dfin) - h.dead_zone, 0.0), dfin);
    if (backlash) {
      if (dfin - df_play > 0.5 * h.backlash) df_play = dfin - 0.5 * h.backlash;
      if (dfin - df_play < -0.5 * h.backlash) df_play = dfin + 0.5 * h.backlash;
      dfin = df_play;
    }
    if (lag) {
      df_lagged += a_lag * (dfin - df_lagged);
      dfin = df_lagged;
    }
    double x[4] = {p, v, phi, df}, k1[4], k2[4], k3[4], k4[4], tmp[4];
    deriv(t, x, dfin, Lw, Yw, k1);
    for (int j = 0; j < 4; ++j) tmp[j] = x[j] + 0.5 * dt * k1[j];
    deriv(t + 0.5 * dt, tmp, dfin, Lw, Yw, k2);
    for (int j = 0; j < 4; ++j) tmp[j] = x[j] + 0.5 * dt * k2[j];
    deriv(t + 0.5 * dt, tmp, dfin, Lw, Yw, k3);
    for (int j = 0; j < 4; ++j) tmp[j] = x[j] + dt * k3[j];
    deriv(t + dt, tmp, dfin, Lw, Yw, k4);
    p += dt / 6.0 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0]);
    v += dt / 6.0 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1]);
    phi += dt / 6.0 * (k1[2] + 2 * k2[2] + 2 * k3[2] + k4[2]);
    df += dt / 6.0 * (k1[3] + 2 * k2[3] + 2 * k3[3] + k4[3]);
    if (gust) vg = a_g * vg + 0.1 * std::sqrt(1.0 - a_g * a_g) * n01(rng);
  }
  if (offset_err) {
    // The recorded p at t is the truth at t - tau (linear between the 2048 Hz steps; held at the
    // record's ends), with the scale, bias and noise it was recorded with.
    Channel& pc = d.channels["p"];
    for (std::size_t j = 0; j < pc.t_s.size(); ++j) {
      const double late = (h.on.count("time_offset") ? h.offset_s : 0.0) +
                          (drift_err ? 1e-6 * h.drift_ppm * (pc.t_s[j] - 0.5 * o.duration_s) : 0.0);
      const double at = pc.t_s[j] - late, pos = std::clamp(at / dt, 0.0, static_cast<double>(steps));
      const auto i0 = std::min(static_cast<std::size_t>(pos), p_true.size() - 2);
      const double f = pos - static_cast<double>(i0);
      const double now = p_true[static_cast<std::size_t>(j) * sub];
      const double then = (1.0 - f) * p_true[i0] + f * p_true[i0 + 1];
      pc.values[j] += (scale_err ? 1.0 + h.scale_k : 1.0) * (then - now);
    }
  }
  return d;
}

}  // namespace nimble::ident::test
