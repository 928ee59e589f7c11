// Unit tests of manoeuvre files and the manoeuvre player: widths, amplitudes,
// 112 pulses, throttle factor, strict loading.

#include <cmath>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "../support/config_error.h"

#include "controller/attitude_controller.h"
#include "controller/manoeuvre.h"
#include "core/config.h"
#include "core/constants.h"

using namespace nimble;

namespace {

const std::string kManoeuvres = std::string(RIG_SOURCE_DIR) + "/rig_configs/manoeuvres/";
constexpr double kDeg = kPi / 180.0;
constexpr double kTrim = 60.0;

Manoeuvre from_text(const std::string& text) {
  ConfigMap map = ConfigMap::load_string(text, "inline.yaml");
  return manoeuvre_from_config(map);
}

std::string with_segments(const std::string& segments) {
  return "name: test\nsource: \"unit test\"\nsegments:\n" + segments;
}

/// A piece of constant set-point: value and length, found by scanning at fine steps.
struct Piece {
  double value;
  double start_s;
  double width_s;
};

/// Constant pieces of the roll set-point between t0 and t1, scanned every dt.
std::vector<Piece> roll_pieces(const ManoeuvrePlayer& player, double t0, double t1, double dt = 1e-5) {
  std::vector<Piece> out;
  double t = t0;
  double value = player.at(t).roll_sp_rad;
  double start = t;
  for (; t < t1; t += dt) {
    const double v = player.at(t).roll_sp_rad;
    if (std::fabs(v - value) > 1e-12) {
      out.push_back({value, start, t - start});
      value = v;
      start = t;
    }
  }
  out.push_back({value, start, t - start});
  return out;
}

/// Requires a ConfigError naming `key` (and `value` if given) from from_text().
void expect_key_error(const std::string& text, const std::string& key, const std::string& value = "") {
  nimble::test::expect_inline_key_error([](const std::string& t) { return from_text(t); }, text, key, value);
}

}  // namespace

TEST_CASE("doublet of main frequency f: two pulses of 1/(2f), negative first", "[manoeuvre]") {
  const Manoeuvre m =
      from_text(with_segments("  - {kind: hold, duration_s: 1.0}\n"
                              "  - {kind: doublet, main_frequency_hz: 7, amplitude_deg: 35}\n"
                              "  - {kind: hold, duration_s: 1.0}\n"));
  const ManoeuvrePlayer player(m, kTrim);
  CHECK(m.segments[1].duration_s == Approx(1.0 / 7.0));
  CHECK(player.duration_s() == Approx(2.0 + 1.0 / 7.0));
  const auto pieces = roll_pieces(player, 0.5, 1.5);
  REQUIRE(pieces.size() == 4);
  CHECK(pieces[0].value == 0.0);
  CHECK(pieces[1].value == Approx(-35.0 * kDeg));
  CHECK(pieces[1].start_s == Approx(1.0).margin(2e-5));
  CHECK(pieces[1].width_s == Approx(1.0 / 14.0).margin(2e-5));
  CHECK(pieces[2].value == Approx(35.0 * kDeg));
  CHECK(pieces[2].width_s == Approx(1.0 / 14.0).margin(2e-5));
  CHECK(pieces[3].value == 0.0);
  CHECK(player.at(1.01).segment_name == "doublet_1");
  CHECK(player.at(1.01).segment_index == 1);
}

TEST_CASE("doublet with sign +1 and an offset", "[manoeuvre]") {
  const Manoeuvre m = from_text(with_segments(
      "  - {kind: doublet, main_frequency_hz: 4, amplitude_deg: 15, roll_deg: 30, sign: 1, pitch_deg: 5}\n"));
  const ManoeuvrePlayer player(m, kTrim);
  CHECK(player.at(0.01).roll_sp_rad == Approx(45.0 * kDeg));
  CHECK(player.at(0.2).roll_sp_rad == Approx(15.0 * kDeg));
  CHECK(player.at(0.2).pitch_sp_rad == Approx(5.0 * kDeg));
  CHECK(player.duration_s() == Approx(0.25));
}

