// calibrate_roll_map: sweeps roll_cmd_to_delta_f_radps (and the doublet amplitude
// of a manoeuvre) on the linear closed loop and prints the state and delta_f
// ranges next to the published ones (thesis Table 9.4 set 1, Table 9.10).
//
//   calibrate_roll_map [--model FILE] [--controller FILE] [--manoeuvre FILE]
//                      [--gain-set NAME] [--maps A,B,...] [--amplitudes-deg A,B,...]
//                      [--tail-s S] [--target-p R] [--target-v R] [--target-phi R] [--target-df R]
//
// Defaults: set-1 model, rig_configs/controller/nimble_attitude.yaml, the
// identification doublet train, fast gains, maps 10..160 rad/s, the manoeuvre's
// own amplitude, 4 s of hover simulated after the manoeuvre ('stable': |phi| < 0.01 rad,
// |p| < 0.1 rad/s, |v| < 0.05 m/s in its last 0.5 s). Exit code 2 on a usage or config error.

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "cmdline/args.h"
#include "controller/attitude_controller.h"
#include "controller/linear_closed_loop.h"
#include "controller/manoeuvre.h"
#include "core/config.h"
#include "core/model.h"
#include "core/vehicle.h"
#include "core/constants.h"

using namespace nimble;

namespace {

/// Sets every doublet/112 amplitude on the roll axis to `amplitude_rad` and
/// recomputes an automatic throttle factor.
Manoeuvre with_amplitude(Manoeuvre m, double amplitude_rad) {
  for (auto& s : m.segments) {
    if ((s.kind == SegmentKind::kDoublet || s.kind == SegmentKind::kOneOneTwo) && s.axis == Axis::kRoll) {
      s.amplitude_rad = amplitude_rad;
    }
  }
  if (m.throttle_factor_auto) m.throttle_factor = throttle_factor_for(m.max_abs_roll_rad());
  return m;
}

double roll_amplitude(const Manoeuvre& m) {
  for (const auto& s : m.segments) {
    if ((s.kind == SegmentKind::kDoublet || s.kind == SegmentKind::kOneOneTwo) && s.axis == Axis::kRoll) {
      return s.amplitude_rad;
    }
  }
  return 0.0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string src = RIG_SOURCE_DIR;
  std::string model_file = src + "/rig_configs/models/nimble_lateral_set1.yaml";
  std::string controller_file = src + "/rig_configs/controller/nimble_attitude.yaml";
  std::string manoeuvre_file = src + "/rig_configs/manoeuvres/id_doublet_train_7_4hz.yaml";
  std::string gain_set = "fast";
  std::vector<double> maps;
  for (double k = 10.0; k <= 160.0 + 1e-9; k += 10.0) maps.push_back(k);
  std::vector<double> amplitudes_deg;
  // Published ranges: thesis Table 9.4 (set 1) and the delta_f range of Table 9.10
  // (RMSE 12.59 rad/s = 10.95 % of the measured range).
  LinearLoopOptions options;
  TargetRanges target;

  cmdline::CommandLine cl(
      "calibrate_roll_map",
      "Sweeps roll_cmd_to_delta_f_radps (and the doublet amplitude of a manoeuvre) on the linear closed\n"
      "loop and prints the state and delta_f ranges next to the published ones (thesis Table 9.4 set 1,\n"
      "Table 9.10).");
  cl->footer(
      "'stable': |phi| < 0.01 rad, |p| < 0.1 rad/s, |v| < 0.05 m/s in the last 0.5 s simulated.\n"
      "Exit code: 0 a stable combination found, 1 none, 2 a usage or config error.");
  cl->add_option("--model", model_file, "the lateral model (default rig_configs/models/nimble_lateral_set1.yaml)")
      ->type_name("FILE");
  cl->add_option("--controller", controller_file,
                 "the controller (default rig_configs/controller/nimble_attitude.yaml)")
      ->type_name("FILE");
  cl->add_option("--manoeuvre", manoeuvre_file,
                 "the manoeuvre (default rig_configs/manoeuvres/id_doublet_train_7_4hz.yaml, the identification "
                 "doublet train)")
      ->type_name("FILE");
  cl->add_option("--gain-set", gain_set, "the roll gain set of the controller")
      ->type_name("NAME")
      ->capture_default_str();
  cmdline::each_value(
      cl->add_option("--maps", "the roll_cmd_to_delta_f_radps values (default 10,20,..,160)")->type_name("A,B,.."),
      [&maps](const std::string& v) { maps = cmdline::number_list(v); });
  cmdline::each_value(cl->add_option("--amplitudes-deg", "the roll doublet amplitudes (default: the manoeuvre's own)")
                          ->type_name("A,B,.."),
                      [&amplitudes_deg](const std::string& v) { amplitudes_deg = cmdline::number_list(v); });
  cl->add_option("--tail-s", options.tail_s, "hover simulated after the manoeuvre")
      ->check(cmdline::kFinite & CLI::NonNegativeNumber)
      ->type_name("S")
      ->capture_default_str();
  cl->add_option("--target-p", target.p_radps, "published range of p [rad/s]")
      ->check(cmdline::kFinite)
      ->type_name("R")
      ->capture_default_str();
  cl->add_option("--target-v", target.v_mps, "published range of v [m/s]")
      ->check(cmdline::kFinite)
      ->type_name("R")
      ->capture_default_str();
  cl->add_option("--target-phi", target.phi_rad, "published range of phi [rad]")
      ->check(cmdline::kFinite)
      ->type_name("R")
      ->capture_default_str();
  cl->add_option("--target-df", target.delta_f_radps, "published range of delta_f [rad/s]")
      ->check(cmdline::kFinite)
      ->type_name("R")
      ->capture_default_str();
  if (const auto done = cl.parse(argc, argv)) return *done;

  try {
    const DerivativeModel model = load_model(model_file);
    const Vehicle vehicle = load_vehicle(model.vehicle_file);
    const ControllerConfig base = load_controller_config(controller_file);
    const Manoeuvre manoeuvre = load_manoeuvre(manoeuvre_file);
    check_gain_sets(manoeuvre, base);
    roll_gain_set(base, gain_set);
    if (amplitudes_deg.empty()) amplitudes_deg.push_back(roll_amplitude(manoeuvre) * 180.0 / kPi);

    std::printf("model %s, manoeuvre %s, gain set %s (kp %.3f /rad, kd %.3f s/rad)\n", model.name.c_str(),
                manoeuvre.name.c_str(), gain_set.c_str(), roll_gain_set(base, gain_set).kp_per_rad,
                roll_gain_set(base, gain_set).kd_per_radps);
    std::printf("targets (ranges max-min): p %.2f rad/s, v %.2f m/s, phi %.2f rad, delta_f %.0f rad/s\n",
                target.p_radps, target.v_mps, target.phi_rad, target.delta_f_radps);
    std::printf("score = rms of log(range / target) over p, v, phi, delta_f (actuator output)\n\n");
    std::printf("%8s %7s %8s %7s %7s %9s %9s %6s %7s %9s %s\n", "map", "amp_deg", "p", "v", "phi", "df", "df_cmd",
                "sat", "THRF", "score", "stable");

    double best_score = INFINITY, best_map = 0.0, best_amp = 0.0;
    for (const double amp_deg : amplitudes_deg) {
      const Manoeuvre m = with_amplitude(manoeuvre, amp_deg * kPi / 180.0);
      const ManoeuvrePlayer player(m, base.trim_throttle_pct);
      for (const double k : maps) {
        ControllerConfig config = base;
        config.roll_cmd_to_delta_f_radps = k;
        const LinearLoopResult r = simulate_linear_closed_loop(model, vehicle, config, gain_set, player, options);
        const bool stable = returned_to_hover(r);
        const double score = range_score(r, target);
        std::printf("%8.1f %7.1f %8.2f %7.2f %7.3f %9.1f %9.1f %6lld %7.3f %9.3f %s\n", k, amp_deg, r.p_radps.range(),
                    r.v_mps.range(), r.phi_rad.range(), r.delta_f_radps.range(), r.delta_f_cmd_radps.range(),
                    static_cast<long long>(r.counters.saturated_steps), m.throttle_factor, score,
                    stable ? "yes" : "NO");
        if (stable && score < best_score) {
          best_score = score;
          best_map = k;
          best_amp = amp_deg;
        }
      }
    }
    if (std::isfinite(best_score)) {
      std::printf("\nbest: roll_cmd_to_delta_f_radps %.1f rad/s per unit, amplitude %.1f deg (score %.3f)\n", best_map,
                  best_amp, best_score);
    } else {
      std::printf("\nno stable combination\n");
      return 1;
    }
  } catch (const std::exception& e) {
    std::cerr << "calibrate_roll_map: " << e.what() << "\n";
    return 2;
  }
  return 0;
}
