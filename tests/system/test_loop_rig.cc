// `rig loop` checked against the rig, not only against itself: the scenarios flown in process
// with the plant's actuator delay at 0.7x and 1.3x the predicted delay margin, and with the roll
// gains at 0.7x and 1.3x the gain margin, for the fast and the slow gains, on hover and on a
// doublet: the vehicle stays regulated below, and rolls in a sustained oscillation above. The
// closed-loop step response of the rig (its dominant pair, by the matrix pencil) against the
// listed poles. The designed gain set flown.

#include <cmath>
#include <complex>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

#include "../support/modal_fit.h"
#include "../support/rig_runs.h"
#include "effects/registry.h"
#include <nimble/controller_status_t.hpp>
#include <nimble/truth_state_t.hpp>
#include "core/constants.h"

using nimble::test::rig_run;
using nimble::test::RunResult;

namespace {

using nimble::kPi;
const std::string kConfigs = std::string(RIG_SOURCE_DIR) + "/rig_configs/";

/// The gain sets as the controller file has them.
struct Gains {
  const char* name;
  double kp, kd;
};
const Gains kFast{"fast", 1.406, 0.200};
const Gains kSlow{"slow", 0.625, 0.156};

/// `rig loop <scenario> <args> --json F`, parsed; the command must succeed.
YAML::Node rig_loop(const std::string& scenario, const std::string& dir, const std::string& args) {
  const std::string json = dir + "/loop.json", out = dir + "/loop.txt";
  const std::string cmd =
      std::string(RIG_BIN) + " loop " + scenario + " " + args + " --json " + json + " >" + out + " 2>&1";
  const int status = std::system(cmd.c_str());
  INFO(cmd << "\n" << nimble::test::slurp(out));
  REQUIRE(WIFEXITED(status));
  REQUIRE(WEXITSTATUS(status) == 0);
  return YAML::LoadFile(json);
}

/// The flown gains scaled by `k` in place of the manoeuvre's set (the scenarios here fly 'fast').
std::string gains_set(const Gains& g, double k) {
  std::ostringstream s;
  s.precision(17);
  s << " --set controller.roll_gain_sets.fast.kp_per_rad=" << g.kp * k
    << " --set controller.roll_gain_sets.fast.kd_per_radps=" << g.kd * k;
  return s.str();
}

std::string delay_set(double delay_s) {
  std::ostringstream s;
  s.precision(17);
  s << " --set plant.effects.actuator_delay.enabled=true --set plant.effects.actuator_delay.delay_s=" << delay_s;
  return s.str();
}

/// The true phi [rad] and time [s] of a log.
struct Trace {
  std::vector<double> t, phi;
  /// Largest |phi| [deg] in [a, b) s.
  double max_abs_deg(double a, double b) const {
    double m = 0.0;
    for (std::size_t i = 0; i < t.size(); ++i) {
      if (t[i] >= a && t[i] < b) m = std::max(m, std::fabs(phi[i]) * 180.0 / kPi);
    }
    return m;
  }
};

Trace truth_of(const std::string& log) {
  Trace tr;
  for (const auto& m : nimble::test::decode_channel<nimble::truth_state_t>(log, nimble::contract::channels::kTruth)) {
    tr.t.push_back(static_cast<double>(m.utime) * 1e-6);
    tr.phi.push_back(m.euler_rad[0]);
  }
  return tr;
}

/// One flight of 20 s in process (the manoeuvre, then hover).
struct Flight {
  RunResult run;
  Trace truth;
};

Flight fly(const std::string& scenario, const std::string& tag, const std::string& args) {
  const std::string dir = nimble::test::scratch_dir(tag);
  Flight f;
  f.run = rig_run(scenario, dir, "--clock inprocess --set duration_s=20" + args);
  f.truth = truth_of(dir + "/run.lcmlog");
  return f;
}

/// One line of figures per flight.
void print_flight(const std::string& what, const Flight& f) {
  std::printf("%-48s max |phi| 5-10 s %6.2f deg, 15-20 s %6.2f deg, exit %d\n", what.c_str(),
              f.truth.max_abs_deg(5.0, 10.0), f.truth.max_abs_deg(15.0, 20.0), f.run.exit_code);
}

/// Below the margin: the loop regulates: over the last 5 s, |phi| within the noise of the
/// estimate-fed loop (0.3-1.8 deg on these flights; a limit cycle is 7-53 deg).
void require_regulated(const Flight& f) {
  INFO(f.run.output);
  CHECK(f.run.exit_code == 0);
  CHECK(f.truth.max_abs_deg(15.0, 20.0) < 2.5);
}

/// Above the margin: an oscillation that does not decay: over the last 5 s at least 5 deg, and
/// no smaller than 0.8 of what it was 10 s before.
void require_oscillating(const Flight& f) {
  INFO(f.run.output);
  const double late = f.truth.max_abs_deg(15.0, 20.0), before = f.truth.max_abs_deg(5.0, 10.0);
  CAPTURE(late, before);
  CHECK(late > 5.0);
  CHECK(late > 0.8 * before);
  // The verdict sees it: not ok, and the oscillation named (kRunNotTracking 6, or 1 if the roll
  // also left the control limits).
  CHECK((f.run.exit_code == 6 || f.run.exit_code == 1));
  CHECK(f.run.output.find("roll oscillation") != std::string::npos);
}

void check_margins_on(const std::string& scenario, const Gains& g) {
  const std::string dir = nimble::test::scratch_dir(std::string("loop_pred_") + g.name);
  const YAML::Node loop = rig_loop(scenario, dir, std::string("--clock inprocess --gains ") + g.name)["loops"][0];
  const double gm = std::pow(10.0, loop["gain_margin_db"].as<double>() / 20.0);
  const double dm_s = loop["delay_margin_ms"].as<double>() * 1e-3;
  INFO(scenario << " gains " << g.name << ": gain margin x" << gm << ", delay margin " << dm_s * 1e3 << " ms");
  REQUIRE(gm > 1.0);
  REQUIRE(dm_s > 0.0);
  const std::string tag = std::string("loop_") + g.name + "_";
  const std::string nominal = gains_set(g, 1.0);
  const std::string name = std::filesystem::path(scenario).stem().string() + " " + g.name;
  std::printf("%s: gain margin x%.3f, delay margin %.2f ms\n", name.c_str(), gm, dm_s * 1e3);
  const Flight d07 = fly(scenario, tag + "d07", nominal + delay_set(0.7 * dm_s));
  print_flight(name + " delay 0.7x", d07);
  require_regulated(d07);
  const Flight d13 = fly(scenario, tag + "d13", nominal + delay_set(1.3 * dm_s));
  print_flight(name + " delay 1.3x", d13);
  require_oscillating(d13);
  const Flight g07 = fly(scenario, tag + "g07", gains_set(g, 0.7 * gm));
  print_flight(name + " gains 0.7x GM", g07);
  require_regulated(g07);
  const Flight g13 = fly(scenario, tag + "g13", gains_set(g, 1.3 * gm));
  print_flight(name + " gains 1.3x GM", g13);
  require_oscillating(g13);
}

}  // namespace

