// System tests of rig discrepancy on rig-flown data: the real processes fly a scenario with one
// plant effect switched on, its magnitude drawn by the seed from a documented physical range;
// the workflow gets only the log and the model, and must name the effect (or, for effects the
// equation-level workflow cannot see, name nothing wrong). The model is set 1 with the exact
// kinematic terms (rig_configs/models/nimble_lateral_set1_kinematic.yaml): the structure of the
// nonlinear plant that Eq 21 drops is known, so a flight without a plant effect is a null case.
// The emulated IMU's vibration at the flapping frequency is switched off (kNoVibration) except
// where a test is about it: in the equation error a rate-gyro vibration at the flapping
// frequency cannot be told from a flapping moment, and the workflow names it flapping_forcing.

#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

#include "../support/rig_runs.h"

namespace {

const std::string kConfigs = std::string(RIG_SOURCE_DIR) + "/rig_configs/";
const std::string kModel = kConfigs + "models/nimble_lateral_set1_kinematic.yaml";
const std::string kNoVibration = " --set sensing.imu.vibration_enabled=false";
/// The nonlinear doublet scenarios fly the plant's lateral inflow (the thesis's measured sideways
/// speed); every flight here starts without it, and a test that wants it switches it on after.
const std::string kLinearOnly = " --set plant.effects.lateral_inflow.enabled=false";

/// Uniform draw in [lo, hi] from the seed (one draw per seed and effect).
double drawn(int seed, double lo, double hi) {
  std::mt19937_64 rng(static_cast<std::uint64_t>(seed) * 104729u + 7u);
  return lo + (hi - lo) * std::uniform_real_distribution<double>(0.0, 1.0)(rng);
}

/// Flies `scenario` in lockstep with `sets`, runs rig discrepancy on the log, returns its JSON.
YAML::Node fly_and_check(const std::string& tag, const std::string& scenario, int seed, const std::string& sets) {
  const std::string dir = nimble::test::scratch_dir("discrepancy_" + tag + "_" + std::to_string(seed));
  // The pilot off: the workflow's naming rates were measured on flights without the pilot's
  // throttle; with it, the kinematic term that Eq 21 drops is larger (docs/paper-flights.md "Flights like the
  // paper's"; system.paper.*).
  const auto run = nimble::test::rig_run(
      kConfigs + scenario, dir,
      "--clock lockstep --set pilot.enabled=false --seed " + std::to_string(seed) + kLinearOnly + " " + sets);
  INFO(run.output);
  REQUIRE(run.exit_code == 0);
  const std::string json = dir + "/discrepancy.json";
  const auto r = nimble::test::run_rig("discrepancy " + dir + "/run.lcmlog --model " + kModel + " --json " + json);
  INFO(r.out << r.err);
  REQUIRE(r.exit_code == 0);
  return YAML::LoadFile(json);
}

/// `--set manoeuvre=` a copy of the 30 deg nonlinear doublet that holds its throttle: THRF of the
/// largest set-point over every non-level segment (`throttle_factor: auto`) instead of the
/// shipped file's factor that follows the set-point. The flapping frequency then stays at one
/// value per segment, which the tests of a forcing at the flapping frequency rest on.
std::string held_throttle() {
  const std::string dir = nimble::test::scratch_dir("discrepancy_held_throttle");
  std::ifstream in(kConfigs + "manoeuvres/nonlinear_doublet_30deg.yaml");
  std::stringstream text;
  text << in.rdbuf();
  std::string s = text.str();
  const std::string from = "\nthrottle_factor: setpoint\n", to = "\nthrottle_factor: auto\n";  // the key, not a comment
  const auto at = s.find(from);
  REQUIRE(at != std::string::npos);
  s.replace(at, from.size(), to);
  const std::string path = dir + "/nonlinear_doublet_30deg_held_throttle.yaml";
  std::ofstream(path) << s;
  return " --set manoeuvre=" + path;
}

/// `--set manoeuvre=` a long identification train and its duration: the 7 and 4 Hz doublets of
/// id_doublet_train_7_4hz (35 deg, fast gains) repeated `cycles` times with 0.6 s holds (1.59 s a
/// cycle), 1 s of hover before and 2 s after. An effect that changes during the flight shows as a
/// difference between the manoeuvres before and after the change (or early and late), so it
/// needs the same manoeuvre many times; the shipped trains fly each doublet once.
std::string repeated_train(int cycles) {
  const std::string dir = nimble::test::scratch_dir("discrepancy_repeated_train_" + std::to_string(cycles));
  std::ostringstream m;
  m << "name: id_doublet_train_7_4hz_x" << cycles
    << "\nsource: \"id_doublet_train_7_4hz repeated (test_discrepancy_rig)\"\n"
    << "gain_set: fast\nthrottle_factor: auto\nsegments:\n"
    << "  - {kind: hold, name: hover_before, duration_s: 1.0}\n";
  for (int i = 0; i < cycles; ++i) {
    m << "  - {kind: doublet, name: doublet_7hz_" << i << ", axis: roll, main_frequency_hz: 7.0, amplitude_deg: 35.0}\n"
      << "  - {kind: hold, name: hold_7hz_" << i << ", duration_s: 0.6}\n"
      << "  - {kind: doublet, name: doublet_4hz_" << i << ", axis: roll, main_frequency_hz: 4.0, amplitude_deg: 35.0}\n"
      << "  - {kind: hold, name: hold_4hz_" << i << ", duration_s: 0.6}\n";
  }
  m << "  - {kind: hold, name: hover_after, duration_s: 2.0}\n";
  const std::string path = dir + "/id_doublet_train_7_4hz_x" + std::to_string(cycles) + ".yaml";
  std::ofstream(path) << m.str();
  const double duration_s = 3.0 + cycles * (1.0 / 7.0 + 0.25 + 1.2);
  return " --set manoeuvre=" + path + " --set duration_s=" + std::to_string(std::ceil(duration_s));
}

std::vector<std::string> named(const YAML::Node& d) {
  std::vector<std::string> out;
  for (const auto& e : d["effects"]) out.push_back(e["name"].as<std::string>());
  return out;
}

}  // namespace

