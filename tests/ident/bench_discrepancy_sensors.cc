// The discrepancy workflow's data-compatibility stage (discrepancy/data_compatibility.h) on records whose
// gyro has its own errors: a scale factor (5-15 %, either sign), a time offset against the attitude
// (10-50 ms, either sign), a clock drift (100-500 ppm), a bias (0.02-0.06 rad/s), three at once, a
// sensor error beside an aerodynamic effect, and records with an actuator delay (which must not be
// taken for a time offset) and where nothing is missing. Each
// record draws its magnitude (discrepancy_generator.h), length (20-40 s), model set (1-5) and seed.
//
// A measurement, not a test: per case it prints how often the error is named (with the right
// sign), how often the true value lies inside the 95 % interval, the value's error, every other
// name given (a wrong name: an aerodynamic effect, a term, or another sensor error), and for the
// nulls every alarm (a name, `ambiguous`, `unexplained`); and the stage's time per record.
//   build/bin/bench_discrepancy_sensors [records per case, default 20] [null records, default 200]
//   build/bin/bench_discrepancy_sensors --stress N   (the stage alone on records of varied noise, gains, length)

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "core/proportion.h"
#include "discrepancy_generator.h"
#include "discrepancy/data_compatibility.h"
#include "discrepancy/discrepancy.h"

using namespace nimble;
using namespace nimble::ident;

