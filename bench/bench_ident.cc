/// bench_ident: time of the OLS + WLS regression of the lateral3 structure on
/// 60 s of synthetic flight data at 512 Hz (about 30 k samples), median over
/// repetitions; also the whole identify() pipeline for reference.
///   bench_ident [repetitions]      (default 21)

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "contract/default_rates.h"
#include "core/bench_timing.h"
#include "core/model.h"
#include "core/vehicle.h"
#include "ident/identify.h"
#include "ident/synthetic.h"

namespace {

using Clock = std::chrono::steady_clock;

}  // namespace

int main(int argc, char** argv) {
  using namespace nimble;
  using namespace nimble::ident;
  const int reps = bench_repetitions(argc, argv,
                                     "usage: bench_ident [REPETITIONS (default 21)]\n"
                                     "  Times the identification of a 60 s, 512 Hz synthetic flight: OLS + WLS\n"
                                     "  regression (target <= 50 ms) and the whole identify(), against this\n"
                                     "  machine's floor measured in the same run.\n",
                                     21);
  if (reps < 0) return -reps - 1;
  const std::string configs = std::string(NIMBLE_SOURCE_DIR) + "/rig_configs/";
  const DerivativeModel model = load_model(configs + "models/nimble_lateral_set1.yaml");
  const Vehicle vehicle = load_vehicle(model.vehicle_file);

  SyntheticOptions so;
  so.duration_s = 60.0;
  so.rate_hz = contract::kDefaultImuRateHz;
  so.moment_noise_Nm = 2e-4;
  so.force_noise_N = 2e-3;
  so.noise_p_radps = 0.02;
  so.noise_v_mps = 0.005;
  so.noise_phi_rad = 0.002;
  const FlightData data = simulate_synthetic(model, vehicle, so);

  IdentOptions opt;
  opt.trim = model.trim;
  const PreparedData prepared = prepare(data, opt.structure, opt.trim, vehicle.gravity_mps2, opt.processing);
  const std::vector<Equation> eqs = lateral_equations(opt.structure, {"delta_f", "delta_t"}, vehicle);
  WlsOptions wls;
  wls.variance_window = static_cast<Eigen::Index>(opt.wls_window_s * opt.processing.rate_hz);

  CovarianceOptions cov;
  cov.correlation_lags = static_cast<Eigen::Index>(coloured_lags(0, opt.processing));
  std::vector<double> regression_ms, cpu_ms, ols_ms, wls_ms, pipeline_ms;
  double sink = 0.0;
  for (int i = 0; i < reps; ++i) {
    const double c0 = thread_cpu_ms();
    const auto t0 = Clock::now();
    const RegressionResult ols = estimate_ols(prepared.filtered.signals, eqs, cov);
    const auto t1 = Clock::now();
    const RegressionResult w = estimate_wls(prepared.filtered.signals, eqs, wls, cov);
    const auto t2 = Clock::now();
    cpu_ms.push_back(thread_cpu_ms() - c0);
    sink += ols.equations[0].theta[0] + w.equations[0].theta[0];
    ols_ms.push_back(elapsed_ms(t0, t1));
    wls_ms.push_back(elapsed_ms(t1, t2));
    regression_ms.push_back(elapsed_ms(t0, t2));
  }
  for (int i = 0; i < std::min(reps, 5); ++i) {
    const auto t0 = Clock::now();
    const IdentResult r = identify(data, vehicle, model.vehicle_file, opt);
    const auto t1 = Clock::now();
    sink += r.eigenvalues.front().real();
    pipeline_ms.push_back(elapsed_ms(t0, t1));
  }
  std::printf("bench_ident: lateral3, %ld samples (%.0f s at %.0f Hz), %d repetitions\n",
              static_cast<long>(prepared.filtered.size()), so.duration_s, so.rate_hz, reps);
  const TimingSpread regression = timing_spread(regression_ms);
  std::printf("  OLS + WLS regression: median %.2f ms (min %.2f, max %.2f); target <= 50 ms\n", regression.median,
              regression.min, regression.max);
  std::printf("    CPU time of the same: median %.2f ms\n", median(cpu_ms));
  std::printf("    OLS median %.2f ms, WLS (its own OLS pass, weights, GLS) median %.2f ms\n", median(ols_ms),
              median(wls_ms));
  std::printf("  whole identify() (resample, filter, differentiate, WLS, metrics, PSDs, modes): median %.1f ms\n",
              median(pipeline_ms));
  return sink == 12345.678 ? 1 : 0;  // keeps the results alive
}