TEST_CASE("112: unit width 1/(2f), pulses u, u, 2u with alternating signs", "[manoeuvre]") {
  const Manoeuvre m =
      from_text(with_segments("  - {kind: hold, duration_s: 0.5}\n"
                              "  - {kind: one_one_two, main_frequency_hz: 7, amplitude_deg: 20}\n"
                              "  - {kind: hold, duration_s: 0.5}\n"));
  const ManoeuvrePlayer player(m, kTrim);
  const double u = 1.0 / 14.0;
  CHECK(m.segments[1].pulse_width_s() == Approx(u));
  CHECK(m.segments[1].duration_s == Approx(4.0 * u));
  const auto pieces = roll_pieces(player, 0.25, 1.0);
  REQUIRE(pieces.size() == 5);
  CHECK(pieces[1].value == Approx(-20.0 * kDeg));
  CHECK(pieces[1].width_s == Approx(u).margin(2e-5));
  CHECK(pieces[2].value == Approx(20.0 * kDeg));
  CHECK(pieces[2].width_s == Approx(u).margin(2e-5));
  CHECK(pieces[3].value == Approx(-20.0 * kDeg));
  CHECK(pieces[3].width_s == Approx(2.0 * u).margin(2e-5));  // half period of 3.5 Hz
  CHECK(pieces[4].value == 0.0);
}

TEST_CASE("ramp is linear on its axis", "[manoeuvre]") {
  const Manoeuvre m = from_text(
      with_segments("  - {kind: ramp, axis: pitch, from_deg: 0, to_deg: 20, duration_s: 0.2, roll_deg: 3}\n"));
  const ManoeuvrePlayer player(m, kTrim);
  CHECK(player.at(0.0).pitch_sp_rad == Approx(0.0).margin(1e-12));
  CHECK(player.at(0.1).pitch_sp_rad == Approx(10.0 * kDeg));
  CHECK(player.at(0.15).pitch_sp_rad == Approx(15.0 * kDeg));
  CHECK(player.at(0.1).roll_sp_rad == Approx(3.0 * kDeg));
}