namespace {

struct Case {
  std::vector<std::string> hidden;  ///< the generator's effects; none for the nulls
  std::vector<std::string> names;   ///< the names they should get
};

const std::vector<Case>& cases() {
  static const std::vector<Case> c{
      {{"sensor_scale"}, {"sensor_scale"}},
      {{"time_offset"}, {"time_offset"}},
      {{"clock_drift"}, {"clock_drift"}},
      {{"sensor_bias"}, {"sensor_bias"}},
      {{"actuator_delay"}, {"actuator_delay"}},
      {{"sensor_scale", "time_offset", "sensor_bias"}, {"sensor_scale", "time_offset", "sensor_bias"}},
      {{"time_offset", "actuator_delay"}, {"time_offset", "actuator_delay"}},
      {{"sensor_scale", "lateral_inflow"}, {"sensor_scale", "lateral_inflow"}}};
  return c;
}

double truth_of(const test::HiddenEffects& h, const std::string& name) {
  if (name == "sensor_scale") return h.scale_k;
  if (name == "time_offset") return h.offset_s;
  if (name == "clock_drift") return h.drift_ppm;
  if (name == "sensor_bias") return h.bias_p;
  if (name == "lateral_inflow") return h.Y_vv;
  return h.delay_s;
}

double value_of(const NamedEffect& e) {
  if (e.name == "actuator_delay") return e.parameters.at("delay_s");
  if (e.name == "lateral_inflow") return e.parameters.at("Y_vv");
  return e.coefficient;
}

struct Record {
  FlightData data;
  test::HiddenEffects h;
  const test::ModelSet* set = nullptr;
  double duration_s = 0.0;
};

Record make(const std::vector<std::string>& hidden, std::uint64_t seed, int i) {
  Record r;
  std::mt19937_64 rng(seed * 31u + 11u);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  r.set = &test::model_set(1 + i % 5);
  r.h.on.insert(hidden.begin(), hidden.end());
  test::draw_magnitudes(r.h, seed);
  test::GeneratorOptions o;
  o.seed = seed;
  o.duration_s = r.duration_s = 20.0 + 20.0 * u(rng);
  r.data = test::generate_flight(r.set->model, r.set->vehicle, r.h, o);
  return r;
}

/// --stress N: the stage alone (check_compatibility) on N records per error and N nulls whose noise,
/// gains and length vary beyond the generator's defaults (phi noise x1-7, p noise x1-5, process
/// noise x1-5, PD gains x0.6-1.4, 8-120 s, most of them short): alarms where nothing is set, and
/// how often each error is named and its true value covered.
int stress(int n) {
  const DiscrepancyOptions opt;
  for (const char* hidden : {"", "time_offset", "sensor_scale", "clock_drift", "sensor_bias"}) {
    int alarms = 0, named = 0, covered = 0;
    for (int i = 0; i < n; ++i) {
      const std::uint64_t seed = 5000u + static_cast<std::uint64_t>(i);
      std::mt19937_64 rng(seed);
      std::uniform_real_distribution<double> u(0.0, 1.0);
      test::HiddenEffects h;
      if (*hidden) h.on = {hidden};
      test::draw_magnitudes(h, seed);
      test::GeneratorOptions o;
      o.seed = seed;
      o.duration_s = 8.0 + 112.0 * u(rng) * u(rng);
      o.noise_phi *= 1.0 + 6.0 * u(rng);
      o.noise_p *= 1.0 + 4.0 * u(rng);
      o.moment_noise_Nm *= 1.0 + 4.0 * u(rng);
      o.force_noise_N *= 1.0 + 4.0 * u(rng);
      const double gain = 0.6 + 0.8 * u(rng);
      o.k_phi *= gain;
      o.k_p *= gain;
      const test::ModelSet& ms = test::model_set(1 + i % 5);
      const CompatibilityResult c = check_compatibility(test::generate_flight(ms.model, ms.vehicle, h, o),
                                                        opt.processing, opt.compatibility, 7.74e-6, opt.folds, 16);
      bool other = false;
      for (const SensorError& e : c.errors) {
        if (!e.significant) continue;
        if (e.name != hidden) {
          other = true;
          continue;
        }
        const double truth = truth_of(h, e.name);
        named += e.named && e.value * truth > 0.0;
        covered += e.named && e.interval[0] <= truth && truth <= e.interval[1];
      }
      alarms += other;
    }
    std::printf("stress %-13s %4d records: named %4d, true value covered %4d, other errors significant in %d\n",
                *hidden ? hidden : "(nothing)", n, named, covered, alarms);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc > 2 && std::string(argv[1]) == "--stress") return stress(std::max(1, std::atoi(argv[2])));
  const int per_case = argc > 1 ? std::max(1, std::atoi(argv[1])) : 20;
  const int nulls = argc > 2 ? std::max(0, std::atoi(argv[2])) : 200;
  const DiscrepancyOptions opt;
  double stage_s = 0.0;
  int stage_runs = 0;
  std::printf(
      "case (hidden -> name)              records  named (right sign)  true value in 95 %% interval  median |error|  "
      "records with a wrong name\n");
  int index = 0;
  for (const Case& c : cases()) {
    std::map<std::string, int> named, inside;
    std::map<std::string, std::vector<double>> err;
    std::map<std::string, int> wrongs;
    int wrong = 0;
    for (int i = 0; i < per_case; ++i) {
      const std::uint64_t seed = 91000u + 1000u * static_cast<std::uint64_t>(index) + static_cast<std::uint64_t>(i);
      const Record rec = make(c.hidden, seed, i);
      const auto t0 = std::chrono::steady_clock::now();
      (void)check_compatibility(rec.data, opt.processing, opt.compatibility, 7.74e-6, opt.folds, 16);
      stage_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      ++stage_runs;
      const DiscrepancyResult r = find_discrepancy(rec.data, rec.set->model, rec.set->vehicle, opt);
      std::string said;
      std::set<std::string> got;
      for (const auto& e : r.effects) {
        const bool expected = std::find(c.names.begin(), c.names.end(), e.name) != c.names.end();
        const double truth = expected ? truth_of(rec.h, e.name) : 0.0, v = value_of(e);
        if (expected && !got.count(e.name) && v * truth > 0.0) {
          got.insert(e.name);
          ++named[e.name];
          err[e.name].push_back(std::fabs(v - truth));
          if (e.interval[0] <= truth && truth <= e.interval[1]) ++inside[e.name];
        } else {
          said += " " + (e.name == "term" ? "term " + e.equation + " " + e.expression : e.name);
        }
      }
      if (!said.empty()) {
        ++wrong;
        ++wrongs[said];
      }
      if (got.size() < c.names.size() || !said.empty()) {
        std::printf("  %s record %d (seed %llu, %.1f s): %s: %s\n", c.names.front().c_str(), i,
                    static_cast<unsigned long long>(seed), rec.duration_s, r.verdict.c_str(), r.summary.c_str());
      }
    }
    for (std::size_t k = 0; k < c.names.size(); ++k) {
      const std::string& name = c.names[k];
      std::string label = k == 0 ? "" : "  ";
      for (const auto& hname : c.hidden) label += (label.size() > 2 || (k == 0 && !label.empty()) ? "+" : "") + hname;
      label = (k == 0 ? label : "  ") + " -> " + name;
      auto& e = err[name];
      std::sort(e.begin(), e.end());
      const Proportion pn = wilson(named[name], per_case);
      const bool interval = name != "actuator_delay" && name != "lateral_inflow";  // model effects: no interval field
      char cover[32] = "-";
      if (interval) std::snprintf(cover, sizeof cover, "%d of %d", inside[name], named[name]);
      std::printf("%-38s %4d  %4d %5.1f%% [%4.1f,%5.1f]  %-10s  %.3g  %s\n", label.c_str(), per_case, named[name],
                  100.0 * named[name] / per_case, 100.0 * pn.lo, 100.0 * pn.hi, cover,
                  e.empty() ? 0.0 : e[e.size() / 2], k == 0 ? std::to_string(wrong).c_str() : "");
    }
    for (const auto& [w, k] : wrongs) std::printf("      wrong:%s x%d\n", w.c_str(), k);
    ++index;
  }
  int alarms = 0;
  std::map<std::string, int> said;
  for (int i = 0; i < nulls; ++i) {
    const std::uint64_t seed = 97000u + static_cast<std::uint64_t>(i);
    const Record rec = make({}, seed, i);
    const DiscrepancyResult r = find_discrepancy(rec.data, rec.set->model, rec.set->vehicle, opt);
    if (r.verdict != "none") {
      ++alarms;
      std::string s = r.verdict + ":";
      for (const auto& e : r.effects) s += " " + e.name;
      ++said[s];
      std::printf("  null record %d (seed %llu): %s: %s\n", i, static_cast<unsigned long long>(seed), r.verdict.c_str(),
                  r.summary.c_str());
    }
  }
  if (nulls > 0) {
    const Proportion pa = wilson(alarms, nulls);
    std::printf("nulls: %d alarms in %d records (%.2f %%, 95 %% upper %.2f %%; target <= 1 %%)\n", alarms, nulls,
                100.0 * alarms / nulls, 100.0 * pa.hi);
    for (const auto& [s, k] : said) std::printf("      %s x%d\n", s.c_str(), k);
  }
  std::printf("compatibility stage: %.1f ms per record (%d records of 20-40 s)\n",
              1e3 * stage_s / std::max(1, stage_runs), stage_runs);
  return 0;
}
