// The discrepancy workflow on the effects its library knows: how often each is named exactly
// (the verdict `effects` with that one name and nothing beside it: no second effect, no `term`),
// with the workflow's defaults (signature checks and the open-world term search on) or, with
// --closed-world, without them (the workflow before its signatures and term search), so that the two can be set side
// by side. Each record draws its magnitude (discrepancy_generator.h's ranges), length (20-40 s;
// 120 s for the drift, which is per minute), model set (1-5) and seed; the command delay's
// records carry the controller's command, which is the only place it shows.
//
// A measurement, not a test: it prints per effect the count, rate and 95 % Wilson interval of
// exact names, other verdicts and what else was named, beside the target of 99 % exact.
//   build/bin/bench_discrepancy_library [--closed-world] [records per effect, default 20]

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "core/proportion.h"
#include "discrepancy_generator.h"
#include "discrepancy/discrepancy.h"

using namespace nimble;
using namespace nimble::ident;

namespace {

/// A hidden library effect, the name the workflow should give it, and its records' setting.
struct LibraryCase {
  const char* hidden;
  const char* name;
  bool record_command;
  double min_s, max_s;
};

const std::vector<LibraryCase>& library_cases() {
  static const std::vector<LibraryCase> cases{
      {"lateral_inflow", "lateral_inflow", false, 20.0, 40.0},
      {"kinematic_coupling", "kinematic_coupling", false, 20.0, 40.0},
      {"forward_speed_coupling", "forward_speed_coupling", false, 20.0, 40.0},
      {"actuator_delay", "actuator_delay", false, 20.0, 40.0},
      {"command_delay", "actuator_delay", true, 20.0, 40.0},
      {"sensor_bias", "sensor_bias", false, 20.0, 40.0},
      {"constant_load", "constant_load", false, 20.0, 40.0},
      {"flapping_forcing", "flapping_forcing", false, 20.0, 40.0},
      {"effectiveness_step", "effectiveness_step", false, 30.0, 40.0},
      {"effectiveness_drift", "effectiveness_drift", false, 120.0, 120.0},
  };
  return cases;
}

}  // namespace

int main(int argc, char** argv) {
  DiscrepancyOptions opt;
  bool closed = false;
  int per_effect = 20;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--closed-world") {
      closed = true;
      opt.signature_checks = false;
      opt.term_search = false;
    } else {
      per_effect = std::max(1, std::atoi(a.c_str()));
    }
  }
  int all = 0, all_exact = 0;
  double seconds = 0.0;
  std::vector<std::string> rows;
  int index = 0;
  for (const LibraryCase& c : library_cases()) {
    int exact = 0, none = 0, unexplained = 0, other = 0;
    std::map<std::string, int> others;
    for (int i = 0; i < per_effect; ++i) {
      const std::uint64_t seed = 70000u + 1000u * static_cast<std::uint64_t>(index) + static_cast<std::uint64_t>(i);
      std::mt19937_64 rng(seed * 31u + 11u);
      std::uniform_real_distribution<double> u(0.0, 1.0);
      const test::ModelSet& ms = test::model_set(1 + i % 5);
      test::HiddenEffects h;
      h.on = {c.hidden};
      test::draw_magnitudes(h, seed);
      test::GeneratorOptions o;
      o.seed = seed;
      o.duration_s = c.min_s + (c.max_s - c.min_s) * u(rng);
      o.record_command = c.record_command;
      const FlightData data = test::generate_flight(ms.model, ms.vehicle, h, o);
      const auto t0 = std::chrono::steady_clock::now();
      const DiscrepancyResult r = find_discrepancy(data, ms.model, ms.vehicle, opt);
      seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      const bool is_exact = r.verdict == "effects" && r.effects.size() == 1 && r.effects.front().name == c.name;
      if (is_exact) {
        ++exact;
      } else if (r.verdict == "none") {
        ++none;
      } else if (r.verdict == "unexplained") {
        ++unexplained;
      } else {
        ++other;
      }
      if (!is_exact) {
        std::string said = r.verdict + ":";
        for (const auto& e : r.effects)
          said += " " + (e.name == "term" ? "term " + e.equation + " " + e.expression : e.name);
        ++others[said];
        std::printf("  %s record %d (seed %llu, %.1f s): %s: %s\n", c.hidden, i, static_cast<unsigned long long>(seed),
                    o.duration_s, r.verdict.c_str(), r.summary.c_str());
      }
    }
    const Proportion p = wilson(exact, per_effect);
    char row[512];
    std::snprintf(row, sizeof row, "%-24s %4d  %4d %5.1f%% [%5.1f,%5.1f]  none %2d  unexplained %2d  other %2d",
                  c.hidden, per_effect, exact, 100.0 * exact / per_effect, 100.0 * p.lo, 100.0 * p.hi, none,
                  unexplained, other);
    std::string line = row;
    for (const auto& [said, k] : others) line += "\n      " + said + " x" + std::to_string(k);
    rows.push_back(line);
    all += per_effect;
    all_exact += exact;
    ++index;
  }
  std::printf("\nlibrary effects, %s: records, named exactly (count, %%, 95 %% interval), the rest\n",
              closed ? "closed world (no signature checks, no term search)" : "the workflow's defaults");
  for (const auto& r : rows) std::printf("%s\n", r.c_str());
  const Proportion p = wilson(all_exact, all);
  std::printf(
      "all: %d of %d named exactly (%.1f %%, 95 %% %.1f-%.1f %%; target 99 %%); workflow time %.2f s (%.3f s per "
      "record)\n",
      all_exact, all, 100.0 * all_exact / all, 100.0 * p.lo, 100.0 * p.hi, seconds, seconds / all);
  return 0;
}