TEST_CASE("rig-flown: no plant effect, the identification train and the 30 deg nonlinear doublet name nothing",
          "[system][discrepancy]") {
  for (const char* scenario : {"id_doublet_train_fast.yaml", "nonlinear_doublet_30deg.yaml"}) {
    for (int seed : {1, 2}) {
      INFO(scenario << " seed " << seed);
      const YAML::Node d = fly_and_check("null", scenario, seed, kNoVibration);
      INFO(d["summary"].as<std::string>());
      CHECK(named(d).empty());
      CHECK(d["verdict"].as<std::string>() != "effects");
    }
  }
}

TEST_CASE(
    "rig-flown: lateral inflow of a drawn size on the 30 deg nonlinear doublet is named with the plant's "
    "coefficients",
    "[system][discrepancy]") {
  // Physical range: the nonlinear doublet scenarios fly Y_vv = -0.07 N s^2/m^2, the size that
  // brings their max |v| to the thesis's; drawn between half and 1.5 times that, with
  // L_vv = 0.01 m * Y_vv (the plant file's ratio).
  for (int seed : {1, 2, 3}) {
    const double y_vv = drawn(seed, -0.105, -0.035), l_vv = 0.01 * y_vv;
    INFO("seed " << seed << " Y_vv " << y_vv << " L_vv " << l_vv);
    const YAML::Node d = fly_and_check(
        "inflow", "nonlinear_doublet_30deg.yaml", seed,
        "--set plant.effects.lateral_inflow.enabled=true --set plant.effects.lateral_inflow.Y_vv=" +
            std::to_string(y_vv) + " --set plant.effects.lateral_inflow.L_vv=" + std::to_string(l_vv) + kNoVibration);
    INFO(d["summary"].as<std::string>());
    REQUIRE(named(d) == std::vector<std::string>{"lateral_inflow"});
    const YAML::Node p = d["effects"][0]["parameters"];
    CHECK(std::fabs(p["Y_vv"].as<double>() - y_vv) < 0.25 * std::fabs(y_vv));
    if (p["L_vv"]) CHECK(std::fabs(p["L_vv"].as<double>() - l_vv) < 0.25 * std::fabs(l_vv));
    CHECK(d["gap"]["after"].as<double>() < 0.5 * d["gap"]["before"].as<double>());
  }
}

