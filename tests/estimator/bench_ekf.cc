// bench_ekf: the attitude/velocity EKF's cost against a bare predict + update of the same model,
// on emulated data of a roll-doublet flight with the rig's default sensing (thesis Eq 8.2 Q and R,
// 512 Hz IMU, 200 Hz motion capture, its latency).
//
//   build/bin/bench_ekf [SECONDS] [--passes N] [--latency-ms MS] [--json FILE]
//
// Per second of flight, the median of N passes (default 5) taken in turn, so that a slow moment
// of the machine falls on every figure alike:
//   floor      a bare EKF of the same model: fixed-size 12x12 Eigen matrices, no allocation,
//              the textbook predict (Phi = I + dt/2 (F0 + F1) + dt^2/2 F1 F0, P = Phi (P + dt/2
//              Qc0) Phi^T + dt/2 Qc1, Heun's state step) and update (Joseph form), each
//              measurement applied as it arrives: no history, no rollback;
//   own floor  the filter itself (estimator/ekf.h) applying each measurement as it arrives
//              (latency mode naive): its blockwise predict and update without latency handling;
//   the filter with the motion capture's latency (default: the rig's 5 ms), the velocity
//              measurement held for half the differentiator span: the exact replay (every
//              replayed step linearised again; the default) and the replay reusing each
//              interval's linearisation (EkfConfig::replay_relinearise_*, estimator/ekf.h);
// and the ratios of each to the floor. Then the cost per call (median, p99) of predict, update
// and rollback, and what the reusing replay changes: its largest state difference from the
// exact replay over the flight, in units of the filter's own standard deviation.
// Not a test: the figures depend on the machine; the ratios travel.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Cholesky>
#include <nlohmann/json.hpp>

#include "cmdline/args.h"
#include "core/attitude.h"
#include "estimator/ekf.h"
#include "estimator/ekf_model.h"
#include "estimator/mocap_measurement.h"
#include "estimator/sensing_config.h"
#include "estimator_test_support.h"
#include "truth_trajectory.h"

