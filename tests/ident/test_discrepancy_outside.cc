// The signature checks of the discrepancy workflow (DiscrepancyOptions::signature_checks, off by
// default until every library effect has its own; docs/discrepancy.md, "Effects outside the
// library, and signatures"): an effect outside the library whose fit a library effect would
// absorb is not given that name, and the library effect itself keeps it. Records of
// tests/ident/discrepancy_generator.h; the per-form rates over 120 records are measured by
// build/bin/bench_discrepancy_outside.

#include <cstdint>
#include <string>

#include <catch2/catch.hpp>

#include "discrepancy_generator.h"
#include "ident/discrepancy.h"

using namespace nimble;
using namespace nimble::ident;

namespace {

/// One record of `effect` (magnitudes times `scale`) and the workflow's verdict on it.
DiscrepancyResult run(const std::string& effect, std::uint64_t seed, int set, bool checks, double scale = 1.0,
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
  opt.signature_checks = checks;
  return find_discrepancy(data, ms.model, ms.vehicle, opt);
}

}  // namespace

TEST_CASE("discrepancy signatures: an asymmetric flap effectiveness is not called a sensor bias, a roll-only inflow "
          "not lateral_inflow",
          "[discrepancy][signature]") {
  for (int i = 0; i < 3; ++i) {
    const std::uint64_t seed = 50000u + static_cast<std::uint64_t>(i);
    const DiscrepancyResult asym = run("flap_asymmetry", seed, 1 + i % 5, true);
    INFO("flap_asymmetry seed " << seed << ": " << asym.verdict << ": " << asym.summary);
    CHECK(asym.verdict != "effects");
    const DiscrepancyResult inflow = run("roll_inflow_only", seed + 5000u, 1 + i % 5, true);
    INFO("roll_inflow_only seed " << seed + 5000u << ": " << inflow.verdict << ": " << inflow.summary);
    CHECK(inflow.verdict != "effects");
  }
}

TEST_CASE("discrepancy signatures: a true sensor bias and a true lateral inflow keep their names with the checks on",
          "[discrepancy][signature]") {
  for (const char* effect : {"sensor_bias", "lateral_inflow"}) {
    int named = 0;
    for (std::uint64_t seed = 1; seed <= 4; ++seed) {
      // At twice the drawn magnitudes (as the sensor bias's own test): named in most records.
      const DiscrepancyResult off = run(effect, seed, 1, false, 2.0, 40.0);
      if (off.verdict != "effects" || off.effects.size() != 1 || off.effects[0].name != effect) continue;
      ++named;
      const DiscrepancyResult on = run(effect, seed, 1, true, 2.0, 40.0);
      INFO(effect << " seed " << seed << ": " << on.verdict << ": " << on.summary);
      CHECK(on.verdict == "effects");
      CHECK((on.effects.size() == 1 && on.effects[0].name == effect));
    }
    INFO(effect);
    CHECK(named >= 2);  // the comparison is made on records where the name is given
  }
}
