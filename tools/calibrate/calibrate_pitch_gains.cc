// calibrate_pitch_gains: scans the pitch PD gains kp, kd (fixed dihedral map) on the
// linear closed loop of the longitudinal model (controller/pitch_loop.h) and picks the
// pair whose closed loop is stable and whose least-damped complex poles are best
// damped. Prints, per kp, the best kd, then the chosen gains and their poles.
//
//   calibrate_pitch_gains [--model FILE] [--controller FILE] [--plant FILE]
//                         [--map RAD] [--kp LIST] [--kd LIST] [--continuous]
//                         [--delay-steps N] [--check KP,KD]... [--full]
//                         [--u0 MPS] [--w0 MPS] [--theta0 RAD]
//
// LIST is A,B,C or FROM:TO:STEP. Defaults: rig_configs/models/nimble_longitudinal.yaml
// (thesis Table E.4), the rate, pitch cut-off and pitch_cmd_to_dihedral_rad of
// rig_configs/controller/nimble_attitude.yaml, the servo of rig_configs/plant/nimble_plant.yaml,
// kp 0.005..0.300 step 0.005, kd 0.0005..0.0400 step 0.0005, the 512 Hz discrete loop
// (zero-order hold) without extra delay. --check evaluates a gain pair (repeatable; the
// controller file's pitch gains are always shown). --full prints every grid point.
// --u0, --w0, --theta0 replace the model's trim (the linearisation point of Eq B.15: w0
// enters A as the -w0 q term of udot, e.g. a climb), for checks away from hover.
// Exit code 1 if no grid point is stable, 2 on a usage or config error.

#include <cmath>
#include <complex>
#include <cstdio>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "cmdline/args.h"
#include "controller/attitude_controller.h"
#include "controller/pitch_loop.h"
#include "core/config.h"
#include "core/model.h"
#include "core/vehicle.h"

using namespace nimble;

namespace {

std::string format_pole(const std::complex<double>& s) {
  char buf[64];
  if (!std::isfinite(s.real())) return "-inf";
  if (s.imag() == 0.0) {
    std::snprintf(buf, sizeof buf, "%.3f", s.real());
  } else {
    std::snprintf(buf, sizeof buf, "%.3f %c %.3fi", s.real(), s.imag() < 0 ? '-' : '+', std::fabs(s.imag()));
  }
  return buf;
}

void print_point_header() {
  std::printf("%8s %8s %9s %9s %8s %10s %8s %s\n", "kp", "kd", "Kp_eff", "Kd_eff", "min_zeta", "max_re/s", "wn_rad/s",
              "stable");
}

void print_point(const PitchGainPoint& p, double map, const char* note = "") {
  const PitchLoopPoles& r = p.poles;
  std::printf("%8.4f %8.4f %9.5f %9.5f %8.3f %10.3f %8.2f %s%s\n", p.gains.kp_per_rad, p.gains.kd_per_radps,
              p.gains.kp_per_rad * map, p.gains.kd_per_radps * map, r.has_oscillatory ? r.min_damping : NAN,
              r.max_real_per_s, r.has_oscillatory ? std::abs(r.least_damped) : NAN, r.stable ? "yes" : "NO", note);
}

/// The loop's options: the controller file's, with the plant file's servo, --map and the
/// discrete loop's extra delay.
PitchLoopOptions loop_options(const ControllerConfig& config, const std::string& plant_file, double map,
                              bool continuous, int delay_steps) {
  PitchLoopOptions options = pitch_loop_options(config);
  {
    // Only the servo section of the plant file is read here.
    ConfigMap plant = ConfigMap::load_file(plant_file);
    if (plant.has("servo")) {
      ConfigMap servo = plant.get_map("servo");
      options.servo_wn2_rad2ps2 = servo.get_double_or("wn2_rad2ps2", options.servo_wn2_rad2ps2, Range::positive());
      options.servo_c1_radps = servo.get_double_or("c1_radps", options.servo_c1_radps, Range::positive());
      servo.finish();
    }
  }
  if (std::isfinite(map)) options.pitch_cmd_to_dihedral_rad = map;
  options.continuous = continuous;
  options.delay_steps = continuous ? 0 : delay_steps;
  return options;
}

/// What is scanned: the model, its trim, the loop, the open loop's poles and the grid.
void print_setup(const DerivativeModel& model, const Vehicle& vehicle, const StateSpace& lon,
                 const PitchLoopOptions& options, bool continuous, const std::vector<double>& kp_values,
                 const std::vector<double>& kd_values) {
  std::printf("model %s (%s), vehicle %s; trim u0 %.3f m/s, w0 %.3f m/s, theta0 %.3f rad\n", model.name.c_str(),
              model.source.c_str(), vehicle.name.c_str(), model.trim.u0_mps, model.trim.w0_mps, model.trim.theta0_rad);
  std::printf(
      "loop: %s; servo %.1f/(s^2 + %.2f s + %.1f); low-pass %.1f Hz Butterworth; "
      "pitch_cmd_to_dihedral_rad %.4f\n",
      continuous ? "continuous" : "discrete at the controller rate, zero-order hold", options.servo_wn2_rad2ps2,
      options.servo_c1_radps, options.servo_wn2_rad2ps2, options.lowpass_cutoff_hz, options.pitch_cmd_to_dihedral_rad);
  if (!continuous) {
    std::printf("controller %.0f Hz, command delay %d control period(s)\n", options.rate_hz, options.delay_steps);
  }
  const PitchLoopPoles open = analyse_pitch_loop(lon, GainSet{0.0, 0.0}, options);
  std::printf("open loop (kp = kd = 0): max real part %.3f /s\n", open.max_real_per_s);
  std::printf("grid: kp %zu values %.4f..%.4f, kd %zu values %.4f..%.4f\n", kp_values.size(), kp_values.front(),
              kp_values.back(), kd_values.size(), kd_values.front(), kd_values.back());
  std::printf(
      "min_zeta: smallest damping ratio of the complex closed-loop poles (real poles excluded);\n"
      "wn: natural frequency of that pole; Kp_eff, Kd_eff = gain * map (dihedral rad per rad, per rad/s)\n\n");
}

/// The best gain pair of the scan, and its closed-loop poles.
void print_best(const PitchGainPoint& best, const PitchLoopOptions& options) {
  std::printf(
      "\nbest: kp_per_rad %.4f, kd_per_radps %.4f (Kp_eff %.5f rad/rad, Kd_eff %.5f rad/(rad/s)); "
      "smallest damping %.3f at wn %.2f rad/s; max real part %.3f /s\n",
      best.gains.kp_per_rad, best.gains.kd_per_radps, best.gains.kp_per_rad * options.pitch_cmd_to_dihedral_rad,
      best.gains.kd_per_radps * options.pitch_cmd_to_dihedral_rad, best.poles.min_damping,
      std::abs(best.poles.least_damped), best.poles.max_real_per_s);
  std::printf("closed-loop poles [1/s]:");
  for (const auto& s : best.poles.poles_s) std::printf("  %s", format_pole(s).c_str());
  std::printf("\n");
}

}  // namespace

