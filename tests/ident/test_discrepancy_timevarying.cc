// Tests of the discrepancy workflow's effects that change during a flight (effectiveness_drift,
// effectiveness_step; ident/README.md "Effects that change during a flight") on records from the
// generator independent of the plant code (discrepancy_generator.h).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
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

DiscrepancyResult run(const std::set<std::string>& effects, std::uint64_t seed) {
  test::HiddenEffects h;
  h.on = effects;
  test::draw_magnitudes(h, seed);
  test::GeneratorOptions o;
  o.seed = seed;
  return find_discrepancy(test::generate_flight(test::set1().model, test::set1().vehicle, h, o), test::set1().model,
                          test::set1().vehicle, {});
}

std::vector<std::string> names(const DiscrepancyResult& r) {
  std::vector<std::string> out;
  for (const auto& e : r.effects) out.push_back(e.name);
  return out;
}

/// The named effect called `name` (nullptr if none).
const NamedEffect* effect(const DiscrepancyResult& r, const std::string& name) {
  for (const auto& e : r.effects) {
    if (e.name == name) return &e;
  }
  return nullptr;
}

}  // namespace

TEST_CASE(
    "discrepancy: a hidden step of the flap input's effectiveness (-15..-40 % in the middle 60 % of a 40 s "
    "record, a damaged wing) is named with its change time inside its interval",
    "[discrepancy][timevarying]") {
  // The change time is located to the manoeuvres around it: between two doublets delta_f is
  // quiet and any t* there fits alike, which the interval shows. The fraction is conditional on
  // the named t*: reported, not held to its interval.
  const int seeds = 24;
  int hits = 0, covered = 0, fraction_covered = 0;
  double worst_s = 0.0;
  for (int s = 1; s <= seeds; ++s) {
    test::HiddenEffects h;
    h.on = {"effectiveness_step"};
    test::draw_magnitudes(h, static_cast<std::uint64_t>(s));
    const double t_true = h.step_at * test::GeneratorOptions{}.duration_s;
    const DiscrepancyResult r = run(h.on, static_cast<std::uint64_t>(s));
    INFO("seed " << s << " fraction " << h.step_fraction << " at " << t_true << " s: " << r.summary);
    CHECK(r.verdict != "ambiguous");
    for (const auto& n : names(r)) CHECK(n == "effectiveness_step");
    const NamedEffect* e = effect(r, "effectiveness_step");
    if (e == nullptr) continue;
    ++hits;
    const auto& p = e->parameters;
    INFO("named " << p.at("t_change_s") << " s in [" << p.at("t_change_lo_s") << ", " << p.at("t_change_hi_s")
                  << "], fraction " << p.at("fraction") << " in [" << p.at("fraction_lo") << ", " << p.at("fraction_hi")
                  << "]");
    covered += p.at("t_change_lo_s") <= t_true && t_true <= p.at("t_change_hi_s");
    fraction_covered += p.at("fraction_lo") <= h.step_fraction && h.step_fraction <= p.at("fraction_hi");
    worst_s = std::max(worst_s, std::fabs(p.at("t_change_s") - t_true));
    CHECK(std::fabs(p.at("t_change_s") - t_true) < 2.5);  // one doublet cycle of the generator (2.5 s)
    CHECK(std::fabs(p.at("fraction") - h.step_fraction) < 0.05);
    CHECK(r.gap_after < r.gap_before);
  }
  std::printf(
      "discrepancy effectiveness step: named in %d of %d records; change time inside its 95 %% interval in %d "
      "of %d, largest error %.2f s; fraction inside its interval in %d of %d\n",
      hits, seeds, covered, hits, worst_s, fraction_covered, hits);
  CHECK(hits >= 22);
  CHECK(covered >= hits - 2);
}