TEST_CASE("rig-flown: forward-speed coupling of a drawn size on the coupled doublet is named",
          "[system][discrepancy]") {
  // Physical range: gain_per_mps 0.3 .. 0.7 (the plant file's 0.5 gives +60 % at 1.22 m/s).
  for (int seed : {1, 2}) {
    const double k = drawn(seed, 0.3, 0.7);
    INFO("seed " << seed << " k " << k);
    const YAML::Node d = fly_and_check("speed", "coupled_doublet_6hz.yaml", seed,
                                       "--set plant.effects.forward_speed_coupling.enabled=true "
                                       "--set plant.effects.forward_speed_coupling.gain_per_mps=" +
                                           std::to_string(k) + kNoVibration);
    INFO(d["summary"].as<std::string>());
    CHECK(named(d) == std::vector<std::string>{"forward_speed_coupling"});
    // The same flight without the effect names nothing.
    const YAML::Node null = fly_and_check("speed_null", "coupled_doublet_6hz.yaml", seed, kNoVibration);
    INFO(null["summary"].as<std::string>());
    CHECK(named(null).empty());
  }
}

TEST_CASE("rig-flown: a lateral gust alone gets no deterministic name, and a strong one is named lateral_gust",
          "[system][discrepancy]") {
  // The plant file's gust (sigma 0.1 m/s, tau 0.5 s) on the 6 s manoeuvres: no deterministic
  // name. Its signature is weak there: the vehicle drifts with a slow wind, and what is left is
  // below the residual of the short manoeuvres, so lateral_gust is not required.
  for (const char* scenario : {"id_doublet_train_fast.yaml", "nonlinear_doublet_30deg.yaml"}) {
    for (int seed : {1, 2}) {
      INFO(scenario << " seed " << seed);
      const YAML::Node d = fly_and_check(std::string("gust_") + scenario, scenario, seed,
                                         "--set plant.effects.lateral_gust.enabled=true" + kNoVibration);
      INFO(d["summary"].as<std::string>());
      for (const auto& n : named(d)) CHECK(n == "lateral_gust");
    }
  }
  // A 0.3 m/s gust through the 9 s closed-loop doublet train: named from its signature, of the
  // right size (the estimate is rough: within a factor of 3).
  for (int seed : {1, 2}) {
    INFO("strong gust, seed " << seed);
    const YAML::Node d = fly_and_check("gust_strong", "cl_doublet_train_slow.yaml", seed,
                                       "--set plant.effects.lateral_gust.enabled=true "
                                       "--set plant.effects.lateral_gust.sigma_mps=0.3" +
                                           kNoVibration);
    INFO(d["summary"].as<std::string>());
    REQUIRE(named(d) == std::vector<std::string>{"lateral_gust"});
    const double sigma = d["effects"][0]["parameters"]["sigma_mps"].as<double>();
    CHECK(sigma > 0.1);
    CHECK(sigma < 0.9);
    CHECK(d["gap"]["after"].as<double>() == Approx(d["gap"]["before"].as<double>()));
  }
}

TEST_CASE(
    "rig-flown: flapping forcing of a drawn size on the 30 deg nonlinear doublet is named at the plant's "
    "flapping frequency, without it nothing is named",
    "[system][discrepancy]") {
  // The nonlinear doublet with its throttle held (held_throttle()): the flapping frequency
  // (about the trim collective, 16.3 Hz) stays put; the roll manoeuvre excites the derivatives (in hover the
  // baseline is barely identifiable). Ideal sensing: the log's states are the plant's truth.
  // Roll moment amplitudes drawn
  // between half and 1.5 times the plant file's 2 mN m (harmonics halving), side force 5 m^-1
  // times that.
  const std::string ideal = " --set processes=[plant,controller] --set run.controller_input=truth" + held_throttle();
  for (int seed : {1, 2}) {
    const double a = drawn(seed, 1e-3, 3e-3);
    INFO("seed " << seed << " roll moment " << a);
    const std::string sets =
        "--set plant.effects.flapping_forcing.enabled=true"
        " --set plant.effects.flapping_forcing.roll_moment_amplitudes_nm=[" +
        std::to_string(a) + "," + std::to_string(a / 2) + "," + std::to_string(a / 4) +
        "] --set plant.effects.flapping_forcing.side_force_amplitudes_n=[" + std::to_string(5 * a) + "," +
        std::to_string(2.5 * a) + "]" + ideal;
    const YAML::Node d = fly_and_check("flapping", "nonlinear_doublet_30deg.yaml", seed, sets);
    INFO(d["summary"].as<std::string>());
    REQUIRE(named(d) == std::vector<std::string>{"flapping_forcing"});
    const double f = d["effects"][0]["parameters"]["flapping_hz"].as<double>();
    CHECK(std::fabs(f - 16.31) < 0.5);
    const YAML::Node null = fly_and_check("flapping_null", "nonlinear_doublet_30deg.yaml", seed, ideal);
    INFO(null["summary"].as<std::string>());
    CHECK(named(null).empty());
  }
}

