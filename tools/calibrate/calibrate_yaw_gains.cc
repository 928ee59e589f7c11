// calibrate_yaw_gains: scans the yaw PD gains kp, kd (fixed wing-root map) on the linear roll-yaw
// loop of the four-state model (controller/yaw_loop.h, thesis Table 8.3 with the trim of Eq D.1)
// with the roll loop of a gain set, and picks the pair whose closed loop decays at least at
// --min-decay (every pole's real part <= -min_decay; default 0.5 /s: a heading error halves within
// 1.4 s) and whose least-damped complex poles are best damped (the criterion of the pitch gains,
// with the decay added: the heading's real pole goes to 0 as kp does). Also reports
// the best proportional-only pair (kd = 0): the thesis's yaw loop is proportional, with a
// feed-forward term.
//
//   calibrate_yaw_gains [--model FILE] [--controller FILE] [--gain-set NAME] [--kp LIST] [--kd LIST]
//                       [--min-decay PER_S] [--check KP,KD]...
//
// Exit code 1 if no grid point decays fast enough, 2 on a usage or config error.

#include <cmath>
#include <cstdio>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "cmdline/args.h"
#include "controller/attitude_controller.h"
#include "controller/yaw_loop.h"
#include "core/model.h"
#include "core/vehicle.h"

using namespace nimble;

namespace {

struct Point {
  GainSet gains;
  YawLoopPoles poles;
};

double g_min_decay = 0.5;

bool acceptable(const Point& p) { return p.poles.max_real_per_s <= -g_min_decay; }

/// Acceptable (decaying at least at min_decay) beats not; among acceptable, the larger smallest
/// damping; among the others, the smaller largest real part.
bool better(const Point& a, const Point& b) {
  if (acceptable(a) != acceptable(b)) return acceptable(a);
  return acceptable(a) ? a.poles.min_damping > b.poles.min_damping : a.poles.max_real_per_s < b.poles.max_real_per_s;
}

void print(const Point& p, const char* note = "") {
  std::printf("%8.4f %8.4f %8.3f %10.3f %s%s\n", p.gains.kp_per_rad, p.gains.kd_per_radps, p.poles.min_damping,
              p.poles.max_real_per_s, p.poles.stable ? "yes" : "NO", note);
}

void print_poles(const Point& p) {
  std::printf("closed-loop poles [1/s]:");
  for (const auto& s : p.poles.poles_s) {
    if (std::fabs(s.imag()) < 1e-9) {
      std::printf("  %.3f", s.real());
    } else if (s.imag() > 0) {
      std::printf("  %.3f +- %.3fi", s.real(), s.imag());
    }
  }
  std::printf("\n");
}

}  // namespace

