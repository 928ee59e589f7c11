#include "estimator/estimator_node.h"

#include <climits>
#include <utility>
#include <iomanip>
#include <sstream>
#include <vector>

#include <nimble/actuator_feedback_t.hpp>
#include <nimble/fault_event_t.hpp>

#include "contract/messages.h"

#include "estimator/sensing_config.h"
#include "transport/process_main.h"

namespace nimble {

EstimatorNode::EstimatorNode(const Scenario& scenario, const transport::NodeOptions& options) {
  ConfigMap section = scenario.section("sensing");
  const SensingConfig sensing = sensing_config_from(section);
  ekf_ = std::make_unique<AttitudeVelocityEkf>(sensing.ekf);
  builder_ = std::make_unique<MocapMeasurementBuilder>(sensing.velocity_differentiator);
  if (sensing.ekf.gate_enabled) {
    divergence_ = std::make_unique<DivergenceMonitor>(kDivergenceWindow, 1.0 - sensing.ekf.gate_probability,
                                                      kDivergenceFalseAlarm);
  }
  if (sensing.imu_prefilter.enabled) {
    prefilter_ = std::make_unique<ImuPrefilter>(sensing.imu_prefilter, sensing.imu.sample_rate_hz);
  }
  node_ = transport::make_process_node(scenario, options);
  node_->set_expected_rate(contract::channels::kImu, scenario.expected_rate(contract::channels::kImu));
  node_->set_expected_rate(contract::channels::kMocapPose, scenario.expected_rate(contract::channels::kMocapPose));
  stuck_check_ = sensing.imu.gyro_noise_sigma_radps.norm() > 0.0 || sensing.imu.accel_noise_sigma_mps2.norm() > 0.0;
  imu_clock_ = sensing.imu.clock();
  if (!imu_clock_.identity()) {
    node_->bus().set_stamp_clock(contract::channels::kImu,
                                 [clock = imu_clock_](int64_t stamp) { return clock.rig_utime(stamp); });
  }
  check_ekf_history(section, sensing, scenario.duration_s);  // the clock's drift over this flight
  stage_imu_in_ = node_->add_stage("estimator: IMU sample received");
  stage_estimate_out_ = node_->add_stage("estimator: ESTIMATE published");
  stage_work_ = node_->add_stage("estimator: its work, IMU sample received to ESTIMATE published");
  stage_filter_ = node_->add_stage("estimator: its work, of which the EKF's prediction");
  stage_publish_ = node_->add_stage("estimator: its work, of which publishing ESTIMATE");
  stage_pose_ = node_->add_stage("estimator: its work on a motion-capture frame (EKF update, rollback)");
  node_->bus().subscribe<imu_sample_t>(contract::channels::kImu, [this](const imu_sample_t& m) {
    const int64_t received_ns = transport::monotonic_ns();
    // The stamp is the IMU's clock; the rig's bookkeeping uses the rig time of the sample.
    const int64_t rig_utime = imu_clock_.rig_utime(m.utime);
    if (!transport::plausible_sim_utime(rig_utime)) {
      node_->fault(fault_event_t::SEVERITY_WARNING, fault_event_t::CODE_MESSAGE_MALFORMED, contract::channels::kImu,
                   "IMU sample at utime " + std::to_string(m.utime) + " us lies outside any run; ignored");
      return;
    }
    const ImuSample s = contract::from_message(m);
    if (!imu_usable(s)) return;
    if (node_->lockstep()) {
      imu_inbox_.push(rig_utime, s);
    } else {
      const int64_t filter_ns = transport::monotonic_ns();
      apply_imu(s, rig_utime);
      const int64_t publish_ns = transport::monotonic_ns();
      publish(rig_utime);
      // End-to-end latency: from the IMU sample's time to its estimate going out.
      const int64_t done_ns = transport::monotonic_ns();
      const int64_t age_ns = node_->age_ns(rig_utime, done_ns);
      node_->record_latency_ns(age_ns);
      if (node_->stage_timing()) {
        node_->record_stage_ns(stage_imu_in_, node_->age_ns(rig_utime, received_ns));
        node_->record_stage_ns(stage_estimate_out_, age_ns);
        node_->record_stage_ns(stage_work_, done_ns - received_ns);
        node_->record_stage_ns(stage_filter_, publish_ns - filter_ns);
        node_->record_stage_ns(stage_publish_, done_ns - publish_ns);
      }
    }
  });
  node_->bus().subscribe<mocap_pose_t>(contract::channels::kMocapPose, [this](const mocap_pose_t& m) {
    if (!transport::plausible_sim_utime(m.utime)) {
      node_->fault(fault_event_t::SEVERITY_WARNING, fault_event_t::CODE_MESSAGE_MALFORMED,
                   contract::channels::kMocapPose,
                   "pose at utime " + std::to_string(m.utime) + " us lies outside any run; ignored");
      return;
    }
    const MocapPose p = contract::from_message(m);
    if (!p.position_ned_m.allFinite() || !p.q_body_to_ned.coeffs().allFinite()) {
      node_->fault(fault_event_t::SEVERITY_WARNING, fault_event_t::CODE_MESSAGE_MALFORMED,
                   contract::channels::kMocapPose,
                   "motion-capture frame " + std::to_string(p.frame_number) + " has non-finite values: not used",
                   p.publish_utime);
      return;
    }
    if (node_->lockstep()) {
      pose_inbox_.push(p.publish_utime, p);
    } else {
      const int64_t start_ns = transport::monotonic_ns();
      apply_pose(p);
      if (node_->stage_timing()) node_->record_stage_ns(stage_pose_, transport::monotonic_ns() - start_ns);
    }
  });
  if (prefilter_) {
    node_->bus().subscribe<actuator_feedback_t>(
        contract::channels::kActuatorFeedback, [this](const actuator_feedback_t& m) {
          // Non-finite values are ignored by the prefilter itself.
          if (node_->lockstep())
            flap_inbox_.push(m.utime, {m.flap_freq_left_radps, m.flap_freq_right_radps});
          else
            prefilter_->set_flap_frequencies(m.flap_freq_left_radps, m.flap_freq_right_radps, m.utime);
        });
  }
  // Lockstep ticks only: in real time the work happens as the inputs arrive.
  node_->add_task(
      "estimator", sensing.imu.sample_rate_hz, [this](int64_t t) { tick(t); }, transport::ProcessNode::Trigger::kInput);
}

int EstimatorNode::run() { return node_->run(); }

bool EstimatorNode::imu_usable(const ImuSample& sample) {
  if (!sample.gyro_radps.allFinite() || !sample.accel_mps2.allFinite()) {
    node_->fault(fault_event_t::SEVERITY_WARNING, fault_event_t::CODE_MESSAGE_MALFORMED, contract::channels::kImu,
                 "IMU sample at " + std::to_string(sample.utime) + " us has non-finite values: not used", sample.utime);
    return false;
  }
  if (!stuck_check_) return true;
  const bool same = sample.gyro_radps == last_imu_.gyro_radps && sample.accel_mps2 == last_imu_.accel_mps2;
  last_imu_ = sample;
  imu_repeats_ = same ? imu_repeats_ + 1 : 0;
  if (!same && imu_stuck_) {
    imu_stuck_ = false;
    node_->fault(fault_event_t::SEVERITY_INFO, fault_event_t::CODE_SENSOR_STUCK, contract::channels::kImu,
                 "IMU values change again at " + std::to_string(sample.utime) + " us: samples used again",
                 sample.utime);
  }
  if (imu_repeats_ + 1 >= kImuStuckSamples && !imu_stuck_) {
    imu_stuck_ = true;
    node_->fault(fault_event_t::SEVERITY_ERROR, fault_event_t::CODE_SENSOR_STUCK, contract::channels::kImu,
                 "IMU stuck: " + std::to_string(kImuStuckSamples) + " bit-identical samples up to " +
                     std::to_string(sample.utime) + " us, impossible with its configured noise; samples not used",
                 sample.utime);
  }
  return !imu_stuck_;
}

void EstimatorNode::apply_imu(const ImuSample& sample, int64_t rig_utime) {
  last_imu_stamp_ = sample.utime;
  last_imu_rig_utime_ = rig_utime;
  if (!prefilter_) {
    if (ekf_->initialized()) ekf_->predict(sample);
    return;
  }
  const ImuSample s = prefilter_->filter(sample, rig_utime);
  if (ekf_->initialized()) ekf_->predict(s, &prefilter_->residual_var());
}

int64_t EstimatorNode::filter_rig_utime() const {
  return ekf_->utime() == last_imu_stamp_ ? last_imu_rig_utime_ : ekf_->utime();
}

void EstimatorNode::apply_pose(const MocapPose& pose) {
  if (last_frame_ >= 0 && pose.frame_number > last_frame_ + 1) poses_missing_ += pose.frame_number - last_frame_ - 1;
  last_frame_ = pose.frame_number;
  if (!pose.tracking_valid) ++poses_missing_;
  // With the on-board IMU filtering the filter starts once its lines are learnt (its start,
  // ImuPrefilter::settled): before, the samples still carry most of the vibration. The frames
  // before then are not differentiated either: their measurements would refer to before the start.
  if (!ekf_->initialized() && prefilter_ && !prefilter_->settled()) return;
  std::vector<PoseMeasurement> zs = builder_->push(pose);
  if (!ekf_->initialized() && !zs.empty()) {
    // The filter runs on the IMU's clock. When the IMU's stamps are behind the motion capture's
    // (sensing.imu.clock_offset_s < 0 in the rig, an unsynchronised clock in a lab) it starts at
    // the newest IMU stamp: started at the frame's, it would refuse every sample until the IMU's
    // clock reached the frame, and its estimate would stand still meanwhile.
    PoseMeasurement first = zs.front();
    if (last_imu_stamp_ != INT64_MIN && last_imu_stamp_ < first.utime) first.utime = last_imu_stamp_;
    ekf_->initialize_from_measurement(first);
    zs.erase(zs.begin());
  }
  // The frame's measurements together: one re-propagation for those that refer to the past.
  const std::vector<EkfMeasurementStatus> status = ekf_->add_measurements(zs);
  for (std::size_t i = 0; i < zs.size(); ++i) {
    if (status[i] == EkfMeasurementStatus::kTooOld || status[i] == EkfMeasurementStatus::kTooNew) {
      report_dropped(zs[i], status[i]);
    }
  }
  watch_divergence();
}

void EstimatorNode::watch_divergence() {
  if (!divergence_ || diverged_) return;
  // Decisions taken since the last look (a measurement held for the IMU is decided later).
  const EkfCounters& c = ekf_->counters();
  bool now_diverged = false;
  for (; seen_accepted_ < c.measurements_accepted; ++seen_accepted_) now_diverged |= divergence_->add(false);
  for (; seen_rejected_ < c.measurements_rejected_gate; ++seen_rejected_) now_diverged |= divergence_->add(true);
  if (!now_diverged) return;
  diverged_ = true;
  std::ostringstream msg;
  msg << std::fixed << std::setprecision(3) << "EKF diverged at t = " << 1e-6 * static_cast<double>(filter_rig_utime())
      << " s: " << divergence_->threshold() << " or more of the last " << divergence_->window()
      << " motion-capture measurements failed the innovation gate (a consistent filter does so with probability "
      << kDivergenceFalseAlarm << "; last NIS " << std::setprecision(1) << ekf_->last_nis()
      << "); no more estimates are published";
  node_->fault(fault_event_t::SEVERITY_ERROR, fault_event_t::CODE_ESTIMATOR_DIVERGED, contract::channels::kEstimate,
               msg.str(), filter_rig_utime());
}

void EstimatorNode::report_dropped(const PoseMeasurement& z, EkfMeasurementStatus status) {
  const int64_t now = ekf_->utime();  // the filter's time: the IMU's clock
  const int64_t rig_now = filter_rig_utime();
  if (last_drop_fault_utime_ != INT64_MIN && rig_now - last_drop_fault_utime_ < 1000000) return;
  last_drop_fault_utime_ = rig_now;
  const EkfCounters& c = ekf_->counters();
  std::ostringstream msg;
  msg << std::fixed << std::setprecision(1) << "mocap frame " << z.frame_number << " dropped by the EKF: ";
  if (status == EkfMeasurementStatus::kTooOld) {
    msg << "it refers to " << 1e-3 * static_cast<double>(now - z.utime)
        << " ms before the newest IMU sample, older than "
        << "the rollback history of " << 1e3 * ekf_->config().history_s << " ms (" << c.measurements_too_old
        << " so far); the motion-capture stream is late: raise sensing.ekf.latency.history_s or find the delay";
  } else {
    msg << "it refers to " << 1e-3 * static_cast<double>(z.utime - now) << " ms after the newest IMU sample, more than "
        << "the history of " << 1e3 * ekf_->config().history_s << " ms ahead (" << c.measurements_too_new
        << " so far); the IMU stream is late or the two clocks differ";
  }
  node_->fault(fault_event_t::SEVERITY_WARNING, fault_event_t::CODE_MEASUREMENT_OUT_OF_WINDOW,
               contract::channels::kMocapPose, msg.str(), rig_now);
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
      // The flapping frequencies measured up to this sample's time.
      while (flap_inbox_.ready(now_us) && flap_inbox_.front_stamp_utime() <= imu_inbox_.front_stamp_utime()) {
        prefilter_->set_flap_frequencies(flap_inbox_.front().first, flap_inbox_.front().second,
                                         flap_inbox_.front_stamp_utime());
        flap_inbox_.pop();
      }
      apply_imu(imu_inbox_.front(), imu_inbox_.front_stamp_utime());
      imu_inbox_.pop();
    } else {
      apply_pose(pose_inbox_.front());
      pose_inbox_.pop();
    }
  }
  publish(now_us);
}

void EstimatorNode::publish(int64_t utime) {
  watch_divergence();  // decisions taken when an IMU sample released a held measurement
  if (!ekf_->initialized() || diverged_) return;
  const EkfState& x = ekf_->state();
  const EkfCovariance& P = ekf_->covariance();
  const Eigen::Vector3d w = ekf_->corrected_rate_radps();
  Estimate m;
  m.utime = utime;
  m.seq = seq_++;
  m.imu_utime = filter_rig_utime();
  m.euler_rad = x.segment<3>(kPhi);
  m.velocity_body_mps = x.segment<3>(kU);
  m.gyro_bias_radps = x.segment<3>(kBiasP);
  m.accel_bias_mps2 = x.segment<3>(kBiasAx);
  m.omega_body_radps = w;
  m.cov_diag = P.diagonal();
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
  node_->bus().publish(contract::channels::kEstimate, contract::to_message(m));
}

}  // namespace nimble