/// The scan, per kp the best kd (a stable one with the largest damping, else the least
/// unstable), or with `full` every grid point.
void print_scan(const PitchGainScan& scan, std::size_t n_kp, std::size_t n_kd, bool full, double map) {
  print_point_header();
  for (std::size_t i = 0; i < n_kp; ++i) {
    if (full) {
      for (std::size_t j = 0; j < n_kd; ++j) {
        print_point(scan.points[i * n_kd + j], map);
      }
      continue;
    }
    // Best kd for this kp: a stable one with the largest damping, else the least unstable.
    std::size_t best = i * n_kd;
    for (std::size_t j = 0; j < n_kd; ++j) {
      const PitchGainPoint& p = scan.points[i * n_kd + j];
      const PitchGainPoint& b = scan.points[best];
      const double pz = p.poles.has_oscillatory ? p.poles.min_damping : -INFINITY;
      const double bz = b.poles.has_oscillatory ? b.poles.min_damping : -INFINITY;
      const bool better = p.poles.stable != b.poles.stable ? p.poles.stable
                          : p.poles.stable                 ? pz > bz
                                                           : p.poles.max_real_per_s < b.poles.max_real_per_s;
      if (better) best = i * n_kd + j;
    }
    print_point(scan.points[best], map);
  }
}

