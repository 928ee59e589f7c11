/// The fixed-interval smoother of a recorded flight (estimator/smoother.h).

#include "estimator/smoother.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Cholesky>

namespace nimble {
namespace {

double wrap_pi(double a) { return std::remainder(a, 2.0 * M_PI); }

EkfInput input_of(const ImuSample& s) {
  EkfInput u;
  u << s.gyro_radps, s.accel_mps2;
  return u;
}

}  // namespace

PrefilteredImu prefilter_imu(const ImuPrefilterConfig& config, double sample_rate_hz, const std::vector<ImuSample>& imu,
                             std::vector<FlapFrequencies> flaps,
                             const std::function<std::int64_t(std::int64_t)>& rig_utime) {
  PrefilteredImu out;
  if (!config.enabled) {
    out.imu = imu;
    return out;
  }
  ImuPrefilter prefilter(config, sample_rate_hz);
  std::stable_sort(flaps.begin(), flaps.end(),
                   [](const FlapFrequencies& a, const FlapFrequencies& b) { return a.utime < b.utime; });
  out.imu.reserve(imu.size());
  out.input_var.reserve(imu.size());
  std::size_t next = 0;  // the next flapping frequency to give
  for (const ImuSample& s : imu) {
    if (!input_of(s).allFinite()) continue;
    const std::int64_t t = rig_utime ? rig_utime(s.utime) : s.utime;
    for (; next < flaps.size() && flaps[next].utime <= t; ++next) {
      prefilter.set_flap_frequencies(flaps[next].left_radps, flaps[next].right_radps, flaps[next].utime);
    }
    const ImuSample filtered = prefilter.filter(s, t);
    if (!prefilter.settled()) continue;  // the estimator starts its filter only then
    out.imu.push_back(filtered);
    out.input_var.push_back(prefilter.residual_var());
  }
  return out;
}

std::vector<SmoothedSample> smooth_flight(const EkfConfig& ekf_config,
                                          const VelocityDifferentiatorConfig& differentiator,
                                          const std::vector<ImuSample>& imu, const std::vector<MocapPose>& poses,
                                          SmootherReport* report, const std::vector<EkfInput>* input_var) {
  if (input_var != nullptr && input_var->size() != imu.size()) {
    throw std::invalid_argument("smooth_flight: " + std::to_string(input_var->size()) + " input variances for " +
                                std::to_string(imu.size()) + " IMU samples");
  }
  // Every measurement the frames make, in time order.
  MocapMeasurementBuilder builder(differentiator);
  std::vector<PoseMeasurement> zs;
  for (const MocapPose& pose : poses) {
    for (PoseMeasurement& z : builder.push(pose)) zs.push_back(std::move(z));
  }
  for (PoseMeasurement& z : builder.flush()) zs.push_back(std::move(z));
  std::stable_sort(zs.begin(), zs.end(),
                   [](const PoseMeasurement& a, const PoseMeasurement& b) { return a.utime < b.utime; });
  if (report) *report = SmootherReport{};
  if (zs.empty() || imu.empty()) return {};

  // Offline nothing is late: the history need only hold a velocity window and an IMU period.
  EkfConfig config = ekf_config;
  std::int64_t window_us = 0;
  for (const PoseMeasurement& z : zs) {
    window_us = std::max(window_us, z.velocity_window_end_utime - z.velocity_window_start_utime);
  }
  config.history_s = std::max(config.history_s, 1e-6 * static_cast<double>(window_us) + 0.05);
  AttitudeVelocityEkf filter(config);
  std::vector<EkfNode> nodes;
  nodes.reserve(imu.size() + zs.size() + 1);
  filter.set_node_observer([&nodes](const EkfNode& n) { nodes.push_back(n); });

  filter.initialize_from_measurement(zs.front());
  std::size_t m = 1;                              // next measurement to offer (the first started the filter)
  const auto offer_until = [&](std::int64_t t) {  // measurements stamped at or before t
    while (m < zs.size() && zs[m].utime <= t) filter.add_measurement(zs[m++]);
  };
  offer_until(filter.utime());
  const ImuSample* previous = nullptr;
  for (std::size_t i = 0; i < imu.size(); ++i) {
    const ImuSample& s = imu[i];
    if (s.utime < filter.utime() || !input_of(s).allFinite()) continue;
    const EkfInput u = input_of(s);
    const EkfInput* var = input_var != nullptr ? &(*input_var)[i] : nullptr;
    // A node at each measurement time inside the interval, the input interpolated.
    while (previous != nullptr && m < zs.size() && zs[m].utime < s.utime) {
      const std::int64_t t = zs[m].utime;
      if (t > filter.utime()) {
        const double a = static_cast<double>(t - previous->utime) / static_cast<double>(s.utime - previous->utime);
        filter.predict(t, input_of(*previous) + std::clamp(a, 0.0, 1.0) * (u - input_of(*previous)), var);
      }
      offer_until(t);
    }
    filter.predict(s.utime, u, var);
    offer_until(s.utime);
    previous = &s;
  }
  const EkfCounters counters = filter.counters();
  filter.release_history();
  if (report) {
    report->counters = counters;
    report->measurements = static_cast<std::int64_t>(m);
    report->nodes = static_cast<std::int64_t>(nodes.size());
  }
  if (nodes.empty()) return {};

  // Backward pass.
  const std::size_t n = nodes.size();
  std::vector<EkfState> xs(n);
  xs[n - 1] = nodes.back().x;
  for (std::size_t k = n - 1; k-- > 0;) {
    const EkfNode& a = nodes[k];
    const EkfNode& b = nodes[k + 1];
    EkfState x_pred = a.x;
    EkfCovariance P_pred = a.P;
    // With the input noise the forward pass used over the interval (EkfNode::input_psd).
    const EkfCovariance Phi =
        filter.predict_between(&x_pred, &P_pred, a.u, b.has_input ? b.u : a.u, a.utime, b.utime, &b.input_psd);
    const EkfCovariance C = P_pred.ldlt().solve(Phi * a.P).transpose();
    EkfState dx = xs[k + 1] - x_pred;
    for (int i = 0; i < 3; ++i) dx(i) = wrap_pi(dx(i));
    xs[k] = a.x + C * dx;
    for (int i = 0; i < 3; ++i) xs[k](i) = wrap_pi(xs[k](i));
  }

  // One sample per recorded IMU sample.
  std::vector<SmoothedSample> out;
  out.reserve(imu.size());
  std::size_t k = 0;
  for (const ImuSample& s : imu) {
    while (k < n && nodes[k].utime < s.utime) ++k;
    if (k >= n) break;
    if (nodes[k].utime != s.utime) continue;
    SmoothedSample o;
    o.utime = s.utime;
    o.x = xs[k];
    o.rate_radps = s.gyro_radps - xs[k].segment<3>(kBiasP);
    out.push_back(o);
  }
  return out;
}

}  // namespace nimble