TEST_CASE("rig loop: hover flown at 0.7x and 1.3x of the fast gains' delay and gain margins", "[system]") {
  check_margins_on(kConfigs + "hover.yaml", kFast);
}

TEST_CASE("rig loop: hover flown at 0.7x and 1.3x of the slow gains' delay and gain margins", "[system]") {
  check_margins_on(kConfigs + "hover.yaml", kSlow);
}

TEST_CASE("rig loop: a 6 Hz doublet flown at 0.7x and 1.3x of the fast gains' margins", "[system]") {
  check_margins_on(kConfigs + "ol_doublet_6hz_fast.yaml", kFast);
}

TEST_CASE("rig loop: a 6 Hz doublet flown at 0.7x and 1.3x of the slow gains' margins", "[system]") {
  check_margins_on(kConfigs + "ol_doublet_6hz_fast.yaml", kSlow);
}

TEST_CASE("rig loop: the rig's step response has the dominant pair rig loop lists, within 10 %", "[system]") {
  // roll_step_fast: a 10 deg set-point step at 1 s, back to 0 at 5 s. The return to hover (the
  // linearisation point) from 5.3 s, when the reference generator's own poles (-12 +- 7j) have
  // died away: the dominant pair, the slow real pole and the offset, four modes.
  for (const Gains& g : {kFast, kSlow}) {
    for (const char* input : {"estimate", "truth"}) {
      CAPTURE(g.name, input);
      const std::string dir = nimble::test::scratch_dir(std::string("loop_step_") + g.name + input);
      const std::string scenario = kConfigs + "roll_step_fast.yaml";
      const std::string on = std::string(" --set run.controller_input=") + input;
      const YAML::Node pair =
          rig_loop(scenario, dir, std::string("--clock inprocess --gains ") + g.name + on)["loops"][0]["dominant_pair"];
      const double zeta = pair["damping"].as<double>(), fn = pair["natural_hz"].as<double>();
      const RunResult r = rig_run(scenario, dir, "--clock inprocess" + on + gains_set(g, 1.0));
      INFO(r.output);
      REQUIRE(r.exit_code == 0);
      const Trace tr = truth_of(dir + "/run.lcmlog");
      std::vector<double> y;
      for (std::size_t i = 0; i < tr.t.size(); i += 5) {  // 200 Hz
        if (tr.t[i] >= 5.3 && tr.t[i] < 9.0) y.push_back(tr.phi[i]);
      }
      std::complex<double> found{};
      for (const auto& s : nimble::test::matrix_pencil_modes(y, 0.005, 4)) {
        if (s.imag() > 2 * kPi * 0.5 && s.imag() < 2 * kPi * 10.0) found = s;
      }
      REQUIRE(found.imag() > 0.0);
      const double zeta_rig = -found.real() / std::abs(found), fn_rig = std::abs(found) / (2 * kPi);
      CAPTURE(zeta, zeta_rig, fn, fn_rig);
      std::printf("step %s on the %s: rig loop zeta %.4f f_n %.3f Hz; rig zeta %.4f f_n %.3f Hz\n", g.name, input, zeta,
                  fn, zeta_rig, fn_rig);
      CHECK(zeta_rig == Approx(zeta).epsilon(0.10));
      CHECK(fn_rig == Approx(fn).epsilon(0.10));
    }
  }
}

