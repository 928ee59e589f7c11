// Tests of the discrepancy workflow on several flights at once (find_discrepancy of a vector of
// flights, rig discrepancy a b c ...): records from the in-test generator (discrepancy_generator.h).

#include <algorithm>
#include <cstdio>
#include <set>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "core/config.h"
#include "discrepancy_generator.h"
#include "discrepancy/discrepancy.h"

using namespace nimble;
using namespace nimble::ident;

namespace {

/// A flight with `effects` at `scale` of the magnitudes drawn by `magnitude_seed`, its noise by `seed`.
FlightData flight(const std::set<std::string>& effects, std::uint64_t magnitude_seed, std::uint64_t seed,
                  double duration_s, double scale = 1.0) {
  test::HiddenEffects h;
  h.on = effects;
  h.scale = scale;
  test::draw_magnitudes(h, magnitude_seed);
  test::GeneratorOptions o;
  o.seed = seed;
  o.duration_s = duration_s;
  FlightData d = test::generate_flight(test::set1().model, test::set1().vehicle, h, o);
  d.source = "flight" + std::to_string(seed);
  return d;
}

bool named(const DiscrepancyResult& r, const std::string& name) {
  return std::any_of(r.effects.begin(), r.effects.end(), [&](const NamedEffect& e) { return e.name == name; });
}

}  // namespace

TEST_CASE("discrepancy pool: a lateral inflow too weak to name on one 12 s record is named on three pooled",
          "[discrepancy][pool]") {
  int single = 0, pooled = 0;
  const int seeds = 6;
  for (std::uint64_t s = 1; s <= static_cast<std::uint64_t>(seeds); ++s) {
    std::vector<FlightData> flights;
    for (std::uint64_t k = 0; k < 3; ++k) {
      flights.push_back(flight({"lateral_inflow"}, s, 100 * s + k, 12.0));
      single += named(find_discrepancy(flights.back(), test::set1().model, test::set1().vehicle, {}), "lateral_inflow");
    }
    const DiscrepancyResult r = find_discrepancy(flights, test::set1().model, test::set1().vehicle, {});
    INFO("seed " << s << ": " << r.summary);
    // Each flight listed with its rows and noise; its own estimate of what was named.
    REQUIRE(r.flights.size() == 3);
    for (const auto& f : r.flights) {
      CHECK(f.samples > 6000);
      CHECK(f.noise.count("L") == 1);
      CHECK(f.noise.count("Y") == 1);
    }
    CHECK(r.folds == 10);
    if (named(r, "lateral_inflow")) {
      ++pooled;
      CHECK(r.flights.front().parameters.count("Y_vv") == 1);
      REQUIRE(r.consistency.size() == r.effects.size());
      CHECK(r.consistency.front().effect == "lateral_inflow");
    }
  }
  std::printf("discrepancy pool: lateral inflow on 12 s records named alone in %d of %d, pooled by three in %d of %d\n",
              single, 3 * seeds, pooled, seeds);
  CHECK(single <= seeds);  // at most a third of the single records
  CHECK(pooled >= seeds - 2);
}

TEST_CASE("discrepancy pool: flights with the same effect agree, a flight with three times it is the one that differs",
          "[discrepancy][pool]") {
  int same = 0, caught = 0;
  const int seeds = 4;
  for (std::uint64_t s = 1; s <= static_cast<std::uint64_t>(seeds); ++s) {
    std::vector<FlightData> flights;
    for (std::uint64_t k = 0; k < 3; ++k) flights.push_back(flight({"forward_speed_coupling"}, s, 10 * s + k, 30.0));
    const DiscrepancyResult r = find_discrepancy(flights, test::set1().model, test::set1().vehicle, {});
    INFO("seed " << s << ": " << r.summary);
    REQUIRE(named(r, "forward_speed_coupling"));
    const auto c = std::find_if(r.consistency.begin(), r.consistency.end(),
                                [](const FlightConsistency& x) { return x.effect == "forward_speed_coupling"; });
    REQUIRE(c != r.consistency.end());
    same += c->same;

    flights.back() = flight({"forward_speed_coupling"}, s, 10 * s + 2, 30.0, 3.0);
    const DiscrepancyResult d = find_discrepancy(flights, test::set1().model, test::set1().vehicle, {});
    INFO("with the third at 3x: " << d.summary);
    const auto cd = std::find_if(d.consistency.begin(), d.consistency.end(),
                                 [](const FlightConsistency& x) { return x.effect == "forward_speed_coupling"; });
    REQUIRE(cd != d.consistency.end());
    caught += !cd->same && cd->differs == flights.back().source;
  }
  std::printf(
      "discrepancy pool: 3 flights with the same forward-speed coupling agree in %d of %d; with one at 3x, "
      "that one is found in %d of %d\n",
      same, seeds, caught, seeds);
  CHECK(same >= seeds - 1);
  CHECK(caught >= seeds - 1);
}

TEST_CASE("discrepancy pool: three null flights raise no alarm", "[discrepancy][pool][null]") {
  for (std::uint64_t s = 1; s <= 4; ++s) {
    std::vector<FlightData> flights;
    for (std::uint64_t k = 0; k < 3; ++k)
      flights.push_back(flight({}, s, 1000 * s + k, 10.0 + 8.0 * static_cast<double>(k)));
    const DiscrepancyResult r = find_discrepancy(flights, test::set1().model, test::set1().vehicle, {});
    INFO("seed " << s << ": " << r.summary);
    CHECK(r.verdict == "none");
    CHECK(r.flights.size() == 3);
    CHECK(r.consistency.empty());
  }
}