TEST_CASE(
    "rig-flown: the emulated IMU's vibration at the flapping frequency is named flapping_forcing, and nothing "
    "else",
    "[system][discrepancy]") {
  // The equation error cannot tell a rate-gyro vibration from a flapping moment (both are a
  // sinusoid in p and its derivative); the 30 deg nonlinear doublet with its throttle held
  // (held_throttle()) keeps the vibration of the default sensing at one frequency.
  const YAML::Node d = fly_and_check("vibration", "nonlinear_doublet_30deg.yaml", 1, held_throttle());
  INFO(d["summary"].as<std::string>());
  CHECK(named(d) == std::vector<std::string>{"flapping_forcing"});
}

TEST_CASE(
    "rig-flown: the plant's actuator delay of a drawn size is named from the actuator equation with its delay, "
    "and the closed loop with it fits better",
    "[system][discrepancy]") {
  // The plant's actuator delay acts before the flap actuator, whose output (ACTUATOR_FB) the log
  // records as delta_f; the L and Y equations cannot see it, the actuator equation (delta_f
  // against the flight board's command, ACTUATOR_CMD) can. Delay drawn from [5, 15] ms: a
  // command link and motor driver; the slow gains' loop stays controlled through it (at 25 ms
  // it does not). Named delay within 3 ms: the scan's grid is one sample (1.95 ms) beyond the
  // known latency of one controller tick, and the rig's own latency is 1-2 ms.
  for (int seed = 1; seed <= 2; ++seed) {
    const double delay = drawn(seed, 0.005, 0.015);
    INFO("seed " << seed << " delay " << delay);
    const YAML::Node d =
        fly_and_check("delay", "cl_doublet_train_slow.yaml", seed,
                      "--set plant.effects.actuator_delay.enabled=true --set plant.effects.actuator_delay.delay_s=" +
                          std::to_string(delay) + kNoVibration);
    INFO(d["summary"].as<std::string>());
    REQUIRE(named(d) == std::vector<std::string>{"actuator_delay"});
    CHECK(std::fabs(d["effects"][0]["parameters"]["delay_s"].as<double>() - delay) < 0.003);
    CHECK(d["effects"][0]["parameters"]["F_cmd_delayed"].as<double>() > 0.0);
    for (const auto& c : d["closed_loop"]["outputs"]) {
      INFO(c["output"].as<std::string>());
      CHECK(c["r2_after"].as<double>() > c["r2_before"].as<double>());
    }
    CHECK(d["closed_loop"]["outputs"].size() == 4);
  }
}

TEST_CASE(
    "rig-flown: the augmented model flies what was found: a scenario with it as model has the named lateral "
    "inflow, and the workflow names it again",
    "[system][discrepancy]") {
  // The scenario as shipped: its lateral inflow on (Y_vv = -0.07 N s^2/m^2).
  const std::string dir = nimble::test::scratch_dir("discrepancy_fly_found");
  const auto found =
      nimble::test::rig_run(kConfigs + "nonlinear_doublet_30deg.yaml", dir, "--clock lockstep --seed 1" + kNoVibration);
  REQUIRE(found.exit_code == 0);
  const std::string augmented = dir + "/augmented.yaml";
  const auto r =
      nimble::test::run_rig("discrepancy " + dir + "/run.lcmlog --model " + kModel + " --model-out " + augmented);
  REQUIRE(r.exit_code == 0);
  // Fly the augmented model as the plant's model, the plant's own effect off.
  const std::string dir2 = nimble::test::scratch_dir("discrepancy_fly_found_2");
  const auto flown =
      nimble::test::rig_run(kConfigs + "nonlinear_doublet_30deg.yaml", dir2,
                            "--clock lockstep --seed 2 --set model=" + augmented + kLinearOnly + kNoVibration);
  INFO(flown.output);
  REQUIRE(flown.exit_code == 0);
  const std::string json = dir2 + "/discrepancy.json";
  const auto again = nimble::test::run_rig("discrepancy " + dir2 + "/run.lcmlog --model " + kModel + " --json " + json);
  REQUIRE(again.exit_code == 0);
  const YAML::Node d = YAML::LoadFile(json);
  INFO(d["summary"].as<std::string>());
  REQUIRE(named(d) == std::vector<std::string>{"lateral_inflow"});
  CHECK(std::fabs(d["effects"][0]["parameters"]["Y_vv"].as<double>() + 0.07) < 0.0175);  // the scenario's -0.07
}