TEST_CASE("rig loop: a designed gain set is written, loads as controller keys, and flies the doublet", "[system]") {
  const std::string dir = nimble::test::scratch_dir("loop_design");
  const std::string gains = dir + "/designed.yaml";
  const std::string cmd = std::string(RIG_BIN) + " loop " + kConfigs + "nonlinear_doublet_20deg.yaml" +
                          " --design phase_margin_deg=45,crossover_hz=1.2 --gains-out " + gains + " --fly --log " +
                          dir + "/fly.lcmlog --json " + dir + "/loop.json >" + dir + "/out.txt 2>&1";
  const int status = std::system(cmd.c_str());
  const std::string out = nimble::test::slurp(dir + "/out.txt");
  INFO(out);
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
  const YAML::Node j = YAML::LoadFile(dir + "/loop.json")["design"];
  REQUIRE(j["feasible"].as<bool>());
  CHECK(j["phase_margin_deg"].as<double>() == Approx(45.0).margin(0.01));
  CHECK(j["crossover_hz"].as<double>() == Approx(1.2).epsilon(1e-3));
  CHECK(j["flight"].as<std::string>() == "ok");
  const YAML::Node written = YAML::LoadFile(gains);
  CHECK(written["roll_gain_sets"]["designed"]["kp_per_rad"].as<double>() ==
        Approx(j["kp_per_rad"].as<double>()).epsilon(1e-5));
  CHECK(written["roll_gain_sets"]["designed"]["kd_per_radps"].as<double>() ==
        Approx(j["kd_per_radps"].as<double>()).epsilon(1e-5));
  CHECK(out.find("result     ok") != std::string::npos);
  // The flight flew the designed gains: its controller status carries them.
  const auto status_msgs = nimble::test::decode_channel<nimble::controller_status_t>(
      dir + "/fly.lcmlog", nimble::contract::channels::kControllerStatus);
  REQUIRE(status_msgs.size() > 3000);
  CHECK(status_msgs.back().kp == Approx(j["kp_per_rad"].as<double>()).epsilon(1e-12));
  CHECK(status_msgs.back().kd == Approx(j["kd_per_radps"].as<double>()).epsilon(1e-12));
}

