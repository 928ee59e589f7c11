// Unit tests of the pilot on the throttle (controller/pilot.h): what it sees and when, the size
// of its correction, its limits, its configuration, and the height loop it closes around a
// vertical axis like the rig's.

#include <cmath>
#include <string>

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

#include "controller/attitude_controller.h"
#include "controller/pilot.h"
#include "core/config.h"

using nimble::AltitudePilot;
using nimble::PilotConfig;

namespace {

constexpr double kAccelPerPct = 0.215;  // m/s^2 per %: the shipped map (1.708 rad/s per %)

PilotConfig enabled() {
  PilotConfig c;
  c.enabled = true;
  return c;
}

/// Feeds heights h(t) at 200 Hz over [t0, t1).
template <typename F>
void feed(AltitudePilot& pilot, double t0, double t1, F h) {
  for (int i = 0;; ++i) {
    const double t = t0 + i / 200.0;
    if (t >= t1) break;
    pilot.observe(t, h(t));
  }
}

}  // namespace

TEST_CASE("pilot: no correction before it has seen a height and its rate", "[pilot]") {
  AltitudePilot pilot(enabled(), kAccelPerPct);
  CHECK(pilot.correction_pct(1.0) == 0.0);
  CHECK(std::isnan(pilot.reference_m()));
  feed(pilot, 0.0, 0.3, [](double) { return 1.0; });
  CHECK(pilot.reference_m() == 1.0);
  // Delay 0.25 s and window 0.1 s: at 0.3 s the pilot sees the sample of 0.05 s, but not one
  // a window before it.
  CHECK(pilot.correction_pct(0.3) == 0.0);
  CHECK(pilot.correction_pct(0.36) == Approx(0.0).margin(1e-12));  // level and on the reference
}

TEST_CASE("pilot: a height below the reference gives bandwidth squared times the error, in % of throttle", "[pilot]") {
  AltitudePilot pilot(enabled(), kAccelPerPct);
  // Starts at 0, drops to -0.1 m at t = 1 s and stays there.
  // Heights come as time goes on: the pilot keeps what it still needs (delay + window) and no more.
  feed(pilot, 0.0, 1.2, [](double t) { return t < 1.0 ? 0.0 : -0.1; });
  // Before the drop reaches the pilot's eyes (1 s + 0.25 s delay), nothing.
  CHECK(pilot.correction_pct(1.2) == Approx(0.0).margin(1e-12));
  feed(pilot, 1.2, 2.5, [](double t) { return t < 1.0 ? 0.0 : -0.1; });
  // Long after it, at rest 0.1 m low: + 1^2 * 0.1 / 0.1635 %.
  CHECK(pilot.correction_pct(2.5) == Approx(0.1 / kAccelPerPct).epsilon(1e-9));
}

TEST_CASE("pilot: a climb gives twice damping times bandwidth times the climb rate less throttle", "[pilot]") {
  PilotConfig c = enabled();
  c.damping = 0.8;
  c.bandwidth_radps = 1.5;
  AltitudePilot pilot(c, kAccelPerPct);
  const double t = 1.5, seen = t - c.reaction_delay_s;
  feed(pilot, 0.0, t + 1e-9, [](double tt) { return 0.3 * tt; });  // climbing at 0.3 m/s from the reference
  const double expected = (-1.5 * 1.5 * 0.3 * seen - 2.0 * 0.8 * 1.5 * 0.3) / kAccelPerPct;
  CHECK(pilot.correction_pct(t) == Approx(expected).epsilon(0.02));  // a sample at most 5 ms old
  CHECK(pilot.correction_pct(t) < 0.0);
}

TEST_CASE("pilot: the correction stops at max_correction_pct, samples out of order or not finite are ignored",
          "[pilot]") {
  PilotConfig c = enabled();
  c.max_correction_pct = 4.0;
  AltitudePilot pilot(c, kAccelPerPct);
  feed(pilot, 0.0, 2.0, [](double t) { return t < 0.5 ? 0.0 : -3.0; });
  CHECK(pilot.correction_pct(1.9) == 4.0);
  CHECK_FALSE(pilot.observe(1.0, 0.0));  // older than the newest sample
  CHECK_FALSE(pilot.observe(2.5, std::nan("")));
  CHECK_FALSE(pilot.observe(std::nan(""), 0.0));
  CHECK(pilot.correction_pct(1.9) == 4.0);
  // Heights whose differences overflow (a malformed pose that still decodes) give no correction.
  AltitudePilot far(c, kAccelPerPct);
  feed(far, 0.0, 1.0, [](double t) { return t < 0.5 ? 1e308 : -1e308; });
  CHECK(far.correction_pct(0.95) == 0.0);
}

