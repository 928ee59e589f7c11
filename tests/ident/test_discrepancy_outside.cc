// The discrepancy workflow's open world (DiscrepancyOptions::signature_checks and term_search;
// docs/discrepancy.md, "Effects outside the library, and signatures" and "Terms"): an effect
// outside the library whose fit a library effect would absorb is not given that name, its form is
// found as a term, and a library effect itself keeps its name with no term beside it. Records of
// tests/ident/discrepancy_generator.h; the per-form rates over 120 records are measured by
// build/bin/bench_discrepancy_outside, the library's by build/bin/bench_discrepancy_library.

#include <cstdint>
#include <string>

#include <catch2/catch.hpp>

#include "discrepancy_generator.h"
#include "ident/discrepancy.h"

using namespace nimble;
using namespace nimble::ident;

namespace {

/// One record of `effect` (magnitudes times `scale`) and the workflow's verdict on it.
/// `open`: the defaults (signature checks and term search on); otherwise the closed world.
DiscrepancyResult run(const std::string& effect, std::uint64_t seed, int set, bool open, double scale = 1.0,
                      double duration_s = 30.0) {
  const test::ModelSet& ms = test::model_set(set);
  test::HiddenEffects h;
  h.on = {effect};
  h.scale = scale;
  test::draw_magnitudes(h, seed);
  test::GeneratorOptions o;
  o.seed = seed;
  o.duration_s = duration_s;
  const FlightData data = test::generate_flight(ms.model, ms.vehicle, h, o);
  DiscrepancyOptions opt;
  opt.signature_checks = open;
  opt.term_search = open;
  return find_discrepancy(data, ms.model, ms.vehicle, opt);
}

/// The term of `r` in `equation` with `expression`, or nullptr.
const NamedEffect* term(const DiscrepancyResult& r, const std::string& equation, const std::string& expression) {
  for (const auto& e : r.effects) {
    if (e.name == "term" && e.equation == equation && e.expression == expression) return &e;
  }
  return nullptr;
}

}  // namespace

TEST_CASE("discrepancy open world: an asymmetric flap effectiveness is not called a sensor bias but found as "
          "pos(delta_f) in L, a roll-only inflow not lateral_inflow but found as v*abs(v) in L",
          "[discrepancy][signature]") {
  for (int i = 0; i < 3; ++i) {
    const std::uint64_t seed = 50000u + static_cast<std::uint64_t>(i);
    const DiscrepancyResult asym = run("flap_asymmetry", seed, 1 + i % 5, true);
    INFO("flap_asymmetry seed " << seed << ": " << asym.verdict << ": " << asym.summary);
    for (const auto& e : asym.effects) CHECK(e.name == "term");
    const NamedEffect* a = term(asym, "L", "pos(delta_f)");
    REQUIRE(a != nullptr);
    CHECK(a->coefficient > 0.0);  // more effective for delta_f > 0, as generated
    CHECK(a->interval[0] > 0.0);
    bool bias_ruled_out = false;
    for (const auto& [name, reason] : a->ruled_out) bias_ruled_out = bias_ruled_out || name == "sensor_bias";
    CHECK(bias_ruled_out);
    const DiscrepancyResult inflow = run("roll_inflow_only", seed + 5000u, 1 + i % 5, true);
    INFO("roll_inflow_only seed " << seed + 5000u << ": " << inflow.verdict << ": " << inflow.summary);
    for (const auto& e : inflow.effects) CHECK(e.name == "term");
    const NamedEffect* v = term(inflow, "L", "v*abs(v)");
    REQUIRE(v != nullptr);
    CHECK(v->coefficient < 0.0);  // L_vo drawn in [-4e-3, -1e-3]
  }
}

TEST_CASE("discrepancy open world: a true sensor bias and a true lateral inflow keep their names, with no term beside "
          "them",
          "[discrepancy][signature]") {
  // At twice the drawn magnitudes (as the sensor bias's own test), with the defaults: named in most
  // records, nothing else beside (no term, no constant_load for the bias: the kinematics show it).
  // (Without the signatures sensor_bias and constant_load, the same columns, are ambiguous.)
  for (const char* effect : {"sensor_bias", "lateral_inflow"}) {
    int named = 0;
    for (std::uint64_t seed = 1; seed <= 4; ++seed) {
      const DiscrepancyResult on = run(effect, seed, 1, true, 2.0, 40.0);
      INFO(effect << " seed " << seed << ": " << on.verdict << ": " << on.summary);
      CHECK(on.verdict != "ambiguous");
      for (const auto& e : on.effects) CHECK(e.name == effect);
      named += on.verdict == "effects" && on.effects.size() == 1;
    }
    INFO(effect);
    CHECK(named >= 3);
  }
}