namespace {

using Clock = std::chrono::steady_clock;
using nimble::AttitudeVelocityEkf;
using nimble::EkfConfig;
using nimble::EkfCovariance;
using nimble::EkfInput;
using nimble::EkfState;
using nimble::test::exact_replay;
using nimble::test::reusing_replay;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

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
    std::printf("  %-44s median %7.2f us   p99 %7.2f us   (%zu calls)\n", name, percentile(0.5), percentile(0.99),
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

/// The floor: a textbook EKF of the filter's model with fixed-size matrices (see the top).
class BareEkf {
 public:
  explicit BareEkf(const EkfConfig& c) : params_(c.model_params()) {
    S_ << c.gyro_noise_var_per_sample_rad2ps2, c.accel_noise_var_per_sample_m2ps4;
    S_ /= c.process_noise_reference_rate_hz;
    q_bias_ << c.gyro_bias_rw_radps_per_sqrts.array().square().matrix(),
        c.accel_bias_rw_mps2_per_sqrts.array().square().matrix();
    R_ << c.attitude_var_rad2, c.velocity_var_m2ps2;
  }
  void initialize(std::int64_t utime, const EkfState& x0, const EkfCovariance& P0) {
    t_ = utime;
    x_ = x0;
    P_ = P0;
    has_u_ = false;
  }
  void predict(const nimble::ImuSample& s) {
    EkfInput u1;
    u1 << s.gyro_radps, s.accel_mps2;
    const EkfInput u0 = has_u_ ? u_ : u1;
    const double dt = 1e-6 * static_cast<double>(s.utime - t_);
    t_ = s.utime;
    u_ = u1;
    has_u_ = true;
    if (dt <= 0.0) return;
    const EkfState k0 = nimble::ekf_process_derivative(x_, u0, params_);
    const EkfState x1 = x_ + dt * k0;
    const EkfState k1 = nimble::ekf_process_derivative(x1, u1, params_);
    const EkfCovariance F0 = nimble::ekf_process_jacobian(x_, u0, params_);
    const EkfCovariance F1 = nimble::ekf_process_jacobian(x1, u1, params_);
    EkfCovariance Phi = EkfCovariance::Identity() + 0.5 * dt * (F0 + F1);
    Phi.noalias() += (0.5 * dt * dt) * (F1 * F0);
    const EkfCovariance Q0 = noise(x_, u0), Q1 = noise(x1, u1);
    const EkfCovariance M = P_ + 0.5 * dt * Q0;
    EkfCovariance P;
    P.noalias() = Phi * M * Phi.transpose();
    P += 0.5 * dt * Q1;
    P_ = 0.5 * (P + P.transpose());
    x_ += 0.5 * dt * (k0 + k1);
    nimble::ekf_wrap_angles(&x_);
  }
  void update(const nimble::PoseMeasurement& z) {
    if (z.has_velocity) {
      Eigen::Matrix<double, 6, 1> zv;
      zv << z.euler_rad, z.velocity_body_mps;
      update_fixed<6>(zv);
    } else {
      update_fixed<3>(z.euler_rad);
    }
  }
  const EkfState& state() const { return x_; }

 private:
  EkfCovariance noise(const EkfState& x, const EkfInput& u) const {
    const nimble::EkfInputJacobian G = nimble::ekf_input_jacobian(x, u, params_);
    EkfCovariance Q;
    Q.noalias() = G * S_.asDiagonal() * G.transpose();
    Q.diagonal().tail<6>() += q_bias_;
    return Q;
  }
  template <int M>
  void update_fixed(const Eigen::Matrix<double, M, 1>& z) {
    Eigen::Matrix<double, M, nimble::kEkfStateDim> H = Eigen::Matrix<double, M, nimble::kEkfStateDim>::Zero();
    H.template leftCols<M>().setIdentity();
    Eigen::Matrix<double, M, 1> y = z - H * x_;
    for (int i = 0; i < 3; ++i) y[i] = nimble::wrap_angle_rad(y[i]);
    const Eigen::Matrix<double, M, M> R = R_.template head<M>().asDiagonal();
    const Eigen::Matrix<double, M, M> S = H * P_ * H.transpose() + R;
    const Eigen::LLT<Eigen::Matrix<double, M, M>> llt(S);
    const double nis = y.dot(llt.solve(y));
    if (!(nis < 1e6)) return;
    const Eigen::Matrix<double, nimble::kEkfStateDim, M> K = llt.solve(H * P_).transpose();
    x_ += K * y;
    const EkfCovariance IKH = EkfCovariance::Identity() - K * H;
    EkfCovariance P;
    P.noalias() = IKH * P_ * IKH.transpose();
    P.noalias() += K * R * K.transpose();
    P_ = 0.5 * (P + P.transpose());
    nimble::ekf_wrap_angles(&x_);
  }

  nimble::EkfModelParams params_;
  EkfInput S_;
  Eigen::Matrix<double, 6, 1> q_bias_, R_;
  std::int64_t t_ = 0;
  EkfState x_ = EkfState::Zero();
  EkfCovariance P_ = EkfCovariance::Identity();
  EkfInput u_ = EkfInput::Zero();
  bool has_u_ = false;
};

/// Feeds the data to a filter: every IMU sample, and each measurement once its frame time plus
/// `delay_us` has passed; `on_sample(k)` after each sample. Returns the wall time [s].
template <typename Predict, typename Add>
double feed(const Data& d, std::int64_t delay_us, Predict predict, Add add,
            const std::function<void(std::size_t)>& on_sample = nullptr) {
  std::size_t next = 0;
  const auto start = Clock::now();
  for (std::size_t k = 0; k < d.imu.size(); ++k) {
    predict(d.imu[k]);
    const std::int64_t until = k + 1 < d.imu.size() ? d.imu[k + 1].utime : d.imu[k].utime + 1;
    while (next < d.measurements.size() && d.frame_utime_of_measurement_arrival[next] + delay_us < until) {
      add(d.measurements[next++]);
    }
    if (on_sample) on_sample(k);
  }
  return std::chrono::duration<double>(Clock::now() - start).count();
}

}  // namespace

int main(int argc, char** argv) {
  double seconds = 60.0;
  int passes = 5;
  double latency_ms = -1.0;
  std::string json_file;
  nimble::cmdline::CommandLine cl(
      "bench_ekf",
      "The EKF's cost per second of flight against a bare predict + update of the same model\n"
      "(fixed-size matrices, measurements at arrival), on emulated flight data with the rig's\n"
      "default sensing; then the cost per call of predict, update and rollback.");
  cl->footer("Not a test: the figures depend on the machine; the ratios travel.");
  cl->add_option("seconds", seconds, "seconds of emulated flight")
      ->check(nimble::cmdline::kFinite & CLI::Range(2.0, 3600.0))
      ->type_name("SECONDS")
      ->capture_default_str();
  cl->add_option("--passes", passes, "passes of each figure, taken in turn (the median is reported)")
      ->check(CLI::Range(1, 100))
      ->type_name("N")
      ->capture_default_str();
  cl->add_option("--latency-ms", latency_ms, "the motion capture's latency (default: the rig's sensing)")
      ->check(nimble::cmdline::kFinite & CLI::Range(0.0, 50.0))
      ->type_name("MS");
  cl.add_json(json_file, "the figures");
  if (const auto done = cl.parse(argc, argv)) return *done;

  const nimble::SensingConfig s;
  const std::int64_t latency_us =
      latency_ms >= 0.0 ? std::llround(latency_ms * 1e3) : static_cast<std::int64_t>(s.mocap.latency_us);
  const Data d = make_data(s, seconds);
  std::printf(
      "bench_ekf: %.0f s of emulated flight, %zu IMU samples, %zu motion-capture measurements, latency %.1f ms\n",
      seconds, d.imu.size(), d.measurements.size(), 1e-3 * static_cast<double>(latency_us));

  // Per second of flight, in turn, `passes` times.
  nimble::EkfConfig naive = s.ekf;
  naive.latency_mode = nimble::EkfLatencyMode::kNaive;
  std::vector<double> bare_us, own_us, exact_us, reuse_us;
  nimble::EkfCounters exact_counters, reuse_counters;
  for (int p = 0; p < passes; ++p) {
    BareEkf bare(s.ekf);
    bare.initialize(d.imu.front().utime, d.x0, s.ekf.initial_covariance());
    bare_us.push_back(1e6 / seconds *
                      feed(
                          d, 0, [&](const nimble::ImuSample& m) { bare.predict(m); },
                          [&](const nimble::PoseMeasurement& z) { bare.update(z); }));
    const auto filter_us = [&](const EkfConfig& c, std::int64_t delay, nimble::EkfCounters* counters) {
      AttitudeVelocityEkf ekf(c);
      ekf.initialize(d.imu.front().utime, d.x0, c.initial_covariance());
      const double t = feed(
          d, delay, [&](const nimble::ImuSample& m) { ekf.predict(m); },
          [&](const nimble::PoseMeasurement& z) { ekf.add_measurement(z); });
      if (counters) *counters = ekf.counters();
      return 1e6 / seconds * t;
    };
    own_us.push_back(filter_us(naive, 0, nullptr));
    exact_us.push_back(filter_us(exact_replay(s.ekf), latency_us, &exact_counters));
    reuse_us.push_back(filter_us(reusing_replay(s.ekf), latency_us, &reuse_counters));
  }
  const double bare = median(bare_us), own = median(own_us), exact = median(exact_us), reuse = median(reuse_us);
  std::printf("\nper second of flight (median of %d passes)             [us]  / floor\n", passes);
  std::printf("  %-50s %7.0f  %6.2f\n", "floor: bare EKF, 12x12 fixed-size, at arrival", bare, 1.0);
  std::printf("  %-50s %7.0f  %6.2f\n", "the filter at arrival (no latency handling)", own, own / bare);
  std::printf("  %-50s %7.0f  %6.2f   (target <= 1.5; %lld rollbacks)\n", "the filter, latency, exact replay (default)",
              exact, exact / bare, static_cast<long long>(exact_counters.rollbacks));
  std::printf("  %-50s %7.0f  %6.2f   (%lld of %lld replayed steps linearised)\n",
              "the filter, latency, replay reusing linearisations", reuse, reuse / bare,
              static_cast<long long>(reuse_counters.replay_steps_linearised),
              static_cast<long long>(reuse_counters.replay_steps));

  // What reusing changes: the largest difference of the default replay's state from the exact
  // replay's, per state in units of the exact filter's standard deviation.
  double worst_sigma = 0.0;
  {
    AttitudeVelocityEkf a(exact_replay(s.ekf)), b(reusing_replay(s.ekf));
    a.initialize(d.imu.front().utime, d.x0, s.ekf.initial_covariance());
    b.initialize(d.imu.front().utime, d.x0, s.ekf.initial_covariance());
    std::vector<EkfState> xa;
    std::vector<EkfState> sa;
    feed(
        d, latency_us, [&](const nimble::ImuSample& m) { a.predict(m); },
        [&](const nimble::PoseMeasurement& z) { a.add_measurement(z); },
        [&](std::size_t) {
          xa.push_back(a.state());
          sa.push_back(a.covariance().diagonal().cwiseSqrt());
        });
    std::size_t k = 0;
    feed(
        d, latency_us, [&](const nimble::ImuSample& m) { b.predict(m); },
        [&](const nimble::PoseMeasurement& z) { b.add_measurement(z); },
        [&](std::size_t) {
          EkfState e = b.state() - xa[k];
          for (int i : {nimble::kPhi, nimble::kPsi}) e[i] = nimble::wrap_angle_rad(e[i]);
          worst_sigma = std::max(worst_sigma, (e.cwiseAbs().array() / sa[k].array()).maxCoeff());
          ++k;
        });
    std::printf("  the reusing replay's state against the exact replay's: largest difference %.4f sigma\n",
                worst_sigma);
  }

  // Per call.
  std::printf("\nper call\n");
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
  for (const std::int64_t delay : {std::int64_t{0}, latency_us, std::int64_t{20000}}) {
    nimble::EkfConfig c = s.ekf;
    if (delay == 0) c.latency_mode = nimble::EkfLatencyMode::kNaive;
    AttitudeVelocityEkf ekf(c);
    ekf.initialize(d.imu.front().utime, d.x0, c.initial_covariance());
    Stats att, full;
    feed(
        d, delay, [&](const nimble::ImuSample& m) { ekf.predict(m); },
        [&](const nimble::PoseMeasurement& z) {
          const auto t1 = Clock::now();
          ekf.add_measurement(z);
          (z.has_velocity ? full : att).add(Clock::now() - t1);
        });
    if (delay == 0) {
      att.print("update (3-dof attitude)");
      full.print("update (6-dof attitude + velocity)");
    } else {
      const std::string ms = std::to_string(static_cast<int>(delay / 1000));
      att.print(("rollback " + ms + " ms, attitude (3-dof)").c_str());
      full.print(("rollback " + ms + "+30 ms, attitude + velocity (6-dof)").c_str());
    }
  }
  if (!json_file.empty()) {
    const nlohmann::json j{{"seconds", seconds},
                           {"passes", passes},
                           {"latency_ms", 1e-3 * static_cast<double>(latency_us)},
                           {"floor_us_per_s", bare},
                           {"own_floor_us_per_s", own},
                           {"filter_us_per_s", exact},
                           {"ratio_to_floor", exact / bare},
                           {"reusing_replay_us_per_s", reuse},
                           {"reusing_ratio_to_floor", reuse / bare},
                           {"replay_largest_difference_sigma", worst_sigma}};
    nimble::cmdline::write_json(json_file, j.dump(2));
  }
  return 0;
}
