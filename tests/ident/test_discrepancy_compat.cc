// Tests of the discrepancy workflow's data-compatibility stage (discrepancy/data_compatibility.h): the
// gyro's own errors found from the kinematics before any aerodynamic name, told from an actuator
// delay, and corrected in the record. Records from the in-test generator (discrepancy_generator.h).
// The rates over many records: build/bin/bench_discrepancy_sensors.

#include <algorithm>
#include <cmath>
#include <set>
#include <string>

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

#include "discrepancy_generator.h"
#include "discrepancy/data_compatibility.h"
#include "discrepancy/discrepancy.h"

using namespace nimble;
using namespace nimble::ident;

namespace {

FlightData flight(const std::set<std::string>& effects, std::uint64_t seed, test::HiddenEffects* drawn = nullptr,
                  double duration_s = 20.0) {
  test::HiddenEffects h;
  h.on = effects;
  test::draw_magnitudes(h, seed);
  test::GeneratorOptions o;
  o.seed = seed;
  o.duration_s = duration_s;
  if (drawn) *drawn = h;
  return test::generate_flight(test::set1().model, test::set1().vehicle, h, o);
}

const NamedEffect* find(const DiscrepancyResult& r, const std::string& name) {
  const auto it =
      std::find_if(r.effects.begin(), r.effects.end(), [&](const NamedEffect& e) { return e.name == name; });
  return it == r.effects.end() ? nullptr : &*it;
}

CompatibilityResult stage(const FlightData& d) {
  const DiscrepancyOptions o;
  return check_compatibility(d, o.processing, o.compatibility, 7.74e-6, o.folds, 16);
}

const SensorError& error(const CompatibilityResult& c, const std::string& name) {
  return *std::find_if(c.errors.begin(), c.errors.end(), [&](const SensorError& e) { return e.name == name; });
}

}  // namespace

TEST_CASE("compatibility: a late gyro is a time offset, a late flap an actuator delay, each named for what it is",
          "[discrepancy][compatibility]") {
  test::HiddenEffects h;
  const FlightData late_gyro = flight({"time_offset"}, 3, &h);
  const DiscrepancyResult r = find_discrepancy(late_gyro, test::set1().model, test::set1().vehicle, {});
  INFO("time offset " << h.offset_s << " s: " << r.summary);
  REQUIRE(r.effects.size() == 1);
  const NamedEffect* e = find(r, "time_offset");
  REQUIRE(e != nullptr);
  CHECK(e->channel == "p");
  CHECK(e->against == "phi");
  CHECK(e->interval[0] <= h.offset_s);
  CHECK(h.offset_s <= e->interval[1]);
  // The gap shrinks in the kinematics and, with the record corrected, in L and Y.
  REQUIRE(r.compatibility.size() == 1);
  const CompatibilityResult& c = r.compatibility.front();
  CHECK(c.kinematic_gap_after < 0.2 * c.kinematic_gap_before);
  // L's held-out error on the record as recorded against the corrected one (the gap table's).
  REQUIRE(c.rmse_uncorrected.count("p_dot"));
  CHECK(r.gap.front().output == "p_dot");
  CHECK(r.gap.front().rmse_before < 0.9 * c.rmse_uncorrected.at("p_dot"));
  // The JSON carries the name, the channel, the pair of sources, the value and its interval.
  const YAML::Node j = YAML::Load(discrepancy_json(r));
  CHECK(j["effects"][0]["name"].as<std::string>() == "time_offset");
  CHECK(j["effects"][0]["against"].as<std::string>() == "phi");
  CHECK(j["effects"][0]["interval"].size() == 2);
  CHECK(j["compatibility"][0]["errors"].size() == 4);  // scale, offset, bias, drift

  test::HiddenEffects hd;
  const FlightData late_flap = flight({"actuator_delay"}, 4, &hd);
  const DiscrepancyResult rd = find_discrepancy(late_flap, test::set1().model, test::set1().vehicle, {});
  INFO("actuator delay " << hd.delay_s << " s: " << rd.summary);
  CHECK(find(rd, "actuator_delay") != nullptr);
  CHECK(find(rd, "time_offset") == nullptr);
  REQUIRE(rd.compatibility.size() == 1);
  CHECK_FALSE(error(rd.compatibility.front(), "time_offset").significant);
}