TEST_CASE(
    "rig-flown: a step of the flap input's effectiveness of a drawn size and time is named with its change "
    "time and fraction, and the same flight without it names nothing",
    "[system][discrepancy]") {
  // The long identification train, 8 cycles (repeated_train(), 16 s). A damaged wing: the
  // fraction drawn from -15..-40 % for both L_df and Y_df, the time from the middle 60 % of the
  // flight (4.2-11.8 s).
  const std::string train = repeated_train(8);
  for (int seed : {1, 2}) {
    const double fraction = drawn(seed, -0.40, -0.15), t_change = drawn(seed + 10, 4.2, 11.8);
    INFO("seed " << seed << " step " << fraction << " at " << t_change << " s");
    const std::string f = std::to_string(fraction);
    const YAML::Node d =
        fly_and_check("step", "id_doublet_train_fast.yaml", seed,
                      "--set plant.effects.effectiveness_step.enabled=true"
                      " --set plant.effects.effectiveness_step.t_change_s=" +
                          std::to_string(t_change) + " --set plant.effects.effectiveness_step.roll_fraction=" + f +
                          " --set plant.effects.effectiveness_step.side_fraction=" + f + train + kNoVibration);
    INFO(d["summary"].as<std::string>());
    REQUIRE(named(d) == std::vector<std::string>{"effectiveness_step"});
    const YAML::Node p = d["effects"][0]["parameters"];
    INFO("named " << p["t_change_s"].as<double>() << " s in [" << p["t_change_lo_s"].as<double>() << ", "
                  << p["t_change_hi_s"].as<double>() << "], fraction " << p["fraction"].as<double>());
    CHECK(p["t_change_lo_s"].as<double>() <= t_change);
    CHECK(t_change <= p["t_change_hi_s"].as<double>());
    CHECK(std::fabs(p["fraction"].as<double>() - fraction) < 0.05);
  }
  // The null flight's gyro without its random turn-on bias: on this 16 s flight (seed 3, a turn-on
  // bias of -0.026 rad/s) the estimator has taken out only 0.005 rad/s of it by the end, and the
  // data-compatibility stage rightly names the estimate's p biased against its phi (sensor_bias,
  // -0.022 rad/s): a finding about the states, not about the effect this case is after.
  const YAML::Node null = fly_and_check("repeated_null", "id_doublet_train_fast.yaml", 3,
                                        train + kNoVibration + " --set sensing.imu.gyro_bias_turn_on_sigma_radps=0");
  INFO(null["summary"].as<std::string>());
  CHECK(named(null).empty());
}

TEST_CASE("rig-flown: a drift of the flap input's effectiveness of a drawn rate is named with its rate",
          "[system][discrepancy]") {
  // Battery sag from the flight's start, the rate drawn from -5..-8 %/min: the upper part of
  // the physical range (-2..-8 %/min), so that a 35 s flight (repeated_train(20)) shows it. The
  // rig's equation error in lockstep is nearly noise-free, and the PSE rule's penalty, the
  // dependent's variance per parameter, then asks for a drop of the residual sum of squares that
  // grows as 1 / (r^2 T^3): at -6 %/min a 16 s flight did not pass it (F 1534 in L), a 51 s
  // flight did. The named rate is per minute of L_df at the record's middle t_mid:
  // r / (1 + r t_mid / 60).
  const std::string train = repeated_train(20);
  for (int seed : {1, 2}) {
    const double rate = drawn(seed + 20, -0.08, -0.05);
    INFO("seed " << seed << " drift " << rate << " /min");
    const YAML::Node d = fly_and_check("drift", "id_doublet_train_fast.yaml", seed,
                                       "--set plant.effects.effectiveness_drift.enabled=true"
                                       " --set plant.effects.effectiveness_drift.rate_per_min=" +
                                           std::to_string(rate) + train + kNoVibration);
    INFO(d["summary"].as<std::string>());
    REQUIRE(named(d) == std::vector<std::string>{"effectiveness_drift"});
    const YAML::Node p = d["effects"][0]["parameters"];
    const double expected = rate / (1.0 + rate * p["t_mid_s"].as<double>() / 60.0);
    INFO("named " << p["rate_per_min"].as<double>() << " in [" << p["rate_per_min_lo"].as<double>() << ", "
                  << p["rate_per_min_hi"].as<double>() << "], expected " << expected);
    CHECK(std::fabs(p["rate_per_min"].as<double>() - expected) < 0.1 * std::fabs(expected));
  }
}
