/// bench_vibration: the paper's manoeuvres flown with the real vehicle's vibration, the on-board
/// estimator in the loop, over many seeds: does the estimator survive it, and is it consistent?
///
///   bench_vibration [--seeds N] [--first-seed S] [--scenario FILE]... [--sensing FILE|none] [--set k=v]... [--json F]
///   bench_vibration --residual [--seeds N] [--first-seed S] [--sensing FILE] [--set k=v]...
///
/// Every flight is flown in process with processes [plant, controller, mocap, estimator], the
/// controller on the estimate, and `sensing.base` = the sensing file (default
/// rig_configs/sensing/nimble_flight_vibration.yaml; `none`: the scenario's own). Per scenario it
/// prints, over seeds 1..N:
///  - flights whose controller took its failsafe, whose EKF's divergence monitor fired, and that
///    stayed controlled (the run's verdict);
///  - the gate's rejections per motion-capture measurement (a consistent filter: 1 - the gate's
///    probability, 0.1 %), the estimate's phi and p error RMS against TRUTH;
///  - NEES of the attitude (phi theta psi) and of the body velocity (u v w), each from the
///    published covariance diagonal (3 dof each; the estimate carries no off-diagonal terms):
///    the mean over every estimate of every seed, and the Monte Carlo test of Bar-Shalom et al.:
///    at each estimate time the mean over the N seeds lies, for a consistent filter, within the
///    two-sided 95 % band [chi2(3N, 0.025), chi2(3N, 0.975)] / N; the share of times inside it
///    (95 % expected) and the shares below and above it.
/// Times start at 0.5 s (the filter's start from its initial sigmas is not judged).
/// Not a test: figures, with the commands that made them, for the estimator's README.

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include <nimble/actuator_feedback_t.hpp>
#include <nimble/estimator_state_t.hpp>
#include <nimble/imu_sample_t.hpp>
#include <nimble/fault_event_t.hpp>
#include <nimble/truth_state_t.hpp>

#include "cmdline/args.h"
#include "contract/channels.h"
#include "contract/messages.h"
#include "core/chi_square.h"
#include "core/output_file.h"
#include "estimator/sensing_config.h"
#include "estimator/smoother.h"
#include "launcher/inprocess.h"
#include "launcher/run_plan.h"

using namespace nimble;

