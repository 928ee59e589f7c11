// The fixed-interval smoother (estimator/smoother.h) against the truth of an offline sensing run:
// the same recorded IMU samples and motion-capture frames the real-time filter used, smoothed
// after the flight.

#include <algorithm>
#include <cmath>

#include <catch2/catch.hpp>

#include "estimator/sensing_config.h"
#include "estimator/smoother.h"
#include "sensing_simulation.h"

using namespace nimble;

namespace {

struct ErrorFigures {
  double rms = 0.0;     ///< rms error of the channel
  double lag_ms = 0.0;  ///< least-squares delay of the estimate behind the truth: e = -lag x_dot
};

/// Error of channel `k` of the estimates against the truth records (same IMU instants): rms, and
/// the delay from the regression of the error on the truth's derivative.
ErrorFigures figures(const std::vector<SensingRecord>& truth, const std::vector<double>& estimate, int k, double dt_s) {
  double se = 0, sxd = 0, sxdxd = 0;
  int n = 0;
  for (std::size_t i = 1; i + 1 < truth.size(); ++i) {
    const double e = estimate[i] - truth[i].truth[k];
    const double xd = (truth[i + 1].truth[k] - truth[i - 1].truth[k]) / (2 * dt_s);
    se += e * e;
    sxd += e * xd;
    sxdxd += xd * xd;
    ++n;
  }
  return {std::sqrt(se / n), -1e3 * sxd / sxdxd};
}

}  // namespace

TEST_CASE(
    "smoother: on recorded IMU and motion capture its v and phi are closer to the truth than the filter's, "
    "and do not lag it",
    "[smoother]") {
  SensingRunConfig c;
  c.duration_s = 12.0;
  c.profile = make_roll_doublet_profile(41, c.duration_s);
  c.sensing.seed = 41;
  {
    const SensingRunResult r = run_sensing_simulation(c);
    SmootherReport report;
    const std::vector<SmoothedSample> s =
        smooth_flight(smoother_ekf_config(c.sensing), c.sensing.velocity_differentiator, r.imu, r.poses, &report);
    REQUIRE(s.size() > r.imu.size() * 9 / 10);
    CHECK(report.measurements > 0);
    CHECK(report.counters.measurements_too_old == 0);
    // The smoothed samples on the truth records' instants (the filter starts at the first frame).
    std::vector<SensingRecord> truth;
    std::vector<double> filt_v, smooth_v, filt_phi, smooth_phi;
    std::size_t j = 0;
    for (const SensingRecord& rec : r.records) {
      while (j < s.size() && s[j].utime < rec.utime) ++j;
      if (j >= s.size()) break;
      if (s[j].utime != rec.utime || rec.utime < 1'000'000) continue;  // after the filter's first second
      truth.push_back(rec);
      filt_v.push_back(rec.truth[kV] + rec.error[kV]);
      filt_phi.push_back(rec.truth[kPhi] + rec.error[kPhi]);
      smooth_v.push_back(s[j].x[kV]);
      smooth_phi.push_back(s[j].x[kPhi]);
    }
    REQUIRE(truth.size() > 1000);
    const double dt = 1.0 / c.sensing.imu.sample_rate_hz;
    const ErrorFigures fv = figures(truth, filt_v, kV, dt), sv = figures(truth, smooth_v, kV, dt);
    const ErrorFigures fphi = figures(truth, filt_phi, kPhi, dt), sphi = figures(truth, smooth_phi, kPhi, dt);
    INFO("v rms filter " << fv.rms << " smoother " << sv.rms << "; lag filter " << fv.lag_ms << " ms smoother "
                         << sv.lag_ms << " ms");
    INFO("phi rms filter " << fphi.rms << " smoother " << sphi.rms << "; lag filter " << fphi.lag_ms << " ms smoother "
                           << sphi.lag_ms << " ms");
    CHECK(sv.rms < 0.8 * fv.rms);
    CHECK(sphi.rms < 0.8 * fphi.rms);
    // No delay worth a quarter of an IMU period (0.49 ms at 512 Hz).
    CHECK(std::fabs(sv.lag_ms) < 0.49);
    CHECK(std::fabs(sphi.lag_ms) < 0.49);
  }
}

TEST_CASE("smoother: no motion capture, nothing smoothed", "[smoother]") {
  std::vector<ImuSample> imu(10);
  for (std::size_t i = 0; i < imu.size(); ++i) imu[i].utime = static_cast<std::int64_t>(i) * 1953;
  CHECK(smooth_flight(EkfConfig{}, VelocityDifferentiatorConfig{}, imu, {}).empty());
}