TEST_CASE("throttle factor 1/cos(max roll) applies only during manoeuvre segments", "[manoeuvre][throttle]") {
  const Manoeuvre m = load_manoeuvre(kManoeuvres + "id_doublet_train_7_4hz.yaml");
  const double max_roll = m.max_abs_roll_rad();
  CHECK(max_roll > 0.0);
  CHECK(m.throttle_factor_auto);
  CHECK(m.throttle_factor == Approx(1.0 / std::cos(max_roll)));
  const ManoeuvrePlayer player(m, kTrim);
  int in_doublets = 0;
  for (double t = -0.5; t < player.duration_s() + 0.5; t += 1.0 / 512.0) {
    const Setpoint sp = player.at(t);
    CHECK(sp.throttle_pct == kTrim);
    const bool doublet =
        sp.active && m.segments[static_cast<std::size_t>(sp.segment_index)].kind == SegmentKind::kDoublet;
    if (doublet) {
      ++in_doublets;
      CHECK(sp.throttle_factor == Approx(m.throttle_factor));
      CHECK(sp.delta_throttle_pct == Approx(kTrim * (m.throttle_factor - 1.0)));
      CHECK(sp.delta_throttle_pct > 0.0);
    } else {
      CHECK(sp.throttle_factor == 1.0);
      CHECK(sp.delta_throttle_pct == 0.0);
    }
  }
  CHECK(in_doublets > 100);

  // Offset manoeuvre: the factor uses offset + amplitude and holds at the offset apply it.
  // The shipped file flies `throttle_factor: setpoint`; the same manoeuvre with the factor of
  // Eq 7.1 held over every non-level segment first.
  const Manoeuvre shipped = load_manoeuvre(kManoeuvres + "nonlinear_doublet_30deg.yaml");
  CHECK(shipped.throttle_factor_from_setpoint);
  Manoeuvre nl = shipped;
  nl.throttle_factor_from_setpoint = false;
  CHECK(nl.throttle_factor == Approx(1.0 / std::cos(45.0 * kDeg)));
  const ManoeuvrePlayer nlp(nl, kTrim);
  CHECK(nlp.at(0.5).throttle_factor == 1.0);                     // hover before
  CHECK(nlp.at(1.5).throttle_factor == Approx(std::sqrt(2.0)));  // sideways hold

  // With `throttle_factor: setpoint` (the shipped file): the factor follows the set-point of the
  // moment (its largest, offset + amplitude, is the manoeuvre's).
  const Manoeuvre& nls = shipped;
  const ManoeuvrePlayer nlsp(nls, kTrim);
  CHECK(nlsp.at(0.5).throttle_factor == 1.0);                                   // hover before
  CHECK(nlsp.at(1.1).throttle_factor == Approx(1.0 / std::cos(15.0 * kDeg)));   // half-way up the ramp
  CHECK(nlsp.at(1.5).throttle_factor == Approx(1.0 / std::cos(30.0 * kDeg)));   // sideways hold
  CHECK(nlsp.at(1.75).throttle_factor == Approx(1.0 / std::cos(15.0 * kDeg)));  // doublet, lower pulse
  CHECK(nlsp.at(1.9).throttle_factor == Approx(std::sqrt(2.0)));                // doublet, far pulse at 45 deg
  CHECK(nlsp.at(1.9).delta_throttle_pct == Approx(kTrim * (std::sqrt(2.0) - 1.0)));
  CHECK(nlsp.at(nlsp.duration_s() - 0.1).throttle_factor == 1.0);  // hover after
  CHECK(nlp.at(nlp.duration_s() - 0.1).throttle_factor == 1.0);    // hover after
}

TEST_CASE("explicit throttle factor, segment offsets and opt-out", "[manoeuvre][throttle]") {
  const Manoeuvre m = from_text(
      "name: t\nsource: s\nthrottle_factor: 1.1\nsegments:\n"
      "  - {kind: hold, duration_s: 1, delta_throttle_pct: 5}\n"
      "  - {kind: doublet, main_frequency_hz: 2, amplitude_deg: 10, apply_throttle_factor: false}\n"
      "  - {kind: hold, duration_s: 1, apply_throttle_factor: true}\n");
  CHECK_FALSE(m.throttle_factor_auto);
  const ManoeuvrePlayer p(m, kTrim);
  CHECK(p.at(0.5).throttle_pct == kTrim + 5.0);
  CHECK(p.at(0.5).delta_throttle_pct == Approx(5.0));
  CHECK(p.at(1.1).throttle_factor == 1.0);
  CHECK(p.at(1.6).throttle_factor == 1.1);
  CHECK(p.at(1.6).delta_throttle_pct == Approx(kTrim * 0.1));
  CHECK(throttle_factor_for(60.0 * kDeg) == Approx(2.0));
  CHECK_THROWS_AS(throttle_factor_for(kPi / 2.0), std::invalid_argument);
}

TEST_CASE("outside the manoeuvre the player gives the idle hover set-point", "[manoeuvre]") {
  const ManoeuvrePlayer p(load_manoeuvre(kManoeuvres + "ol_doublet_6hz.yaml"), kTrim);
  for (const double t : {-0.1, p.duration_s(), p.duration_s() + 3.0}) {
    const Setpoint sp = p.at(t);
    CHECK_FALSE(sp.active);
    CHECK(sp.segment_index == -1);
    CHECK(sp.segment_name.empty());
    CHECK(sp.manoeuvre.empty());
    CHECK(sp.roll_sp_rad == 0.0);
    CHECK(sp.throttle_pct == kTrim);
    CHECK(sp.throttle_factor == 1.0);
  }
  CHECK(p.at(0.0).active);
  CHECK(p.at(0.0).manoeuvre == "ol_doublet_6hz");
  CHECK(p.at(0.0).gain_set == "fast");
}