TEST_CASE(
    "discrepancy: a hidden drift of the flap input's effectiveness (-2..-8 %/min over a 120 s record, battery "
    "sag) is named with its rate inside its interval",
    "[discrepancy][timevarying]") {
  // A sag of a few percent per minute needs minutes: over 40 s the rate's standard deviation is
  // about 1.4 %/min on these records, so only the largest rates reach the partial-F rule; over
  // 120 s it is about 0.3 %/min. The Nimble flies about 5 min on a battery. The generator scales
  // from t = 0; the named rate is per minute of L_df at the record's middle: r / (1 + r t_mid / 60).
  const int seeds = 16;
  int hits = 0, covered = 0;
  for (int s = 1; s <= seeds; ++s) {
    test::HiddenEffects h;
    h.on = {"effectiveness_drift"};
    test::draw_magnitudes(h, static_cast<std::uint64_t>(s));
    test::GeneratorOptions o;
    o.seed = static_cast<std::uint64_t>(s);
    o.duration_s = 120.0;
    const DiscrepancyResult r = find_discrepancy(test::generate_flight(test::set1().model, test::set1().vehicle, h, o),
                                                 test::set1().model, test::set1().vehicle, {});
    INFO("seed " << s << " rate " << h.drift_per_min << " /min: " << r.summary);
    CHECK(r.verdict != "ambiguous");
    for (const auto& n : names(r)) CHECK(n == "effectiveness_drift");
    const NamedEffect* e = effect(r, "effectiveness_drift");
    if (e == nullptr) continue;
    ++hits;
    const auto& p = e->parameters;
    const double expected = h.drift_per_min / (1.0 + h.drift_per_min * p.at("t_mid_s") / 60.0);
    INFO("named " << p.at("rate_per_min") << " in [" << p.at("rate_per_min_lo") << ", " << p.at("rate_per_min_hi")
                  << "], expected " << expected);
    covered += p.at("rate_per_min_lo") <= expected && expected <= p.at("rate_per_min_hi");
    CHECK(std::fabs(p.at("rate_per_min") - expected) < 0.3 * std::fabs(expected) + 0.005);
  }
  std::printf(
      "discrepancy effectiveness drift: named in %d of %d 120 s records; rate inside its 95 %% interval in %d "
      "of %d\n",
      hits, seeds, covered, hits);
  CHECK(hits >= 14);
  CHECK(covered >= hits - 2);
}

TEST_CASE(
    "discrepancy: null records of 8-60 s under other noise and gains name no effect that changes during the "
    "record",
    "[discrepancy][null][timevarying]") {
  // Lengths drawn from 8-60 s, process noise x1/x2/x5, measurement noise x1/x2/x4 (delta_f's
  // too), three PD gain pairs, half the records with the recorded command: settings the entry
  // rules were not derived on. effectiveness_step is scanned over many t*; no t* may name it.
  const int records = 24;
  int named_tv = 0, named_any = 0, alarms = 0;
  for (int s = 1; s <= records; ++s) {
    std::mt19937_64 rng(static_cast<std::uint64_t>(1000 + s));
    test::GeneratorOptions o;
    o.seed = static_cast<std::uint64_t>(5000 + s);
    o.duration_s = 8.0 + 52.0 * std::uniform_real_distribution<double>(0.0, 1.0)(rng);
    const double process = std::vector<double>{1, 2, 5}[s % 3], measurement = std::vector<double>{1, 2, 4}[(s / 3) % 3];
    const std::size_t gains = static_cast<std::size_t>((s / 9) % 3);
    o.k_phi = std::vector<double>{80, 60, 100}[gains];
    o.k_p = std::vector<double>{15, 10, 20}[gains];
    o.moment_noise_Nm *= process;
    o.force_noise_N *= process;
    o.noise_p *= measurement;
    o.noise_v *= measurement;
    o.noise_phi *= measurement;
    o.noise_df *= measurement;
    o.record_command = s % 2 == 0;
    DiscrepancyOptions opt;
    opt.command_latency_s = 0.0;  // the generator's command path has no latency of its own
    const DiscrepancyResult r = find_discrepancy(test::generate_flight(test::set1().model, test::set1().vehicle, {}, o),
                                                 test::set1().model, test::set1().vehicle, opt);
    INFO("seed " << s << ", " << o.duration_s << " s: " << r.summary);
    CHECK(effect(r, "effectiveness_drift") == nullptr);
    CHECK(effect(r, "effectiveness_step") == nullptr);
    named_tv += effect(r, "effectiveness_drift") != nullptr || effect(r, "effectiveness_step") != nullptr;
    named_any += !r.effects.empty();
    alarms += r.verdict != "none";  // a name, ambiguous or unexplained
    if (r.verdict != "none") std::printf("  alarm: seed %d: %s\n", s, r.summary.c_str());
  }
  std::printf(
      "discrepancy null records of 8-60 s: %d of %d named a time-varying effect, %d named any effect, %d raised "
      "any alarm\n",
      named_tv, records, named_any, alarms);
}