TEST_CASE("rig loop: bad input names the problem", "[system]") {
  const std::string dir = nimble::test::scratch_dir("loop_bad");
  auto run = [&](const std::string& args) {
    const std::string cmd = std::string(RIG_BIN) + " loop " + args + " >" + dir + "/out.txt 2>&1";
    const int status = std::system(cmd.c_str());
    return std::make_pair(WIFEXITED(status) ? WEXITSTATUS(status) : -1, nimble::test::slurp(dir + "/out.txt"));
  };
  const auto yaw = run(kConfigs + "yaw_hold_lateral4.yaml");
  CHECK(yaw.first == 2);
  CHECK(yaw.second.find("lateral3") != std::string::npos);
  const auto gains = run(kConfigs + "hover.yaml --gains medium");
  CHECK(gains.first == 2);
  CHECK(gains.second.find("unknown roll gain set 'medium'") != std::string::npos);
  const auto design = run(kConfigs + "hover.yaml --design phase_margin=45");
  CHECK(design.first == 2);
  CHECK(design.second.find("unknown key 'phase_margin'") != std::string::npos);
  const auto fly = run(kConfigs + "hover.yaml --fly");
  CHECK(fly.first == 2);
  CHECK(fly.second.find("--design") != std::string::npos);
  std::ofstream(dir + "/broken.json") << "{\"parameters\": {\"Lp\": {\"value\": 1}}}";
  const auto box = run(kConfigs + "hover.yaml --all-sets --box " + dir + "/broken.json");
  CHECK(box.first == 2);
  CHECK(box.second.find("no value and sigma of Lp") != std::string::npos);
}

TEST_CASE("rig loop: robustness over an identified model's +-2 sigma box from rig identify --json", "[system]") {
  // The rig's own identification flight, identified: its derivatives are set 1's within their
  // small sigma, so every corner of the box holds and the worst margins are near set 1's. The
  // published set-1 box (Lv's sigma 406 % of its value) does not hold: Lv alone loses the loop.
  const std::string dir = nimble::test::scratch_dir("loop_box");
  const RunResult r = rig_run(kConfigs + "id_doublet_train_fast.yaml", dir, "--clock inprocess");
  REQUIRE(r.exit_code == 0);
  const std::string id = dir + "/identify.json";
  REQUIRE(std::system(
              (std::string(RIG_BIN) + " identify " + dir + "/run.lcmlog --json " + id + " > /dev/null").c_str()) == 0);
  const YAML::Node identified = rig_loop(kConfigs + "hover.yaml", dir, "--clock inprocess --all-sets --box " + id);
  REQUIRE(identified["loops"].size() == 10);
  REQUIRE(identified["robustness"].size() == 4);
  const YAML::Node sets = identified["robustness"][0], box = identified["robustness"][1];
  CHECK(sets["gains"].as<std::string>() == "fast");
  CHECK(sets["loops"].as<int>() == 5);
  CHECK(box["loops"].as<int>() == 64);
  CHECK(box["unstable"].as<int>() == 0);
  CHECK(box["unstable_alone"].size() == 0);
  CHECK(box["gain_margin_db"].as<double>() == Approx(sets["gain_margin_db"].as<double>()).margin(0.5));
  CHECK(box["gain_margin_db"].as<double>() > 2.0);

  const YAML::Node published = rig_loop(kConfigs + "hover.yaml", dir, "--clock inprocess --all-sets");
  const YAML::Node pbox = published["robustness"][1];
  CHECK(pbox["unstable"].as<int>() > 0);
  bool lv = false;
  for (const auto& n : pbox["unstable_alone"]) lv = lv || n.as<std::string>().rfind("Lv", 0) == 0;
  CHECK(lv);
}

TEST_CASE("rig loop names every plant effect on that its linear loop leaves out, from the effect registry",
          "[system]") {
  const std::string dir = nimble::test::scratch_dir("loop_effects");
  // Every plant effect of the registry but actuator_delay, which the linear loop models as a delay.
  REQUIRE(nimble::effects::plant_effects().size() >= 8);
  for (const auto* e : nimble::effects::plant_effects()) {
    if (e->plant.in_linear_loop) continue;
    const std::string& effect = e->name();
    INFO(effect);
    const std::string cmd = std::string(RIG_BIN) + " loop " + kConfigs + "hover.yaml --set plant.effects." + effect +
                            ".enabled=true >" + dir + "/out.txt 2>&1";
    const int status = std::system(cmd.c_str());
    const std::string out = nimble::test::slurp(dir + "/out.txt");
    INFO(out);
    CHECK(WIFEXITED(status));
    CHECK(out.find("plant effects on: " + effect) != std::string::npos);
  }
}
