// bench_ekf: cost of the attitude/velocity EKF per call, on emulated data of a roll-doublet flight
// with the rig's default sensing (thesis Eq 8.2 Q and R, 512 Hz IMU, 200 Hz mocap).
//
//   build/bin/bench_ekf [seconds_of_flight]     (default 60)
//
// Prints the median and 99th percentile in microseconds of:
//   predict            one IMU sample (Heun step and covariance propagation)
//   update 3 / 6       one attitude (3-dof) or attitude+velocity (6-dof) update at the current time
//   rollback 20 ms     one measurement arriving 20 ms after its timestamp (restore, update,
//                      re-propagate to the present), split by measurement type; 6-dof measurements
//                      are in addition held for half the differentiator span (30 ms)
// and the total filter time per second of flight with 20 ms pose latency.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "estimator/ekf.h"
#include "estimator/mocap_measurement.h"
#include "estimator/sensing_config.h"
#include "truth_trajectory.h"

namespace {

using Clock = std::chrono::steady_clock;
using nimble::AttitudeVelocityEkf;
using nimble::EkfState;

struct Stats {
  std::vector<double> us;
  void add(Clock::duration d) { us.push_back(std::chrono::duration<double, std::micro>(d).count()); }
  double percentile(double p) {
    if (us.empty()) return 0.0;
    std::sort(us.begin(), us.end());
    const auto i = static_cast<std::size_t>(std::min<double>(us.size() - 1, std::floor(p * (us.size() - 1) + 0.5)));
    return us[i];
  }
  void print(const char* name) {
    std::printf("  %-38s median %7.2f us   p99 %7.2f us   (%zu calls)\n", name, percentile(0.5), percentile(0.99),
                us.size());
  }
};

struct Data {
  std::vector<nimble::ImuSample> imu;
  std::vector<nimble::PoseMeasurement> measurements;             // in arrival order (builder output)
  std::vector<std::int64_t> frame_utime_of_measurement_arrival;  // timestamp of the frame that completed it
  EkfState x0;
};

Data make_data(const nimble::SensingConfig& s, double seconds) {
  Data d;
  nimble::TruthTrajectory truth(nimble::make_roll_doublet_profile(5, seconds), 0);
  nimble::ImuModel imu(s.imu, s.seed);
  nimble::MocapEmulator mocap(s.mocap, s.seed + 1);
  nimble::MocapMeasurementBuilder builder(s.velocity_differentiator);
  const auto end = static_cast<std::int64_t>(seconds * 1e6);
  std::int64_t k = 0;
  while (true) {
    const auto t_imu = static_cast<std::int64_t>(std::llround(k * 1e6 / s.imu.sample_rate_hz));
    const std::int64_t t_cap = mocap.next_frame_utime();
    if (std::min(t_imu, t_cap) > end) break;
    if (t_cap < t_imu) {
      const nimble::MocapPose pose = mocap.capture(truth.advance_to(t_cap).mocap_input());
      for (const auto& z : builder.push(pose)) {
        d.measurements.push_back(z);
        d.frame_utime_of_measurement_arrival.push_back(pose.utime);
      }
    } else {
      const nimble::TruthSample& tr = truth.advance_to(t_imu);
      if (k == 0) d.x0 << tr.euler_rad, tr.velocity_body_mps, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero();
      d.imu.push_back(imu.sample(tr.imu_input()));
      ++k;
    }
  }
  return d;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc > 1 && (std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h")) {
    std::printf(
        "usage: bench_ekf [seconds_of_flight >= 2 (default 60)]\n"
        "  Times the EKF's predict and update on emulated flight data.\n");
    return 0;
  }
  const double seconds = argc > 1 ? std::atof(argv[1]) : 60.0;
  if (!(seconds >= 2.0)) {
    std::fprintf(stderr, "usage: bench_ekf [seconds_of_flight >= 2]\n");
    return 2;
  }
  const nimble::SensingConfig s;
  const Data d = make_data(s, seconds);
  std::printf("bench_ekf: %.0f s of emulated flight, %zu IMU samples, %zu mocap measurements\n", seconds, d.imu.size(),
              d.measurements.size());

  // 1. predict only.
  {
    AttitudeVelocityEkf ekf(s.ekf);
    ekf.initialize(d.imu.front().utime, d.x0, s.ekf.initial_covariance());
    Stats predict;
    for (const auto& sample : d.imu) {
      const auto t0 = Clock::now();
      ekf.predict(sample);
      predict.add(Clock::now() - t0);
    }
    predict.print("predict");
  }

  // 2. updates at the current time (naive mode: the update alone, no re-propagation).
  // 3. rollback with 20 ms latency.
  for (const bool rollback : {false, true}) {
    nimble::EkfConfig c = s.ekf;
    c.latency_mode = rollback ? nimble::EkfLatencyMode::kRollback : nimble::EkfLatencyMode::kNaive;
    AttitudeVelocityEkf ekf(c);
    ekf.initialize(d.imu.front().utime, d.x0, c.initial_covariance());
    const std::int64_t delay = rollback ? 20000 : 0;
    Stats att, full, all_predict;
    std::size_t next = 0;
    const auto start = Clock::now();
    for (std::size_t k = 0; k < d.imu.size(); ++k) {
      const auto t0 = Clock::now();
      ekf.predict(d.imu[k]);
      all_predict.add(Clock::now() - t0);
      const std::int64_t until = k + 1 < d.imu.size() ? d.imu[k + 1].utime : d.imu[k].utime + 1;
      while (next < d.measurements.size() && d.frame_utime_of_measurement_arrival[next] + delay < until) {
        const nimble::PoseMeasurement& z = d.measurements[next++];
        const auto t1 = Clock::now();
        ekf.add_measurement(z);
        (z.has_velocity ? full : att).add(Clock::now() - t1);
      }
    }
    const double total_s = std::chrono::duration<double>(Clock::now() - start).count();
    if (rollback) {
      att.print("rollback 20 ms, attitude (3-dof)");
      full.print("rollback 20+30 ms, att.+velocity (6)");
      std::printf(
          "  filter time with 20 ms latency: %.0f us per second of flight (%.2f %% of one core); "
          "rollbacks %lld, too old %lld\n",
          1e6 * total_s / seconds, 100.0 * total_s / seconds, static_cast<long long>(ekf.counters().rollbacks),
          static_cast<long long>(ekf.counters().measurements_too_old));
    } else {
      att.print("update (3-dof attitude)");
      full.print("update (6-dof attitude + velocity)");
    }
  }
  return 0;
}