TEST_CASE("pilot: a % of throttle accelerates by the thrust curve's slope times the map over the mass", "[pilot]") {
  const nimble::ControllerConfig c;
  const double a = nimble::throttle_accel_per_pct(c.f_trim_radps, c.throttle_to_freq_radps_per_pct, 9.81);
  // Eq 4.18: dT/df = 2 * 0.0114 / (2 pi) N per rad/s; the mass from weight = thrust at trim.
  const double mass = nimble::flap_thrust_n(c.f_trim_radps) / 9.81;
  CHECK(a == Approx(2.0 * 0.0114 / (2.0 * M_PI) * c.throttle_to_freq_radps_per_pct / mass).epsilon(1e-9));
  CHECK(a == Approx(0.215).epsilon(0.01));  // the shipped map: 1.708 rad/s per %, 28.76 g
  CHECK_THROWS_AS(AltitudePilot(enabled(), 0.0), std::invalid_argument);
  CHECK_THROWS_AS(AltitudePilot(enabled(), std::nan("")), std::invalid_argument);
}

TEST_CASE("pilot: the section is checked, naming the key", "[pilot]") {
  const auto load = [](const std::string& text) {
    nimble::ConfigMap map(YAML::Load(text), "scenario.yaml", "pilot");
    return nimble::pilot_config_from(map);
  };
  CHECK_FALSE(load("{}").enabled);
  const PilotConfig c = load("{enabled: true, reaction_delay_s: 0.3}");
  CHECK(c.enabled);
  CHECK(c.reaction_delay_s == 0.3);
  // Below 50 ms the pilot could use a pose of the very cycle (lockstep determinism).
  CHECK_THROWS_WITH(load("{enabled: true, reaction_delay_s: 0.01}"), Catch::Contains("pilot.reaction_delay_s"));
  CHECK_THROWS_WITH(load("{enabled: true, bandwidth_radps: 0}"), Catch::Contains("pilot.bandwidth_radps"));
  CHECK_THROWS_WITH(load("{enabled: true, bandwith_radps: 1}"), Catch::Contains("bandwith_radps"));
}

TEST_CASE("pilot: closed around a vertical axis like the rig's, it stops a 0.3 m/s climb without pumping", "[pilot]") {
  // Height h (up), climb rate hd; throttle acts through the collective's first-order lag
  // (12.56 rad/s, thesis Eq 33) with kAccelPerPct per %, weak vertical damping Zw/m.
  const double dt = 1.0 / 512.0, pole = 12.56, damping_per_s = 5.9e-3 / 0.02876;
  AltitudePilot pilot(enabled(), kAccelPerPct);
  double h = 0.0, hd = 0.3, thrust_accel = 0.0, t = 0.0;
  double h_max = 0.0, hd_min = hd;
  int sign_changes = 0;
  double last_hd = hd;
  for (int i = 0; i < 512 * 12; ++i, t += dt) {
    if (i % 2 == 0) pilot.observe(t, h);  // a pose every ~4 ms
    const double cmd = pilot.correction_pct(t) * kAccelPerPct;
    thrust_accel += dt * pole * (cmd - thrust_accel);
    hd += dt * (thrust_accel - damping_per_s * hd);
    h += dt * hd;
    h_max = std::max(h_max, h);
    hd_min = std::min(hd_min, hd);
    if ((hd > 0.01) != (last_hd > 0.01)) ++sign_changes;
    last_hd = hd;
  }
  // Critically damped, but 0.25 s of delay and the 0.1 s rate window cost damping: the climb is
  // stopped within about 0.3 m and comes back at less than two thirds of the climb rate it stopped,
  // without pumping, and settles.
  CHECK(h_max < 0.35);
  CHECK(hd_min > -0.2);
  CHECK(sign_changes <= 2);
  CHECK(std::fabs(h) < 0.05);
  CHECK(std::fabs(hd) < 0.02);
}