TEST_CASE(
    "compatibility: a gyro scale error and a bias are estimated with the truth inside their intervals, and a "
    "true gyro is left alone",
    "[discrepancy][compatibility]") {
  for (std::uint64_t s = 11; s <= 12; ++s) {
    test::HiddenEffects h;
    const CompatibilityResult c = stage(flight({"sensor_scale"}, s, &h));
    const SensorError& k = error(c, "sensor_scale");
    INFO("seed " << s << " k " << h.scale_k << " estimated " << k.value << " +- " << k.sigma);
    CHECK(k.named);
    CHECK(k.interval[0] <= h.scale_k);
    CHECK(h.scale_k <= k.interval[1]);
    CHECK_FALSE(error(c, "time_offset").significant);
    CHECK_FALSE(error(c, "sensor_bias").significant);
  }
  test::HiddenEffects h;
  const CompatibilityResult b = stage(flight({"sensor_bias"}, 13, &h));
  CHECK(error(b, "sensor_bias").named);
  CHECK(error(b, "sensor_bias").interval[0] <= h.bias_p);
  CHECK(h.bias_p <= error(b, "sensor_bias").interval[1]);
  for (std::uint64_t s = 21; s <= 23; ++s) {
    const CompatibilityResult c = stage(flight({}, s));
    REQUIRE(c.ran);
    for (const SensorError& e : c.errors) {
      INFO("null seed " << s << ": " << e.name << " " << e.value << " p " << e.p_value);
      CHECK_FALSE(e.significant);
    }
  }
}

TEST_CASE("compatibility: the corrected record restamps the IMU's channels and unscales the gyro",
          "[discrepancy][compatibility]") {
  FlightData d;
  d.source = "unit";
  for (const char* c : {"p", "r", "phi"}) {
    d.channels[c].t_s = {0.0, 0.01, 0.02};
    d.channels[c].values = {1.0, 2.0, 3.0};
  }
  CompatibilityResult c;
  c.errors.resize(3);
  c.errors[0].name = "sensor_scale";
  c.errors[0].value = 0.25;
  c.errors[1].name = "time_offset";
  c.errors[1].value = 0.004;
  c.errors[2].name = "sensor_bias";
  c.errors[2].value = 0.5;
  for (auto& e : c.errors) e.corrected = true;
  const FlightData out = corrected_record(d, c, {});
  CHECK(out.at("p").t_s[1] == Approx(0.006));
  CHECK(out.at("r").t_s[1] == Approx(0.006));
  CHECK(out.at("phi").t_s[1] == 0.01);  // the attitude's clock is the reference
  CHECK(out.at("p").values[1] == Approx((2.0 - 0.5) / 1.25));
  CHECK(out.at("r").values[1] == 2.0);
  c.errors[0].corrected = c.errors[1].corrected = c.errors[2].corrected = false;
  CHECK(corrected_record(d, c, {}).at("p").t_s[1] == 0.01);

  DiscrepancyOptions off;
  off.compatibility.enabled = false;
  CHECK(find_discrepancy(flight({}, 31, nullptr, 10.0), test::set1().model, test::set1().vehicle, off)
            .compatibility.empty());
}

TEST_CASE("compatibility: where the kinematics cannot time the gyro, an actuator delay is ambiguous with a time offset",
          "[discrepancy][compatibility]") {
  // An offset scan longer than the record leaves no rows to check: the stage does not run, and a
  // delay the search finds in L and Y could as well be the gyro's clock.
  test::HiddenEffects h;
  h.on = {"actuator_delay"};
  h.scale = 1.5;
  test::draw_magnitudes(h, 4);
  test::GeneratorOptions o;
  o.seed = 4;
  o.duration_s = 12.0;
  const FlightData d = test::generate_flight(test::set1().model, test::set1().vehicle, h, o);
  DiscrepancyOptions opt;
  opt.compatibility.max_offset_s = 6.0;
  const DiscrepancyResult r = find_discrepancy(d, test::set1().model, test::set1().vehicle, opt);
  INFO(r.summary);
  REQUIRE(r.compatibility.size() == 1);
  CHECK_FALSE(r.compatibility.front().ran);
  CHECK(r.compatibility.front().note.find("too short") != std::string::npos);
  REQUIRE(find(r, "actuator_delay") != nullptr);
  CHECK(r.verdict == "ambiguous");
  REQUIRE(r.ambiguous.size() == 1);
  CHECK(r.ambiguous.front() == std::vector<std::string>{"actuator_delay", "time_offset"});
  const bool says_how = std::any_of(r.notes.begin(), r.notes.end(), [](const std::string& n) {
    return n.find("tells them apart") != std::string::npos;
  });
  CHECK(says_how);
  // The same record with the kinematics checked: the delay, named alone.
  const DiscrepancyResult checked = find_discrepancy(d, test::set1().model, test::set1().vehicle, {});
  CHECK(checked.verdict == "effects");
  CHECK(find(checked, "actuator_delay") != nullptr);
}