int main(int argc, char** argv) {
  const std::string src = RIG_SOURCE_DIR;
  std::string model_file = src + "/rig_configs/models/nimble_longitudinal.yaml";
  std::string controller_file = src + "/rig_configs/controller/nimble_attitude.yaml";
  std::string plant_file = src + "/rig_configs/plant/nimble_plant.yaml";
  double map = NAN;
  std::vector<double> kp_values = default_pitch_kp_grid();
  std::vector<double> kd_values = default_pitch_kd_grid();
  std::vector<GainSet> checks;
  bool continuous = false, full = false;
  int delay_steps = 0;
  double u0 = NAN, w0 = NAN, theta0 = NAN;

  cmdline::CommandLine cl(
      "calibrate_pitch_gains",
      "Scans the pitch PD gains kp, kd (fixed dihedral map) on the linear closed loop of the longitudinal\n"
      "model and picks the pair whose closed loop is stable and whose least-damped complex poles are best\n"
      "damped. Prints, per kp, the best kd, then the chosen gains and their poles.");
  cl->footer(
      "LIST: A,B,C or FROM:TO:STEP. The controller file's pitch gains are always checked.\n"
      "Exit code: 0 a stable pair found, 1 no grid point is stable, 2 a usage or config error.");
  cl->add_option("--model", model_file,
                 "the longitudinal model (default rig_configs/models/nimble_longitudinal.yaml, thesis Table E.4)")
      ->type_name("FILE");
  cl->add_option("--controller", controller_file,
                 "the controller: its rate, pitch cut-off and pitch_cmd_to_dihedral_rad (default "
                 "rig_configs/controller/nimble_attitude.yaml)")
      ->type_name("FILE");
  cl->add_option("--plant", plant_file,
                 "the plant, of which only the servo is read (default rig_configs/plant/nimble_plant.yaml)")
      ->type_name("FILE");
  cl->add_option("--map", map, "pitch_cmd_to_dihedral_rad (default: the controller file's)")
      ->check(cmdline::kFinite)
      ->type_name("RAD");
  cmdline::each_value(cl->add_option("--kp", "the kp grid [1/rad] (default 0.005:0.300:0.005)")->type_name("LIST"),
                      [&kp_values](const std::string& v) { kp_values = cmdline::number_grid(v); });
  cmdline::each_value(cl->add_option("--kd", "the kd grid [s/rad] (default 0.0005:0.0400:0.0005)")->type_name("LIST"),
                      [&kd_values](const std::string& v) { kd_values = cmdline::number_grid(v); });
  cl->add_flag("--continuous", continuous, "the continuous loop instead of the discrete one at the controller rate");
  cl->add_option("--delay-steps", delay_steps, "extra command delay of the discrete loop [control periods]")
      ->check(CLI::Range(0, 100))
      ->type_name("N")
      ->capture_default_str();
  cmdline::each_value(cl->add_option("--check", "also evaluate this gain pair; repeatable")
                          ->type_name("KP,KD")
                          ->allow_extra_args(false)
                          ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll),
                      [&checks](const std::string& v) {
                        const std::vector<double> g = cmdline::number_list(v, ',');
                        if (g.size() != 2) throw std::invalid_argument("'" + v + "' is not KP,KD");
                        checks.push_back({g[0], g[1]});
                      });
  cl->add_flag("--full", full, "print every grid point, not only the best kd per kp");
  cl->add_option("--u0", u0, "replaces the model's trim u0 (the linearisation point, Eq B.15)")
      ->check(cmdline::kFinite)
      ->type_name("MPS");
  cl->add_option("--w0", w0, "replaces the model's trim w0 (enters A as the -w0 q term of udot, e.g. a climb)")
      ->check(cmdline::kFinite)
      ->type_name("MPS");
  cl->add_option("--theta0", theta0, "replaces the model's trim theta0")->check(cmdline::kFinite)->type_name("RAD");
  if (const auto done = cl.parse(argc, argv)) return *done;

  try {
    DerivativeModel model = load_model(model_file);
    if (std::isfinite(u0)) model.trim.u0_mps = u0;
    if (std::isfinite(w0)) model.trim.w0_mps = w0;
    if (std::isfinite(theta0)) model.trim.theta0_rad = theta0;
    const Vehicle vehicle = load_vehicle(model.vehicle_file);
    const StateSpace lon = build_state_space(model, vehicle);
    const ControllerConfig config = load_controller_config(controller_file);
    const PitchLoopOptions options = loop_options(config, plant_file, map, continuous, delay_steps);
    print_setup(model, vehicle, lon, options, continuous, kp_values, kd_values);

    const PitchGainScan scan = scan_pitch_gains(lon, options, kp_values, kd_values);
    print_scan(scan, kp_values.size(), kd_values.size(), full, options.pitch_cmd_to_dihedral_rad);

    std::printf("\ngain pairs checked:\n");
    print_point_header();
    print_point({config.pitch_gains, analyse_pitch_loop(lon, config.pitch_gains, options)},
                options.pitch_cmd_to_dihedral_rad, "   (controller file)");
    for (const GainSet& g : checks) {
      print_point({g, analyse_pitch_loop(lon, g, options)}, options.pitch_cmd_to_dihedral_rad, "   (--check)");
    }

    if (!scan.best) {
      std::printf("\nno stable gain pair in the grid\n");
      return 1;
    }
    print_best(scan.points[*scan.best], options);
  } catch (const std::exception& e) {
    std::cerr << "calibrate_pitch_gains: " << e.what() << "\n";
    return 2;
  }
  return 0;
}
