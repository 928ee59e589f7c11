// The discrepancy workflow's family-wise false-alarm rate, measured on records where nothing is
// missing. An alarm is anything that sends a user looking: a name, `ambiguous`, `unexplained`.
// The records come from the in-test generator (discrepancy_generator.h), each with its own
// length, noise, gains and model set drawn by its seed, so the rate is not that of one setting
// the thresholds could have been fitted to. The thresholds are derived (ident/README.md "One
// error rate for every alarm"); this test measures what they give.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "core/config.h"
#include "core/proportion.h"
#include "discrepancy_generator.h"
#include "discrepancy/discrepancy.h"

using namespace nimble;
using namespace nimble::ident;

namespace {

struct NullRecord {
  int set = 1;
  test::GeneratorOptions options;
};

/// Record `i`'s settings: length 8-60 s (log-uniform), process noise x0.3-5 and measurement
/// noise x0.3-4 (log-uniform; p, v, phi and delta_f alike), each PD gain x0.7-1.3, model set 1-5,
/// the controller's command recorded in every other record (the actuator equation F joins).
NullRecord draw_null(int i) {
  std::mt19937_64 rng(static_cast<std::uint64_t>(i) * 2654435761u + 99u);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  auto log_uniform = [&](double lo, double hi) { return std::exp(std::log(lo) + u(rng) * std::log(hi / lo)); };
  NullRecord r;
  r.set = 1 + i % 5;
  test::GeneratorOptions& o = r.options;
  o.seed = static_cast<std::uint64_t>(20000 + i);
  o.duration_s = log_uniform(8.0, 60.0);
  const double process = log_uniform(0.3, 5.0), measurement = log_uniform(0.3, 4.0);
  o.moment_noise_Nm *= process;
  o.force_noise_N *= process;
  o.noise_p *= measurement;
  o.noise_v *= measurement;
  o.noise_phi *= measurement;
  o.noise_df *= measurement;
  o.k_phi *= 0.7 + 0.6 * u(rng);
  o.k_p *= 0.7 + 0.6 * u(rng);
  o.record_command = i % 2 == 1;
  return r;
}

}  // namespace

TEST_CASE(
    "discrepancy: over 240 null records of varied length, noise, gains and model set, at most 1 % raise an "
    "alarm (a name, ambiguous or unexplained)",
    "[discrepancy][null]") {
  const int records = 240;
  int alarms = 0;
  std::map<std::string, int> kinds;
  double bound_max = 0.0;
  for (int i = 0; i < records; ++i) {
    const NullRecord rec = draw_null(i);
    const test::ModelSet& ms = test::model_set(rec.set);
    const FlightData data = test::generate_flight(ms.model, ms.vehicle, {}, rec.options);
    const DiscrepancyResult r = find_discrepancy(data, ms.model, ms.vehicle, {});
    bound_max = std::max(bound_max, r.alarm_rule.family_wise);
    // Every record ran its location tests (the generator records phi_sp and delta_t).
    CHECK(r.located.excitation == std::vector<std::string>{"phi_sp", "delta_t"});
    const bool alarm = r.verdict != "none";
    if (!alarm) {
      CHECK(r.effects.empty());
      CHECK(r.located.frequency.empty());
      CHECK(r.located.state.empty());
      continue;
    }
    ++alarms;
    for (const auto& e : r.effects) ++kinds["name " + e.name];
    for (const auto& f : r.located.frequency) ++kinds["frequency " + f.output];
    for (const auto& f : r.located.state) ++kinds["state " + f.output + " on " + f.signal];
    std::printf("  null record %d (set %d, %.1f s): %s: %s\n", i, rec.set, rec.options.duration_s, r.verdict.c_str(),
                r.summary.c_str());
  }
  const Proportion rate = wilson(alarms, records);
  const double lo = rate.lo, hi = rate.hi;
  std::printf(
      "discrepancy null records: %d of %d raised an alarm (%.2f %%, 95 %% interval %.2f-%.2f %%); stated bound "
      "per record <= %.2g (tests x p_critical)\n",
      alarms, records, 100.0 * alarms / records, 100.0 * lo, 100.0 * hi, bound_max);
  for (const auto& [k, v] : kinds) std::printf("  %s: %d\n", k.c_str(), v);
  CHECK(static_cast<double>(alarms) / records <= 0.01);
}