namespace {

const std::vector<std::string> kPaperManoeuvres = {
    "id_doublet_train_fast", "ol_doublet_6hz_fast",     "ol_112_fast",        "cl_112_slow",
    "cl_doublet_train_slow", "nonlinear_doublet_30deg", "coupled_doublet_6hz"};

/// Sums over the seeds at one estimate time.
struct NeesAt {
  double att = 0.0, vel = 0.0;
  int n = 0;
};

struct ScenarioFigures {
  std::string name;
  int flights = 0, failsafe = 0, diverged = 0, controlled = 0;
  long long accepted = 0, rejected = 0;
  double phi2 = 0.0, p2 = 0.0, att_sum = 0.0, vel_sum = 0.0;
  long long samples = 0;
  std::map<int64_t, NeesAt> by_time;
};

/// One flight: its messages into `f`.
void fly(const std::string& scenario, int seed, const std::vector<Override>& overrides, ScenarioFigures* f) {
  launcher::RunOptions o;
  o.scenario_file = scenario;
  o.clock = launcher::kClockInprocess;
  o.seed = static_cast<unsigned long long>(seed);
  o.overrides = overrides;
  const launcher::RunPlan plan = launcher::load_run_plan(o);
  std::map<int64_t, Truth> truth;  // recent TRUTH by utime
  launcher::InprocessOptions io;
  io.config_digest = false;
  io.on_message = [&](const std::string& channel, const void* data, int size) {
    if (channel == contract::channels::kTruth) {
      truth_state_t m;
      if (m.decode(data, 0, size) != size) return;
      truth[m.utime] = contract::from_message(m);
      while (truth.size() > 2048) truth.erase(truth.begin());
    } else if (channel == contract::channels::kEstimate) {
      estimator_state_t m;
      if (m.decode(data, 0, size) != size) return;
      const Estimate e = contract::from_message(m);
      const auto it = truth.find(e.imu_utime);
      if (it == truth.end() || e.imu_utime < 500000) return;
      double att = 0.0, vel = 0.0;
      for (int i = 0; i < 3; ++i) {
        const double da = std::remainder(e.euler_rad[i] - it->second.euler_rad[i], 2.0 * M_PI);
        const double dv = e.velocity_body_mps[i] - it->second.velocity_body_mps[i];
        att += da * da / e.cov_diag[i];
        vel += dv * dv / e.cov_diag[3 + i];
      }
      const double dphi = std::remainder(e.euler_rad[0] - it->second.euler_rad[0], 2.0 * M_PI);
      f->phi2 += dphi * dphi;
      f->p2 += std::pow(e.omega_body_radps[0] - it->second.omega_body_radps[0], 2);
      f->att_sum += att;
      f->vel_sum += vel;
      ++f->samples;
      NeesAt& at = f->by_time[e.utime];
      at.att += att;
      at.vel += vel;
      ++at.n;
    }
  };
  const launcher::RunReport r = launcher::fly_inprocess(plan, io);
  ++f->flights;
  bool failsafe = false, diverged = false;
  for (const auto& fault : r.faults) {
    failsafe |= fault.code == fault_event_t::CODE_FAILSAFE;
    diverged |= fault.code == fault_event_t::CODE_ESTIMATOR_DIVERGED;
    if (fault.code == fault_event_t::CODE_FAILSAFE || fault.code == fault_event_t::CODE_ESTIMATOR_DIVERGED) {
      std::fprintf(stderr, "  %s seed %d: %s\n", f->name.c_str(), seed, fault.message.c_str());
    }
  }
  f->failsafe += failsafe;
  f->diverged += diverged;
  f->controlled += r.verdict.controlled;
  f->accepted += r.estimator.poses_accepted;
  f->rejected += r.estimator.poses_rejected;
}

/// Shares of the estimate times (every seed present) whose seed mean lies below, inside and above
/// the 95 % band of a 3-dof NEES averaged over `seeds`.
struct Band {
  double below = 0.0, inside = 0.0, above = 0.0, lo = 0.0, hi = 0.0;
  long long times = 0;
};

Band band(const std::map<int64_t, NeesAt>& by_time, int seeds, bool attitude) {
  Band b;
  b.lo = chi_square_quantile(0.025, 3.0 * seeds) / seeds;
  b.hi = chi_square_quantile(0.975, 3.0 * seeds) / seeds;
  long long lo = 0, in = 0, hi = 0;
  for (const auto& [t, at] : by_time) {
    if (at.n != seeds) continue;
    const double m = (attitude ? at.att : at.vel) / seeds;
    (m < b.lo ? lo : m > b.hi ? hi : in) += 1;
  }
  b.times = lo + in + hi;
  if (b.times > 0) {
    b.below = static_cast<double>(lo) / b.times;
    b.inside = static_cast<double>(in) / b.times;
    b.above = static_cast<double>(hi) / b.times;
  }
  return b;
}

/// --residual: the on-board filtering's output against TRUTH on hover flights (seeds first..),
/// per IMU channel: the per-sample variance and the low-frequency level (0.5-5 Hz, the band the
/// EKF's attitude and velocity integrate) as the per-sample variance of a white noise with that
/// PSD. The flight's IMU is filtered here from its ACTUATOR_FB as the estimator filters it (prefilter_imu).
int residual(const std::string& sensing, int first_seed, int seeds, const std::vector<Override>& extra) {
  constexpr int kSegment = 1024;  // 2 s at 512 Hz: bins 0.5 Hz apart
  Eigen::Matrix<double, 6, 1> var = Eigen::Matrix<double, 6, 1>::Zero(), low = var;
  long long samples = 0, segments = 0;
  for (int seed = first_seed; seed < first_seed + seeds; ++seed) {
    launcher::RunOptions o;
    o.scenario_file = std::string(RIG_SOURCE_DIR) + "/rig_configs/hover.yaml";
    o.clock = launcher::kClockInprocess;
    o.seed = static_cast<unsigned long long>(seed);
    o.overrides = {{"processes", "[plant, controller, mocap, estimator]"},
                   {"run.controller_input", "estimate"},
                   {"sensing.base", sensing}};
    o.overrides.insert(o.overrides.end(), extra.begin(), extra.end());
    const launcher::RunPlan plan = launcher::load_run_plan(o);
    ConfigMap section = plan.scenario.section("sensing");
    const SensingConfig sc = sensing_config_from(section);
    std::map<int64_t, Truth> truth;
    std::vector<ImuSample> imu;
    std::vector<FlapFrequencies> flaps;
    launcher::InprocessOptions io;
    io.config_digest = false;
    io.on_message = [&](const std::string& channel, const void* data, int size) {
      if (channel == contract::channels::kTruth) {
        truth_state_t m;
        if (m.decode(data, 0, size) == size) truth[m.utime] = contract::from_message(m);
      } else if (channel == contract::channels::kActuatorFeedback) {
        actuator_feedback_t m;
        if (m.decode(data, 0, size) == size)
          flaps.push_back({m.utime, m.flap_freq_left_radps, m.flap_freq_right_radps});
      } else if (channel == contract::channels::kImu) {
        imu_sample_t m;
        if (m.decode(data, 0, size) == size) imu.push_back(contract::from_message(m));
      }
    };
    launcher::fly_inprocess(plan, io);
    // The flight's IMU through its on-board filtering, fed as the estimator feeds it.
    const PrefilteredImu filtered = prefilter_imu(sc.imu_prefilter, sc.imu.sample_rate_hz, imu, flaps);
    std::vector<Eigen::Matrix<double, 6, 1>> err;
    for (const ImuSample& f : filtered.imu) {
      const auto it = truth.find(f.utime);
      if (it == truth.end() || f.utime < 1000000) continue;
      Eigen::Matrix<double, 6, 1> e;
      e << f.gyro_radps - it->second.omega_body_radps, f.accel_mps2 - it->second.specific_force_body_mps2;
      err.push_back(e);
    }
    // Per-channel mean out (the biases); per-sample variance; 0.5-5 Hz periodogram level per segment.
    Eigen::Matrix<double, 6, 1> mean = Eigen::Matrix<double, 6, 1>::Zero();
    for (const auto& e : err) mean += e;
    mean /= std::max<std::size_t>(1, err.size());
    for (const auto& e : err) var += (e - mean).cwiseAbs2();
    samples += static_cast<long long>(err.size());
    for (std::size_t start = 0; start + kSegment <= err.size(); start += kSegment) {
      for (int bin = 1; bin <= 10; ++bin) {  // 0.5 .. 5 Hz
        Eigen::Matrix<std::complex<double>, 6, 1> X = Eigen::Matrix<std::complex<double>, 6, 1>::Zero();
        for (int n = 0; n < kSegment; ++n) {
          const std::complex<double> w = std::polar(1.0, -2.0 * M_PI * bin * n / kSegment);
          X += (err[start + static_cast<std::size_t>(n)] - mean).cast<std::complex<double>>() * w;
        }
        low += X.cwiseAbs2() / (10.0 * kSegment);
      }
      ++segments;
    }
  }
  var /= std::max<long long>(1, samples);
  low /= std::max<long long>(1, segments);
  const char* names[6] = {"gyro p (rad/s)^2",  "gyro q (rad/s)^2",  "gyro r (rad/s)^2",
                          "accel x (m/s^2)^2", "accel y (m/s^2)^2", "accel z (m/s^2)^2"};
  std::printf("the on-board filtering's output against TRUTH, hover, seeds %d-%d, %lld samples, %lld segments of 2 s\n",
              first_seed, first_seed + seeds - 1, samples, segments);
  std::printf("%-20s %14s %22s\n", "channel", "per-sample var", "0.5-5 Hz, white-equiv.");
  for (int i = 0; i < 6; ++i) std::printf("%-20s %14.4g %22.4g\n", names[i], var[i], low[i]);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  int seeds = 20, first_seed = 1;
  std::vector<std::string> scenarios;
  std::vector<std::string> sets;
  std::string sensing = std::string(RIG_SOURCE_DIR) + "/rig_configs/sensing/nimble_flight_vibration.yaml";
  std::string json_file;
  cmdline::CommandLine cl("bench_vibration",
                          "Flies the paper's manoeuvres with the real vehicle's vibration, the on-board estimator in\n"
                          "the loop, over seeds 1..N: failsafes, divergences, gate rejections, errors and NEES.");
  cl->footer("Not a test: figures for the estimator's README.");
  cl->add_option("--seeds", seeds, "seeds 1..N per scenario")->check(CLI::Range(1, 1000))->capture_default_str();
  cl->add_option("--first-seed", first_seed, "the first seed (the seeds are FIRST..FIRST+N-1)")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str();
  cl->add_option("--scenario", scenarios, "a scenario file (repeatable; default: the seven paper manoeuvres)")
      ->type_name("FILE");
  cl->add_option("--sensing", sensing, "the sensing base file, or none for the scenario's own")->capture_default_str();
  cl->add_option("--set", sets, "a scenario override k=v (repeatable)")->type_name("K=V");
  cl->add_option("--json", json_file, "the figures as JSON to FILE")->type_name("FILE");
  bool residual_mode = false, series = false;
  cl->add_flag("--series", series, "also the seed-mean NEES per 0.1 s of each scenario");
  cl->add_flag("--residual", residual_mode,
               "instead: the on-board filtering's output against TRUTH on hover flights (seeds FIRST..), per-sample "
               "and 0.5-5 Hz levels per IMU channel: what the EKF's input noise must hold");
  if (const auto done = cl.parse(argc, argv)) return *done;
  if (scenarios.empty()) {
    for (const auto& s : kPaperManoeuvres)
      scenarios.push_back(std::string(RIG_SOURCE_DIR) + "/rig_configs/" + s + ".yaml");
  }
  std::vector<Override> overrides = {{"processes", "[plant, controller, mocap, estimator]"},
                                     {"run.controller_input", "estimate"}};
  if (sensing != "none") overrides.push_back({"sensing.base", sensing});
  std::vector<Override> extra;
  try {
    for (const auto& s : sets) extra.push_back(parse_override(s));
  } catch (const std::exception& e) {
    return cl.fail(e.what());
  }
  overrides.insert(overrides.end(), extra.begin(), extra.end());
  if (residual_mode) {
    try {
      return residual(sensing, first_seed, seeds, extra);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "bench_vibration: %s\n", e.what());
      return 2;
    }
  }
  std::printf("sensing %s, seeds %d-%d, controller on the estimate\n", sensing.c_str(), first_seed,
              first_seed + seeds - 1);
  std::printf("%-24s %8s %8s %8s %10s %9s %9s %9s %22s %9s %22s\n", "scenario", "failsafe", "diverged", "ctrl'd",
              "rejected", "phi rms", "p rms", "NEES att", "in band (below/above)", "NEES vel", "in band (below/above)");
  nlohmann::json out = nlohmann::json::array();
  try {
    for (const auto& scenario : scenarios) {
      ScenarioFigures f;
      f.name = std::filesystem::path(scenario).stem().string();
      for (int seed = first_seed; seed < first_seed + seeds; ++seed) fly(scenario, seed, overrides, &f);
      const Band ba = band(f.by_time, seeds, true), bv = band(f.by_time, seeds, false);
      if (series) {
        // The seed mean of each NEES over 0.1 s windows (every estimate time with every seed).
        double sa = 0.0, sv = 0.0;
        int n = 0;
        int64_t window = -1;
        for (const auto& [t, at] : f.by_time) {
          if (at.n != seeds) continue;
          if (t / 100000 != window && n > 0) {
            std::printf("  %s t %.1f s: NEES att %.2f vel %.2f\n", f.name.c_str(), window / 10.0, sa / n, sv / n);
            sa = sv = 0.0;
            n = 0;
          }
          window = t / 100000;
          sa += at.att / seeds;
          sv += at.vel / seeds;
          ++n;
        }
      }
      const double n = std::max<long long>(1, f.samples);
      const double rej = static_cast<double>(f.rejected) / std::max<long long>(1, f.accepted + f.rejected);
      std::printf(
          "%-24s %5d/%-2d %5d/%-2d %5d/%-2d %9.2f%% %8.3f° %9.3f %9.2f %8.0f%% (%2.0f/%2.0f%%) %9.2f %8.0f%% "
          "(%2.0f/%2.0f%%)\n",
          f.name.c_str(), f.failsafe, f.flights, f.diverged, f.flights, f.controlled, f.flights, 100 * rej,
          std::sqrt(f.phi2 / n) * 180 / M_PI, std::sqrt(f.p2 / n), f.att_sum / n, 100 * ba.inside, 100 * ba.below,
          100 * ba.above, f.vel_sum / n, 100 * bv.inside, 100 * bv.below, 100 * bv.above);
      std::fflush(stdout);
      out.push_back({{"scenario", f.name},
                     {"flights", f.flights},
                     {"failsafe", f.failsafe},
                     {"diverged", f.diverged},
                     {"controlled", f.controlled},
                     {"gate_rejected_fraction", rej},
                     {"phi_rms_deg", std::sqrt(f.phi2 / n) * 180 / M_PI},
                     {"p_rms_radps", std::sqrt(f.p2 / n)},
                     {"nees_attitude_mean", f.att_sum / n},
                     {"nees_velocity_mean", f.vel_sum / n},
                     {"nees_attitude_in_band", ba.inside},
                     {"nees_attitude_below", ba.below},
                     {"nees_velocity_in_band", bv.inside},
                     {"nees_velocity_below", bv.below},
                     {"band", {ba.lo, ba.hi}}});
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_vibration: %s\n", e.what());
    return 2;
  }
  std::printf("band of the seed mean of a 3-dof NEES over %d seeds: [%.2f, %.2f] (expected mean 3)\n", seeds,
              chi_square_quantile(0.025, 3.0 * seeds) / seeds, chi_square_quantile(0.975, 3.0 * seeds) / seeds);
  if (!json_file.empty()) write_file(json_file, out.dump(1) + "\n");
  return 0;
}
