// bench_discrepancy: the whole discrepancy workflow (gap, location, every candidate with the
// actuator_delay scan, stepwise rounds, the signatures, the open-world term search, refit,
// held-out gap) on 60 s at 512 Hz of a generated
// record with two hidden effects and the recorded command (three equations: L, Y and the flap
// actuator's F). Prints figures; not a test. The machine's floor in the same run: one OLS
// regression of the two baseline L and Y equations on the same prepared data
// (ident::estimate_ols), and the ratio of the two. The term search's cost is reported on its own:
// the workflow timed again without it (DiscrepancyOptions::term_search), the difference.
//   build/bin/bench_discrepancy [repetitions]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "core/bench_timing.h"
#include "discrepancy_generator.h"
#include "discrepancy/data_compatibility.h"
#include "discrepancy/discrepancy.h"
#include "ident/identify.h"

using namespace nimble;
using namespace nimble::ident;
using Clock = std::chrono::steady_clock;

int main(int argc, char** argv) {
  const int reps = bench_repetitions(argc, argv,
                                     "usage: bench_discrepancy [REPETITIONS (default 5)]\n"
                                     "  Times the discrepancy workflow on a 60 s flight with two hidden effects,\n"
                                     "  against the machine's floor (one identification) in the same run.\n",
                                     5);
  if (reps < 0) return -reps - 1;
  const DerivativeModel model =
      load_model(std::string(RIG_SOURCE_DIR) + "/rig_configs/models/nimble_lateral_set1.yaml");
  const Vehicle vehicle = load_vehicle(model.vehicle_file);
  test::HiddenEffects h;
  h.on = {"kinematic_coupling", "forward_speed_coupling"};
  test::draw_magnitudes(h, 1);
  test::GeneratorOptions o;
  o.duration_s = 60.0;
  o.record_command = true;  // with the actuator equation, as on a rig log
  const FlightData data = test::generate_flight(model, vehicle, h, o);

  // The data-compatibility stage: on the same record (nothing to correct) and on one whose gyro is
  // 5 % off and 30 ms late (corrected, with the baseline's gap on the record as recorded).
  test::HiddenEffects hs = h;
  hs.on.insert({"sensor_scale", "time_offset"});
  hs.scale_k = 0.05;
  hs.offset_s = 0.030;
  const FlightData sensed = test::generate_flight(model, vehicle, hs, o);
  std::vector<double> stage_ms, added_ms;
  for (int i = 0; i < reps; ++i) {
    const DiscrepancyOptions d;
    const auto t0 = Clock::now();
    const CompatibilityResult c = check_compatibility(data, d.processing, d.compatibility, 7.74e-6, d.folds, 16);
    stage_ms.push_back(elapsed_ms(t0, Clock::now()));
    if (!c.ran) return 1;
    const DiscrepancyResult r = find_discrepancy(sensed, model, vehicle, {});
    if (r.compatibility.size() != 1 || r.compatibility.front().corrections.empty()) return 1;
    added_ms.push_back(r.compatibility.front().elapsed_ms);
  }

  std::vector<double> workflow_ms, closed_ms, floor_ms;
  DiscrepancyResult last;
  DiscrepancyOptions no_terms;
  no_terms.term_search = false;
  for (int i = 0; i < reps; ++i) {
    const auto t0 = Clock::now();
    last = find_discrepancy(data, model, vehicle, {});
    const auto t1 = Clock::now();
    workflow_ms.push_back(elapsed_ms(t0, t1));
    const auto tc = Clock::now();
    find_discrepancy(data, model, vehicle, no_terms);
    closed_ms.push_back(elapsed_ms(tc, Clock::now()));
    const PreparedData prep = prepare(data, Structure::kLateral3, model.trim, vehicle.gravity_mps2, {});
    const auto eqs = lateral_equations(Structure::kLateral3, model.inputs, vehicle);
    const auto t2 = Clock::now();
    const RegressionResult r = estimate_ols(prep.filtered.signals, eqs);
    const auto t3 = Clock::now();
    floor_ms.push_back(elapsed_ms(t2, t3));
    if (r.equations.empty()) return 1;
  }
  std::printf("bench_discrepancy: %zu samples (60 s at 512 Hz), %d repetitions, verdict %s:", last.samples, reps,
              last.verdict.c_str());
  for (const auto& e : last.effects) std::printf(" %s", e.name.c_str());
  const TimingSpread workflow = timing_spread(workflow_ms);
  std::printf("\n  whole workflow: median %.0f ms (min %.0f, max %.0f); target <= 1000 ms\n", workflow.median,
              workflow.min, workflow.max);
  std::printf("  of which the open-world term search: median %.0f ms (the workflow without it: %.0f ms)\n",
              workflow.median - median(closed_ms), median(closed_ms));
  std::printf(
      "  data-compatibility stage: the check on the record, median %.1f ms; the whole stage in the workflow on a "
      "record it corrects (gyro 5 %% off, 30 ms late: check, correction, the baseline's error as recorded), "
      "median %.1f ms; target <= 100 ms\n",
      median(stage_ms), median(added_ms));
  std::printf("  machine floor, one OLS of the baseline L and Y equations: median %.2f ms; workflow / floor = %.0f\n",
              median(floor_ms), median(workflow_ms) / median(floor_ms));
  return 0;
}