TEST_CASE("every manoeuvre file error names its key", "[manoeuvre][config]") {
  expect_key_error(with_segments("  - {kind: triplet, duration_s: 1}\n"), "segments[0].kind", "triplet");
  expect_key_error(with_segments("  - {kind: hold, duration_s: 1}\n  - {kind: hold, duration_s: -1}\n"),
                   "segments[1].duration_s", "-1");
  expect_key_error(with_segments("  - {kind: doublet, main_frequency_hz: 4, amplitude_deg: 70}\n"),
                   "segments[0].amplitude_deg", "70");
  expect_key_error(with_segments("  - {kind: doublet, main_frequency_hz: 4, amplitude_deg: 15, roll_deg: 50}\n"),
                   "segments[0].amplitude_deg", "15");
  expect_key_error(with_segments("  - {kind: doublet, main_frequency_hz: 0, amplitude_deg: 15}\n"),
                   "segments[0].main_frequency_hz", "0");
  expect_key_error(with_segments("  - {kind: doublet, main_frequency_hz: 4, amplitude_deg: 15, duration_s: 1}\n"),
                   "segments[0].duration_s", "1");
  expect_key_error(with_segments("  - {kind: doublet, main_frequency_hz: 4, amplitude_deg: 15, sign: 0}\n"),
                   "segments[0].sign", "0");
  expect_key_error(with_segments("  - {kind: doublet, main_frequency_hz: 4, amplitude_deg: 15, axis: yaw}\n"),
                   "segments[0].axis", "yaw");
  expect_key_error(with_segments("  - {kind: hold, duration_s: 1, roll_deg: 61}\n"), "segments[0].roll_deg", "61");
  expect_key_error(with_segments("  - {kind: hold, duration_s: 1, amplitude: 3}\n"), "segments[0].amplitude", "3");
  expect_key_error(with_segments("  - {kind: hold}\n"), "segments[0].duration_s");
  expect_key_error(with_segments("  - {kind: ramp, axis: roll, from_deg: 0, to_deg: 20, duration_s: 1, roll_deg: 5}\n"),
                   "segments[0].roll_deg", "5");
  expect_key_error("name: t\nsource: s\nsegments: []\n", "segments");
  expect_key_error("name: t\nsource: s\nthrottle_factor: 0.5\nsegments:\n  - {kind: hold, duration_s: 1}\n",
                   "throttle_factor", "0.5");
  expect_key_error("name: t\nsource: s\nspeed: 3\nsegments:\n  - {kind: hold, duration_s: 1}\n", "speed", "3");
  expect_key_error("source: s\nsegments:\n  - {kind: hold, duration_s: 1}\n", "name");
}

TEST_CASE("unknown gain set in a manoeuvre is an error naming it", "[manoeuvre][gains]") {
  const ControllerConfig cfg;
  const Manoeuvre bad = from_text("name: t\nsource: s\ngain_set: medium\nsegments:\n  - {kind: hold, duration_s: 1}\n");
  try {
    check_gain_sets(bad, cfg);
    FAIL("expected a ConfigError");
  } catch (const ConfigError& e) {
    CHECK(e.key() == "gain_set");
    CHECK(e.value() == "medium");
  }
  const Manoeuvre seg =
      from_text(with_segments("  - {kind: hold, duration_s: 1}\n"
                              "  - {kind: hold, duration_s: 1, gain_set: turbo}\n"));
  CHECK_THROWS_WITH(check_gain_sets(seg, cfg), Catch::Contains("segments[1].gain_set") && Catch::Contains("turbo"));
  CHECK_NOTHROW(check_gain_sets(load_manoeuvre(kManoeuvres + "cl_112_4_2hz.yaml"), cfg));
}

