#include "estimator/estimator_node.h"

#include <climits>
#include <iomanip>
#include <sstream>

#include <nimble/estimator_state_t.hpp>
#include <nimble/fault_event_t.hpp>
#include <nimble/imu_sample_t.hpp>
#include <nimble/mocap_pose_t.hpp>

#include "contract/messages.h"

#include "estimator/sensing_config.h"
#include "transport/process_main.h"

namespace nimble {

EstimatorNode::EstimatorNode(const Scenario& scenario, const transport::NodeOptions& options) {
  ConfigMap section = scenario.section("sensing");
  const SensingConfig sensing = sensing_config_from(section);
  ekf_ = std::make_unique<AttitudeVelocityEkf>(sensing.ekf);
  builder_ = std::make_unique<MocapMeasurementBuilder>(sensing.velocity_differentiator);
  node_ = std::make_unique<transport::ProcessNode>(options, transport::realtime_settings(scenario));
  node_->set_expected_rate(contract::channels::kImu, sensing.imu.sample_rate_hz);
  node_->set_expected_rate(contract::channels::kMocapPose, sensing.mocap.frame_rate_hz);
  node_->bus().subscribe<imu_sample_t>(contract::channels::kImu, [this](const imu_sample_t& m) {
    if (!transport::plausible_sim_utime(m.utime)) {
      node_->fault(fault_event_t::SEVERITY_WARNING, fault_event_t::CODE_MESSAGE_MALFORMED, contract::channels::kImu,
                   "IMU sample at utime " + std::to_string(m.utime) + " us lies outside any run; ignored");
      return;
    }
    const ImuSample s = contract::from_message(m);
    if (node_->lockstep()) {
      imu_inbox_.push(s.utime, s);
    } else {
      apply_imu(s);
      publish(s.utime);
      // End-to-end latency: from the IMU sample's time to its estimate going out.
      node_->record_latency_ns(transport::monotonic_ns() -
                                (node_->t0_monotonic_ns() + transport::message_us_to_ns(s.utime)));
    }
  });
  node_->bus().subscribe<mocap_pose_t>(contract::channels::kMocapPose, [this](const mocap_pose_t& m) {
    if (!transport::plausible_sim_utime(m.utime)) {
      node_->fault(fault_event_t::SEVERITY_WARNING, fault_event_t::CODE_MESSAGE_MALFORMED, contract::channels::kMocapPose,
                   "pose at utime " + std::to_string(m.utime) + " us lies outside any run; ignored");
      return;
    }
    const MocapPose p = contract::from_message(m);
    if (node_->lockstep()) pose_inbox_.push(p.publish_utime, p);
    else apply_pose(p);
  });
  // Lockstep ticks only: in real time the work happens as the inputs arrive.
  node_->add_task("estimator", sensing.imu.sample_rate_hz, [this](int64_t t) { tick(t); },
                  transport::ProcessNode::Trigger::kInput);
}

int EstimatorNode::run() { return node_->run(); }

void EstimatorNode::apply_imu(const ImuSample& sample) {
  if (ekf_->initialized()) ekf_->predict(sample);
}

void EstimatorNode::apply_pose(const MocapPose& pose) {
  if (last_frame_ >= 0 && pose.frame_number > last_frame_ + 1) poses_missing_ += pose.frame_number - last_frame_ - 1;
  last_frame_ = pose.frame_number;
  if (!pose.tracking_valid) ++poses_missing_;
  for (const PoseMeasurement& z : builder_->push(pose)) {
    if (!ekf_->initialized()) {
      ekf_->initialize_from_measurement(z);
    } else {
      const EkfMeasurementStatus status = ekf_->add_measurement(z);
      if (status == EkfMeasurementStatus::kTooOld || status == EkfMeasurementStatus::kTooNew) report_dropped(z, status);
    }
  }
}

void EstimatorNode::report_dropped(const PoseMeasurement& z, EkfMeasurementStatus status) {
  const int64_t now = ekf_->utime();
  if (last_drop_fault_utime_ != INT64_MIN && now - last_drop_fault_utime_ < 1000000) return;
  last_drop_fault_utime_ = now;
  const EkfCounters& c = ekf_->counters();
  std::ostringstream msg;
  msg << std::fixed << std::setprecision(1) << "mocap frame " << z.frame_number << " dropped by the EKF: ";
  if (status == EkfMeasurementStatus::kTooOld) {
    msg << "it refers to " << 1e-3 * static_cast<double>(now - z.utime) << " ms before the newest IMU sample, older than "
        << "the rollback history of " << 1e3 * ekf_->config().history_s << " ms (" << c.measurements_too_old
        << " so far); the motion-capture stream is late: raise sensing.ekf.latency.history_s or find the delay";
  } else {
    msg << "it refers to " << 1e-3 * static_cast<double>(z.utime - now) << " ms after the newest IMU sample, more than "
        << "the history of " << 1e3 * ekf_->config().history_s << " ms ahead (" << c.measurements_too_new
        << " so far); the IMU stream is late or the two clocks differ";
  }
  node_->fault(fault_event_t::SEVERITY_WARNING, fault_event_t::CODE_MEASUREMENT_OUT_OF_WINDOW,
               contract::channels::kMocapPose, msg.str());
}

void EstimatorNode::tick(int64_t sim_time_ns) {
  if (!node_->lockstep()) return;  // real time works on arrival
  const int64_t now_us = sim_time_ns / 1000;
  // Inputs available before this tick, in the order they became available.
  for (;;) {
    const bool imu_ready = imu_inbox_.ready(now_us);
    const bool pose_ready = pose_inbox_.ready(now_us);
    if (!imu_ready && !pose_ready) break;
    if (imu_ready && (!pose_ready || imu_inbox_.front_stamp_utime() <= pose_inbox_.front_stamp_utime())) {
      apply_imu(imu_inbox_.front());
      imu_inbox_.pop();
    } else {
      apply_pose(pose_inbox_.front());
      pose_inbox_.pop();
    }
  }
  publish(now_us);
}

void EstimatorNode::publish(int64_t utime) {
  if (!ekf_->initialized()) return;
  const EkfState& x = ekf_->state();
  const EkfCovariance& P = ekf_->covariance();
  const Eigen::Vector3d w = ekf_->corrected_rate_radps();
  estimator_state_t m;
  m.utime = utime;
  m.seq = seq_++;
  m.imu_utime = ekf_->utime();
  for (int i = 0; i < 3; ++i) {
    m.euler_rad[i] = x[kPhi + i];
    m.velocity_body_mps[i] = x[kU + i];
    m.gyro_bias_radps[i] = x[kBiasP + i];
    m.accel_bias_mps2[i] = x[kBiasAx + i];
    m.omega_body_radps[i] = w[i];
  }
  for (int i = 0; i < 12; ++i) m.cov_diag[i] = P(i, i);
  const EkfCounters& c = ekf_->counters();
  m.poses_accepted = c.measurements_accepted;
  m.poses_rejected = c.measurements_rejected_gate;
  m.poses_missing = poses_missing_;
  m.last_nis = ekf_->last_nis();
  m.poses_too_old = c.measurements_too_old;
  m.poses_too_new = c.measurements_too_new;
  m.velocity_windows_uncovered = c.velocity_window_uncovered;
  m.imu_rejected = c.imu_rejected;
  m.imu_gaps = c.imu_gaps;
  node_->bus().publish(contract::channels::kEstimate, m);
}

}  // namespace nimble
