/// bench_turbulence: time of the rig turbulence work (both systems: exact discretisation,
/// a 10-minute record at 100 Hz, periodogram, Welch, analytical and sampled PSDs, the five
/// variances with their uncertainties, Table 2.1 and 5.1), median over repetitions, in thread
/// CPU time. As a machine floor measured in the same run: a plain loop of as many 10 x 10
/// matrix-vector products as the record has samples per system (2 x 60000), and the ratio.
///   bench_turbulence [repetitions]      (default 5)

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "core/bench_timing.h"
#include "turbulence/ce500_analysis.h"
#include "turbulence/ce500_config.h"

int main(int argc, char** argv) {
  using namespace nimble;
  using namespace nimble::turbulence;
  const int reps = bench_repetitions(argc, argv,
                                     "usage: bench_turbulence [REPETITIONS (default 5)]\n"
                                     "  Times rig turbulence's work on a 10-minute record at 100 Hz against the\n"
                                     "  machine's floor measured in the same run.\n",
                                     5);
  if (reps < 0) return -reps - 1;
  const Ce500Config config =
      load_ce500_config(std::string(RIG_SOURCE_DIR) + "/rig_configs/turbulence/ce500_practical.yaml");
  Ce500Options options = ce500_default_options(config);
  options.dt_s = 0.01;         // 100 Hz
  options.duration_s = 600.0;  // 10 minutes
  const std::size_t samples = 60000;

  std::vector<double> work_ms;
  double checksum = 0.0;
  for (int r = 0; r < reps; ++r) {
    const double t0 = thread_cpu_ms();
    const Ce500Analysis a = analyse_ce500(config, options);
    work_ms.push_back(thread_cpu_ms() - t0);
    checksum += a.controlled.variances[0].welch.value;
  }

  // Floor: the same number of 10 x 10 matrix-vector products (two systems), nothing else.
  const Eigen::MatrixXd Phi = Eigen::MatrixXd::Random(10, 10) * 0.3;
  std::vector<double> floor_ms;
  for (int r = 0; r < reps; ++r) {
    Eigen::VectorXd x = Eigen::VectorXd::Ones(10);
    const double t0 = thread_cpu_ms();
    for (std::size_t k = 0; k < 2 * samples; ++k) {
      x = Phi * x;
      x[0] += 1.0;
    }
    floor_ms.push_back(thread_cpu_ms() - t0);
    checksum += x.sum();
  }
  const double work = median(work_ms), floor = median(floor_ms);
  std::printf("bench_turbulence: rig turbulence work, 10-minute record at 100 Hz (%zu samples), controlled + reduced\n",
              samples);
  std::printf("  work (median of %d): %.1f ms   target < 1000 ms: %s\n", reps, work, work < 1000.0 ? "met" : "NOT met");
  std::printf("  floor: %zu plain 10x10 matrix-vector products: %.3f ms\n", 2 * samples, floor);
  std::printf("  ratio work / floor: %.0f\n", work / floor);
  std::printf("  (checksum %.6g)\n", checksum);
  return 0;
}