TEST_CASE("player rejects a throttle outside 0..100 and names the segment", "[manoeuvre][throttle]") {
  const Manoeuvre m =
      from_text(with_segments("  - {kind: hold, name: boost, duration_s: 1, delta_throttle_pct: 50}\n"));
  CHECK_THROWS_WITH(ManoeuvrePlayer(m, 60.0), Catch::Contains("boost"));
  CHECK_NOTHROW(ManoeuvrePlayer(m, 40.0));
  CHECK_THROWS_AS(ManoeuvrePlayer(m, 0.0), std::invalid_argument);
}

TEST_CASE("shipped manoeuvre files load, name their thesis source, match their names", "[manoeuvre][files]") {
  const std::vector<std::string> files = {"hover",
                                          "id_doublet_train_7_4hz",
                                          "ol_doublet_6hz",
                                          "ol_112_7_3p5hz",
                                          "cl_doublet_train_6_4_2hz",
                                          "cl_112_4_2hz",
                                          "coupled_doublet_6hz",
                                          "nonlinear_doublet_20deg",
                                          "nonlinear_doublet_30deg"};
  const ControllerConfig cfg;
  for (const auto& name : files) {
    const std::string path = kManoeuvres + name + ".yaml";
    INFO(path);
    const Manoeuvre m = load_manoeuvre(path);
    CHECK(m.name == name);
    CHECK(m.source.find("thesis") != std::string::npos);
    std::ifstream in(path);
    std::string first;
    std::getline(in, first);
    CHECK(first.rfind("#", 0) == 0);
    CHECK_NOTHROW(check_gain_sets(m, cfg));
    CHECK(m.max_abs_roll_rad() <= kManoeuvreAngleLimitRad);
    const ManoeuvrePlayer p(m, cfg.trim_throttle_pct);
    CHECK(p.duration_s() > 1.0);
    CHECK(p.at(0.0).roll_sp_rad == 0.0);                    // every manoeuvre starts from hover
    CHECK(p.at(p.duration_s() - 1e-6).roll_sp_rad == 0.0);  // and ends in hover
  }
  // Gain sets and frequencies named by the thesis.
  CHECK(load_manoeuvre(kManoeuvres + "cl_doublet_train_6_4_2hz.yaml").gain_set == "slow");
  CHECK(load_manoeuvre(kManoeuvres + "cl_112_4_2hz.yaml").gain_set == "slow");
  const Manoeuvre id = load_manoeuvre(kManoeuvres + "id_doublet_train_7_4hz.yaml");
  std::vector<double> f;
  for (const auto& s : id.segments) {
    if (s.kind == SegmentKind::kDoublet) f.push_back(s.main_frequency_hz);
  }
  CHECK(f == std::vector<double>{7.0, 4.0});
  const Manoeuvre coupled = load_manoeuvre(kManoeuvres + "coupled_doublet_6hz.yaml");
  const ManoeuvrePlayer cp(coupled, kTrim);
  double max_pitch = 0.0, max_roll = 0.0, first_pitch_t = -1.0, first_roll_t = -1.0;
  for (double t = 0.0; t < cp.duration_s(); t += 1e-3) {
    const Setpoint sp = cp.at(t);
    max_pitch = std::max(max_pitch, std::fabs(sp.pitch_sp_rad));
    max_roll = std::max(max_roll, std::fabs(sp.roll_sp_rad));
    if (first_pitch_t < 0.0 && sp.pitch_sp_rad != 0.0) first_pitch_t = t;
    if (first_roll_t < 0.0 && sp.roll_sp_rad != 0.0) first_roll_t = t;
  }
  CHECK(max_pitch == Approx(20.0 * kDeg));
  CHECK(max_roll == Approx(30.0 * kDeg));
  CHECK(first_pitch_t < first_roll_t);  // pitch input first
}