int main(int argc, char** argv) {
  const std::string src = RIG_SOURCE_DIR;
  std::string model_file = src + "/rig_configs/models/nimble_lateral4_yaw.yaml";
  std::string controller_file = src + "/rig_configs/controller/nimble_attitude.yaml";
  std::string gain_set = "fast";
  std::vector<double> kp_values = cmdline::number_grid("0:1.5:0.01");
  std::vector<double> kd_values = cmdline::number_grid("0:0.3:0.005");
  std::vector<GainSet> checks;

  cmdline::CommandLine cl("calibrate_yaw_gains",
                          "Scans the yaw PD gains kp, kd (fixed wing-root map) on the linear roll-yaw loop of the\n"
                          "four-state model with the roll loop of a gain set, and picks the pair whose closed loop is\n"
                          "stable and whose least-damped complex poles are best damped.");
  cl->footer(
      "LIST: A,B,C or FROM:TO:STEP. The controller file's yaw gains are always checked.\n"
      "Exit code: 0 a pair found, 1 no grid point decays fast enough, 2 a usage or config error.");
  cl->add_option("--model", model_file, "the four-state model (default rig_configs/models/nimble_lateral4_yaw.yaml)")
      ->type_name("FILE");
  cl->add_option(
        "--controller", controller_file,
        "the controller: roll gains and map, yaw map, cut-off (default rig_configs/controller/nimble_attitude.yaml)")
      ->type_name("FILE");
  cl->add_option("--gain-set", gain_set, "the roll gain set flown with the yaw loop")->capture_default_str();
  cmdline::each_value(cl->add_option("--kp", "the kp grid [1/rad] (default 0:1.5:0.01)")->type_name("LIST"),
                      [&kp_values](const std::string& v) { kp_values = cmdline::number_grid(v); });
  cmdline::each_value(cl->add_option("--kd", "the kd grid [s/rad] (default 0:0.3:0.005)")->type_name("LIST"),
                      [&kd_values](const std::string& v) { kd_values = cmdline::number_grid(v); });
  cmdline::each_value(cl->add_option("--check", "also evaluate this gain pair; repeatable")
                          ->type_name("KP,KD")
                          ->allow_extra_args(false)
                          ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll),
                      [&checks](const std::string& v) {
                        const std::vector<double> g = cmdline::number_list(v, ',');
                        if (g.size() != 2) throw std::invalid_argument("'" + v + "' is not KP,KD");
                        checks.push_back({g[0], g[1]});
                      });
  cl->add_option("--min-decay", g_min_decay, "slowest decay accepted: every pole's real part <= -this [1/s]")
      ->check(CLI::Range(0.0, 100.0))
      ->type_name("PER_S")
      ->capture_default_str();
  if (const auto done = cl.parse(argc, argv)) return *done;

  try {
    const DerivativeModel model = load_model(model_file);
    const StateSpace lat4 = build_state_space(model, load_vehicle(model.vehicle_file));
    const ControllerConfig config = load_controller_config(controller_file);
    const YawLoopOptions options = yaw_loop_options(config, gain_set);
    std::printf(
        "model %s; roll gains '%s' (kp %.3f, kd %.3f), roll map %.1f rad/s, yaw map %.3f rad, low-pass %.1f Hz\n",
        model.name.c_str(), gain_set.c_str(), options.roll_gains.kp_per_rad, options.roll_gains.kd_per_radps,
        options.roll_cmd_to_delta_f_radps, options.yaw_cmd_to_wing_root_rad, options.lowpass_cutoff_hz);
    const Point open{{0.0, 0.0}, analyse_yaw_loop(lat4, {0.0, 0.0}, options)};
    std::printf("roll loop alone (yaw kp = kd = 0): max real part %.3f /s\n", open.poles.max_real_per_s);
    print_poles(open);

    std::optional<Point> best, best_p;
    std::printf("\nbest kd per kp (of every 10th kp):\n%8s %8s %8s %10s %s\n", "kp", "kd", "min_zeta", "max_re/s",
                "stable");
    for (std::size_t i = 0; i < kp_values.size(); ++i) {
      std::optional<Point> row;
      for (double kd : kd_values) {
        const GainSet g{kp_values[i], kd};
        const Point p{g, analyse_yaw_loop(lat4, g, options)};
        if (!row || better(p, *row)) row = p;
        if (kd == 0.0 && (!best_p || better(p, *best_p))) best_p = p;
      }
      if (!best || better(*row, *best)) best = row;
      if (i % 10 == 0) print(*row);
    }
    std::printf("\ngain pairs checked:\n");
    print({config.yaw_gains, analyse_yaw_loop(lat4, config.yaw_gains, options)}, "   (controller file)");
    for (const GainSet& g : checks) print({g, analyse_yaw_loop(lat4, g, options)}, "   (--check)");
    if (best_p) {
      print(*best_p, "   (best proportional only, kd = 0)");
    }
    if (!best || !acceptable(*best)) {
      std::printf("\nno gain pair in the grid decays at %.3f /s or faster\n", g_min_decay);
      return 1;
    }
    std::printf("\nbest: kp_per_rad %.4f, kd_per_radps %.4f; smallest damping %.3f; max real part %.3f /s\n",
                best->gains.kp_per_rad, best->gains.kd_per_radps, best->poles.min_damping, best->poles.max_real_per_s);
    print_poles(*best);
  } catch (const std::exception& e) {
    std::cerr << "calibrate_yaw_gains: " << e.what() << "\n";
    return 2;
  }
  return 0;
}
