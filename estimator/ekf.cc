#include "estimator/ekf.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include <Eigen/Cholesky>

#include "core/attitude.h"
#include "core/chi_square.h"

namespace nimble {
namespace {

/// Velocity relative to the world in NED axes [m/s] of a filter state.
Eigen::Vector3d world_velocity(const EkfState& x) { return rotation_from_euler_zyx(x.head<3>()) * x.segment<3>(3); }

EkfInput lerp(const EkfInput& a, const EkfInput& b, std::int64_t ta, std::int64_t tb, std::int64_t t) {
  if (tb <= ta) return b;
  const double s = static_cast<double>(t - ta) / static_cast<double>(tb - ta);
  return a + s * (b - a);
}

template <int M>
bool update_fixed(EkfState* x, EkfCovariance* P, const Eigen::Matrix<double, M, 1>& z,
                  const Eigen::Matrix<double, M, 1>& r_diag, double gate_threshold, bool gate,
                  EkfUpdateRecord* record) {
  Eigen::Matrix<double, M, 1> y = z - x->template head<M>();
  for (int i = 0; i < 3; ++i) y[i] = wrap_angle_rad(y[i]);
  Eigen::Matrix<double, M, M> S = P->template topLeftCorner<M, M>();
  S.diagonal() += r_diag;
  const Eigen::LLT<Eigen::Matrix<double, M, M>> llt(S);
  record->dim = M;
  if (llt.info() != Eigen::Success) {  // S not positive definite: reject, reported as infinite NIS
    record->nis = std::numeric_limits<double>::infinity();
    record->accepted = false;
    return false;
  }
  const double nis = y.dot(llt.solve(y));
  record->nis = nis;
  record->innovation.setZero();
  record->innovation.template head<M>() = y;
  if (!std::isfinite(nis) || (gate && nis > gate_threshold)) {
    record->accepted = false;
    return false;
  }
  // K = P H^T S^-1 with H = [I 0]: P H^T = left M columns of P.
  const Eigen::Matrix<double, kEkfStateDim, M> PHt = P->template leftCols<M>();
  const Eigen::Matrix<double, kEkfStateDim, M> K = llt.solve(PHt.transpose()).transpose();
  *x += K * y;
  // Joseph form (I - K H) P (I - K H)^T + K R K^T with H = [I 0], without forming I - K H:
  //   X = (I - K H) P = P - K P_top               (P_top: the first M rows of P)
  //   X (I - K H)^T = X - X_left K^T                (X_left: the first M columns of X)
  // two 12 x M x 12 products instead of two 12 x 12 x 12.
  const Eigen::Matrix<double, M, kEkfStateDim> P_top = P->template topRows<M>();
  EkfCovariance X = *P;
  X.noalias() -= K.lazyProduct(P_top);
  const Eigen::Matrix<double, kEkfStateDim, M> X_left = X.template leftCols<M>();
  EkfCovariance Pn = X;
  Pn.noalias() -= X_left.lazyProduct(K.transpose());
  const Eigen::Matrix<double, kEkfStateDim, M> KR = K * r_diag.asDiagonal();
  Pn.noalias() += KR.lazyProduct(K.transpose());
  *P = 0.5 * (Pn + Pn.transpose());
  ekf_wrap_angles(x);
  record->accepted = true;
  return true;
}

bool finite(const PoseMeasurement& z) {
  return z.euler_rad.allFinite() && (!z.has_velocity || z.velocity_body_mps.allFinite());
}

}  // namespace

AttitudeVelocityEkf::AttitudeVelocityEkf(const EkfConfig& config) : config_(config) {
  validate(config_);
  params_ = config_.model_params();
  input_psd_ << config_.gyro_noise_var_per_sample_rad2ps2, config_.accel_noise_var_per_sample_m2ps4;
  input_psd_ /= config_.process_noise_reference_rate_hz;
  bias_rw_psd_ << config_.gyro_bias_rw_radps_per_sqrts.array().square().matrix(),
      config_.accel_bias_rw_mps2_per_sqrts.array().square().matrix();
  gate3_ = chi_square_quantile(config_.gate_probability, 3.0);
  gate6_ = chi_square_quantile(config_.gate_probability, 6.0);
  history_us_ = static_cast<std::int64_t>(std::llround(config_.history_s * 1e6));
}

void AttitudeVelocityEkf::initialize(std::int64_t utime, const EkfState& x0, const EkfCovariance& P0) {
  history_.clear();
  kept_.clear();
  accepted_.clear();
  pending_.clear();
  Node node;
  node.utime = utime;
  node.x = x0;
  ekf_wrap_angles(&node.x);
  node.P = 0.5 * (P0 + P0.transpose());
  node.input_psd = input_psd_;
  history_.push_back(node);
  kept_.emplace_back();
  initialized_utime_ = utime;
  last_nis_ = -1.0;
}

void AttitudeVelocityEkf::initialize_from_measurement(const PoseMeasurement& z) {
  EkfState x0 = EkfState::Zero();
  x0.head<3>() = z.euler_rad;
  if (z.has_velocity) x0.segment<3>(kU) = z.velocity_body_mps;
  initialize(z.utime, x0, config_.initial_covariance());
}

Eigen::Vector3d AttitudeVelocityEkf::corrected_rate_radps() const {
  const Node& n = history_.back();
  return n.u.head<3>() - n.x.segment<3>(kBiasP);
}

bool AttitudeVelocityEkf::state_at(std::int64_t utime, EkfState* x, EkfCovariance* P) const {
  for (auto it = history_.rbegin(); it != history_.rend(); ++it) {
    if (it->utime <= utime) {
      if (x) *x = it->x;
      if (P) *P = it->P;
      return true;
    }
  }
  return false;
}

void AttitudeVelocityEkf::propagate(EkfState* x, EkfCovariance* P, const EkfInput& u0, const EkfInput& u1, double dt_s,
                                    const EkfInput& psd, EkfCovariance* Phi, StepLinearisation* made) const {
  using Mat63 = Eigen::Matrix<double, 6, 3>;
  // One linearisation (f, A, B) at each end of the step, each with one evaluation of the trigonometry.
  const EkfLinearisation lin0 = ekf_linearise(*x, u0, params_);
  const EkfState& k0 = lin0.x_dot;
  const EkfState x1 = *x + dt_s * k0;
  const EkfLinearisation lin1 = ekf_linearise(x1, u1, params_);
  const EkfState& k1 = lin1.x_dot;

  // The bias rows of F are zero: F = [A B; 0 0] (6x6 blocks), so
  //   Phi = I + dt/2 (F0 + F1) + dt^2/2 F1 F0 = [Phi11 Phi12; 0 I],
  //   Phi11 = I + dt/2 (A0 + A1) + dt^2/2 A1 A0,  Phi12 = dt/2 (B0 + B1) + dt^2/2 A1 B0,
  // and G = df/du_m = -B (top rows). The products below are the 12x12 formula of the header
  // written blockwise (a third of the operations). Small fixed-size products use lazyProduct
  // (coefficient-based), which is faster than Eigen's blocked GEMM at this size.
  // B = [B_g B_a]: the gyro-bias columns B_g (6x3) depend on the point, the accelerometer-bias
  // columns are B_a = [0; -I] at every point (ekf_model.cc), which the products below use.
  const Mat6& A0 = lin0.A;
  const Mat6& A1 = lin1.A;
  const Mat63 Bg0 = lin0.B.leftCols<3>();
  const Mat63 Bg1 = lin1.B.leftCols<3>();
  const double h2 = 0.5 * dt_s, hh2 = 0.5 * dt_s * dt_s;
  StepLinearisation step;
  step.Phi11.noalias() = A1.lazyProduct(A0);
  step.Phi11 = hh2 * step.Phi11 + h2 * (A0 + A1);
  step.Phi11.diagonal().array() += 1.0;
  // Phi12 = [dt/2 (B_g0 + B_g1) + dt^2/2 A1 B_g0,  -dt [0; I] - dt^2/2 A1 [0; I]]; A1 [0; I] are
  // the velocity columns of A1, zero in the attitude rows.
  Mat63 A1Bg0;
  A1Bg0.noalias() = A1.lazyProduct(Bg0);
  step.Phi12.leftCols<3>() = hh2 * A1Bg0 + h2 * (Bg0 + Bg1);
  step.Phi12.rightCols<3>() = -hh2 * A1.rightCols<3>();
  step.Phi12.bottomRightCorner<3, 3>().diagonal().array() -= dt_s;
  // Qc = G S G^T + diag(0, 0, q_bg, q_ba) = [Q 0; 0 diag(q_bg, q_ba)] with
  // Q = B S B^T = B_g S_g B_g^T + diag(0, S_a) (S = diag(S_g, S_a)).
  const auto input_noise = [&psd](const Mat63& Bg) {
    const Mat63 BgS = Bg * psd.head<3>().asDiagonal();
    Mat6 Q;
    Q.noalias() = BgS.lazyProduct(Bg.transpose());
    Q.diagonal().tail<3>() += psd.tail<3>();
    return Q;
  };
  step.Q0 = input_noise(Bg0);
  step.Q1 = input_noise(Bg1);
  propagate_covariance(P, step, dt_s);
  *x += 0.5 * dt_s * (k0 + k1);
  ekf_wrap_angles(x);
  if (Phi != nullptr) {
    EkfCovariance transition = EkfCovariance::Identity();
    transition.topLeftCorner<6, 6>() = step.Phi11;
    transition.topRightCorner<6, 6>() = step.Phi12;
    *Phi = transition * *Phi;
  }
  if (made != nullptr) *made = step;
}

void AttitudeVelocityEkf::propagate_covariance(EkfCovariance* P, const StepLinearisation& step, double dt_s) const {
  const double h2 = 0.5 * dt_s;
  const Mat6& Phi11 = step.Phi11;
  const Mat6& Phi12 = step.Phi12;
  // M = P + dt/2 Qc0
  const Mat6 M11 = P->topLeftCorner<6, 6>() + h2 * step.Q0;
  const Mat6 M12 = P->topRightCorner<6, 6>();
  const Mat6 M21 = P->bottomLeftCorner<6, 6>();
  Mat6 M22 = P->bottomRightCorner<6, 6>();
  M22.diagonal() += h2 * bias_rw_psd_;
  // Phi M = [X11 X12; M21 M22]
  Mat6 X11, X12;
  X11.noalias() = Phi11.lazyProduct(M11);
  X11.noalias() += Phi12.lazyProduct(M21);
  X12.noalias() = Phi11.lazyProduct(M12);
  X12.noalias() += Phi12.lazyProduct(M22);
  // Phi M Phi^T + dt/2 Qc1 = [X11 Phi11^T + X12 Phi12^T + dt/2 Q1, X12; X12^T, M22 + dt/2 diag(q_bg, q_ba)].
  // P is kept exactly symmetric, so only the top-left block needs symmetrising.
  Mat6 N11;
  N11.noalias() = X11.lazyProduct(Phi11.transpose());
  N11.noalias() += X12.lazyProduct(Phi12.transpose());
  N11 += h2 * step.Q1;
  M22.diagonal() += h2 * bias_rw_psd_;
  P->topLeftCorner<6, 6>() = 0.5 * (N11 + N11.transpose());
  P->topRightCorner<6, 6>() = X12;
  P->bottomLeftCorner<6, 6>() = X12.transpose();
  P->bottomRightCorner<6, 6>() = M22;
}

void AttitudeVelocityEkf::propagate_with(EkfState* x, EkfCovariance* P, const EkfInput& u0, const EkfInput& u1,
                                         double dt_s, const StepLinearisation& step) const {
  // The state as propagate() makes it (f alone: the same values as the linearisation's x_dot).
  const EkfState k0 = ekf_process_derivative(*x, u0, params_);
  const EkfState x1 = *x + dt_s * k0;
  const EkfState k1 = ekf_process_derivative(x1, u1, params_);
  propagate_covariance(P, step, dt_s);
  *x += 0.5 * dt_s * (k0 + k1);
  ekf_wrap_angles(x);
}

bool AttitudeVelocityEkf::reusable(const EkfState& x0, const EkfState& x) const {
  const EkfState d = (x - x0).cwiseAbs();
  // f depends on phi and theta, not on psi (ekf_model.h); phi wraps, and a wrapped difference
  // near 2 pi simply linearises again.
  return std::max(d[kPhi], d[kTheta]) <= config_.replay_relinearise_attitude_rad &&
         d.segment<3>(kU).maxCoeff() <= config_.replay_relinearise_velocity_mps &&
         d.segment<3>(kBiasP).maxCoeff() <= config_.replay_relinearise_gyro_bias_radps;
}

void AttitudeVelocityEkf::propagate_interval(EkfState* x, EkfCovariance* P, const EkfInput& u0, const EkfInput& u1,
                                             std::int64_t t0, std::int64_t t1, const EkfInput& psd, EkfCovariance* Phi,
                                             KeptSteps* kept, bool* reused) const {
  if (reused != nullptr) *reused = false;
  if (t1 <= t0) return;
  const double dt_s = 1e-6 * (static_cast<double>(t1) - static_cast<double>(t0));
  // At most kMaxSubsteps: an IMU time far ahead (a stray message, found by fuzz_node_estimator)
  // took one step per max_step_s, without end; such an interval is integrated coarsely instead.
  constexpr double kMaxSubsteps = 400;  // 1 s at the default max_step_s
  const int steps = static_cast<int>(std::clamp(std::ceil(dt_s / config_.max_step_s - 1e-9), 1.0, kMaxSubsteps));
  // The inputs at the substeps' ends, u0 + (i / steps) (u1 - u0) (for one step: u0 and
  // u0 + (u1 - u0), which may differ from u1 in the last bit; kept as the substeps make them).
  const auto input_at = [&](int i) { return EkfInput(u0 + (static_cast<double>(i) / steps) * (u1 - u0)); };
  if (kept != nullptr && steps == 1 && Phi == nullptr) {
    const EkfInput ua = input_at(0), ub = input_at(1);
    for (KeptStep& e : kept->entry) {
      if (e.t0 == t0 && e.t1 == t1 && reusable(e.x0, *x)) {
        propagate_with(x, P, ua, ub, dt_s, e.step);
        if (reused != nullptr) *reused = true;
        return;
      }
    }
    // A new step, kept in place of the same interval's or else of the older entry.
    KeptStep* slot = &kept->entry[kept->next];
    for (KeptStep& e : kept->entry) {
      if (e.t0 == t0 && e.t1 == t1) slot = &e;
    }
    if (slot == &kept->entry[kept->next]) kept->next = (kept->next + 1) % 2;
    slot->t0 = t0;
    slot->t1 = t1;
    slot->x0 = *x;
    propagate(x, P, ua, ub, dt_s, psd, nullptr, &slot->step);
    return;
  }
  const double h = dt_s / steps;
  for (int i = 0; i < steps; ++i) propagate(x, P, input_at(i), input_at(i + 1), h, psd, Phi);
}

void AttitudeVelocityEkf::replay_interval(EkfState* x, EkfCovariance* P, const EkfInput& u0, const EkfInput& u1,
                                          std::int64_t t0, std::int64_t t1, const EkfInput& psd, KeptSteps* kept) {
  bool reused = false;
  propagate_interval(x, P, u0, u1, t0, t1, psd, nullptr, kept, &reused);
  ++counters_.replay_steps;
  if (!reused) ++counters_.replay_steps_linearised;
}

EkfCovariance AttitudeVelocityEkf::predict_between(EkfState* x, EkfCovariance* P, const EkfInput& u0,
                                                   const EkfInput& u1, std::int64_t t0, std::int64_t t1,
                                                   const EkfInput* input_psd) const {
  EkfCovariance Phi = EkfCovariance::Identity();
  propagate_interval(x, P, u0, u1, t0, t1, input_psd != nullptr ? *input_psd : input_psd_, &Phi);
  return Phi;
}

void AttitudeVelocityEkf::release_history() {
  if (node_observer_) {
    for (const Node& n : history_) node_observer_(n);
  }
  history_.clear();
  kept_.clear();
  accepted_.clear();
  pending_.clear();
}

bool AttitudeVelocityEkf::predict(const ImuSample& sample, const EkfInput* input_var_per_sample) {
  EkfInput u;
  u << sample.gyro_radps, sample.accel_mps2;
  return predict(sample.utime, u, input_var_per_sample);
}

bool AttitudeVelocityEkf::predict(std::int64_t utime, const EkfInput& imu_input, const EkfInput* input_var_per_sample) {
  if (!initialized() || !imu_input.allFinite()) {
    ++counters_.imu_rejected;
    return false;
  }
  Node& last = history_.back();
  if (utime <= last.utime) {
    if (!last.has_input && utime == last.utime) {
      last.u = imu_input;
      last.has_input = true;
      ++counters_.imu_samples;
      return true;
    }
    ++counters_.imu_rejected;
    return false;
  }
  if (1e-6 * (static_cast<double>(utime) - static_cast<double>(last.utime)) > config_.imu_gap_s) ++counters_.imu_gaps;
  Node next;
  next.utime = utime;
  next.u = imu_input;
  next.has_input = true;
  next.x = last.x;
  next.P = last.P;
  next.input_psd = input_psd_;
  if (input_var_per_sample != nullptr && input_var_per_sample->allFinite()) {
    next.input_psd = next.input_psd.cwiseMax(*input_var_per_sample / config_.process_noise_reference_rate_hz);
  }
  const EkfInput u0 = last.has_input ? last.u : imu_input;
  if (!last.has_input) {
    last.u = imu_input;
    last.has_input = true;
  }
  kept_.emplace_back();
  propagate_interval(&next.x, &next.P, u0, imu_input, last.utime, utime, next.input_psd, nullptr, &kept_.back());
  history_.push_back(next);
  ++counters_.imu_samples;

  // Measurements that were waiting for this sample.
  while (!pending_.empty() && ready_utime(pending_.front()) <= utime) {
    const PoseMeasurement z = prepared(pending_.front());
    pending_.erase(pending_.begin());
    if (config_.latency_mode == EkfLatencyMode::kNaive) {
      apply_now(z);
    } else {
      insert_in_past(z);
    }
  }
  trim();
  return true;
}

void AttitudeVelocityEkf::trim() {
  const std::int64_t cutoff = history_.back().utime - history_us_;
  while (history_.size() >= 2 && history_[1].utime <= cutoff) {
    if (node_observer_) node_observer_(history_.front());
    history_.pop_front();
    kept_.pop_front();
  }
  while (!accepted_.empty() && accepted_.front().z.utime <= history_.front().utime) accepted_.pop_front();
}

void AttitudeVelocityEkf::report(const EkfUpdateRecord& record) {
  last_nis_ = record.nis;
  if (record.accepted) {
    ++counters_.measurements_accepted;
  } else {
    ++counters_.measurements_rejected_gate;
  }
  if (observer_) observer_(record);
}

bool AttitudeVelocityEkf::update(EkfState* x, EkfCovariance* P, const PoseMeasurement& z, bool gate,
                                 EkfUpdateRecord* record) const {
  record->utime = z.utime;
  record->frame_number = z.frame_number;
  record->filter_utime = history_.back().utime;
  const bool use_gate = gate && config_.gate_enabled;
  if (z.has_velocity) {
    Eigen::Matrix<double, 6, 1> zv, r;
    zv << z.euler_rad, z.velocity_body_mps;
    r << config_.attitude_var_rad2, config_.velocity_var_m2ps2;
    return update_fixed<6>(x, P, zv, r, gate6_, use_gate, record);
  }
  return update_fixed<3>(x, P, z.euler_rad, config_.attitude_var_rad2, gate3_, use_gate, record);
}

EkfMeasurementStatus AttitudeVelocityEkf::apply_now(const PoseMeasurement& z) {
  Node& now = history_.back();
  EkfUpdateRecord record;
  const bool ok = update(&now.x, &now.P, z, true, &record);
  report(record);
  return ok ? EkfMeasurementStatus::kAccepted : EkfMeasurementStatus::kRejectedGate;
}

EkfMeasurementStatus AttitudeVelocityEkf::insert_in_past(const PoseMeasurement& z) {
  if (too_old(z)) {
    ++counters_.measurements_too_old;
    return EkfMeasurementStatus::kTooOld;
  }
  EkfMeasurementStatus status = EkfMeasurementStatus::kAccepted;
  replay(store(z, &status));
  return status;
}

std::size_t AttitudeVelocityEkf::store(const PoseMeasurement& z, EkfMeasurementStatus* status) {
  // j: last node strictly before the measurement.
  std::size_t j = history_.size() - 1;
  while (j > 0 && history_[j].utime >= z.utime) --j;
  if (z.utime < history_.back().utime) ++counters_.rollbacks;
  // Insert into the stored measurements, after those with the same or an earlier time.
  auto pos = std::upper_bound(accepted_.begin(), accepted_.end(), z.utime,
                              [](std::int64_t t, const Stored& s) { return t < s.z.utime; });
  accepted_.insert(pos, Stored{z, true, status});
  return j;
}

void AttitudeVelocityEkf::replay(std::size_t j) {
  EkfState x = history_[j].x;
  EkfCovariance P = history_[j].P;
  std::int64_t t = history_[j].utime;
  std::size_t k =
      static_cast<std::size_t>(std::upper_bound(accepted_.begin(), accepted_.end(), t,
                                                [](std::int64_t tt, const Stored& s) { return tt < s.z.utime; }) -
                               accepted_.begin());
  for (std::size_t i = j; i + 1 < history_.size(); ++i) {
    const Node& a = history_[i];
    Node& b = history_[i + 1];
    while (k < accepted_.size() && accepted_[k].z.utime <= b.utime) {
      const std::int64_t tm = accepted_[k].z.utime;
      if (tm > t) {
        replay_interval(&x, &P, lerp(a.u, b.u, a.utime, b.utime, t), lerp(a.u, b.u, a.utime, b.utime, tm), t, tm,
                        b.input_psd, &kept_[i + 1]);
        t = tm;
      }
      EkfUpdateRecord record;
      if (accepted_[k].is_new) {
        const bool ok = update(&x, &P, accepted_[k].z, true, &record);
        report(record);
        if (accepted_[k].status) {
          *accepted_[k].status = ok ? EkfMeasurementStatus::kAccepted : EkfMeasurementStatus::kRejectedGate;
        }
        if (!ok) {
          accepted_.erase(accepted_.begin() + static_cast<std::ptrdiff_t>(k));
          continue;
        }
        accepted_[k].is_new = false;
        accepted_[k].status = nullptr;
      } else {
        update(&x, &P, accepted_[k].z, false, &record);
      }
      ++k;
    }
    if (t < b.utime) {
      replay_interval(&x, &P, lerp(a.u, b.u, a.utime, b.utime, t), b.u, t, b.utime, b.input_psd, &kept_[i + 1]);
      t = b.utime;
    }
    b.x = x;
    b.P = P;
  }
}

bool AttitudeVelocityEkf::too_old(const PoseMeasurement& z) const {
  return z.utime <= history_.front().utime || z.utime < history_.back().utime - history_us_;
}

std::int64_t AttitudeVelocityEkf::ready_utime(const PoseMeasurement& z) const {
  const bool window = z.has_velocity && config_.velocity_measurement == EkfVelocityMeasurement::kWindowMean;
  return window ? std::max(z.utime, z.velocity_window_end_utime) : z.utime;
}

bool AttitudeVelocityEkf::velocity_window_offset(const PoseMeasurement& z, Eigen::Vector3d* offset) const {
  const std::int64_t ts = z.velocity_window_start_utime, te = z.velocity_window_end_utime;
  if (!(ts <= z.utime && z.utime <= te && ts < te)) return false;
  if (history_.front().utime > ts || history_.back().utime < te) return false;
  std::size_t i = 0;
  while (i + 1 < history_.size() && history_[i + 1].utime <= ts) ++i;
  // World velocity of the nodes from i on [m/s], each evaluated once (a rotation each).
  std::vector<Eigen::Vector3d> node_velocity(history_.size() - i);
  std::vector<char> node_velocity_known(history_.size() - i, 0);
  const auto velocity_of = [&](std::size_t n) -> const Eigen::Vector3d& {
    if (!node_velocity_known[n - i]) {
      node_velocity[n - i] = world_velocity(history_[n].x);
      node_velocity_known[n - i] = 1;
    }
    return node_velocity[n - i];
  };
  // World velocity along the history, linear between nodes; its integral over [ts, te] by the
  // trapezoidal rule, ends interpolated.
  const auto at = [&](std::size_t k, std::int64_t t) {  // between node k and k + 1
    const Node& a = history_[k];
    if (k + 1 >= history_.size() || t <= a.utime) return velocity_of(k);
    const Node& b = history_[k + 1];
    const double s = static_cast<double>(t - a.utime) / static_cast<double>(b.utime - a.utime);
    return Eigen::Vector3d((1.0 - s) * velocity_of(k) + s * velocity_of(k + 1));
  };
  Eigen::Vector3d integral = Eigen::Vector3d::Zero(), v_mid = at(i, ts), v_prev = v_mid;
  std::int64_t t_prev = ts;
  std::size_t mid_node = i;
  bool mid_found = false;
  for (std::size_t k = i; t_prev < te; ++k) {
    const std::int64_t t_next = (k + 1 < history_.size()) ? std::min(history_[k + 1].utime, te) : te;
    const Eigen::Vector3d v_next = at(k, t_next);
    if (!mid_found && z.utime <= t_next) {
      v_mid = at(k, z.utime);
      mid_node = (z.utime - history_[k].utime <= t_next - z.utime || k + 1 >= history_.size()) ? k : k + 1;
      mid_found = true;
    }
    integral += 0.5 * static_cast<double>(t_next - t_prev) * (v_prev + v_next);
    t_prev = t_next;
    v_prev = v_next;
  }
  const Eigen::Vector3d mean = integral / static_cast<double>(te - ts);
  *offset = rotation_from_euler_zyx(history_[mid_node].x.head<3>()).transpose() * (mean - v_mid);
  return true;
}

PoseMeasurement AttitudeVelocityEkf::prepared(const PoseMeasurement& z) {
  if (!z.has_velocity || config_.velocity_measurement != EkfVelocityMeasurement::kWindowMean) return z;
  // Without a window (start not before end) the velocity is taken as instantaneous.
  if (z.velocity_window_start_utime >= z.velocity_window_end_utime) return z;
  // Too old for the history: dropped by insert_in_past, nothing to offset or count.
  if (too_old(z)) return z;
  PoseMeasurement out = z;
  Eigen::Vector3d offset;
  if (velocity_window_offset(z, &offset)) {
    out.velocity_body_mps -= offset;
  } else if (z.velocity_window_start_utime >= initialized_utime_) {
    // A window that starts before the filter did cannot be covered; only later ones count.
    ++counters_.velocity_window_uncovered;
  }
  return out;
}

EkfMeasurementStatus AttitudeVelocityEkf::add_measurement(const PoseMeasurement& z) {
  EkfMeasurementStatus status = EkfMeasurementStatus::kAccepted;
  add_batch(&z, 1, &status);
  return status;
}

std::vector<EkfMeasurementStatus> AttitudeVelocityEkf::add_measurements(const std::vector<PoseMeasurement>& zs) {
  std::vector<EkfMeasurementStatus> status(zs.size(), EkfMeasurementStatus::kAccepted);
  add_batch(zs.data(), zs.size(), status.data());
  return status;
}

void AttitudeVelocityEkf::add_batch(const PoseMeasurement* zs, std::size_t n, EkfMeasurementStatus* status) {
  constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();
  std::size_t from = kNone;  // first node of the replay the stored measurements wait for
  std::int64_t last_stored_utime = std::numeric_limits<std::int64_t>::min();
  for (std::size_t i = 0; i < n; ++i) {
    const PoseMeasurement& z = zs[i];
    if (!initialized()) {
      ++counters_.measurements_invalid;
      status[i] = EkfMeasurementStatus::kNotInitialized;
      continue;
    }
    if (!finite(z)) {
      ++counters_.measurements_invalid;
      status[i] = EkfMeasurementStatus::kInvalid;
      continue;
    }
    const std::int64_t now = history_.back().utime;
    if (config_.latency_mode == EkfLatencyMode::kNaive) {
      status[i] = apply_now(prepared(z));
      continue;
    }
    if (z.utime > now + history_us_) {
      ++counters_.measurements_too_new;
      status[i] = EkfMeasurementStatus::kTooNew;
      continue;
    }
    const std::int64_t ready = ready_utime(z);
    if (ready > now) {
      auto pos = std::upper_bound(pending_.begin(), pending_.end(), ready,
                                  [this](std::int64_t t, const PoseMeasurement& m) { return t < ready_utime(m); });
      pending_.insert(pos, z);
      status[i] = EkfMeasurementStatus::kPending;
      continue;
    }
    // One replay serves the measurements stored since the last, with the result of one replay
    // each: a window offset reads the history, which must hold the earlier measurements first,
    // and a measurement before one already stored would be gated before it.
    const bool reads_history = z.has_velocity && config_.velocity_measurement == EkfVelocityMeasurement::kWindowMean;
    if (from != kNone && (reads_history || z.utime < last_stored_utime)) {
      replay(from);
      from = kNone;
    }
    const PoseMeasurement zp = prepared(z);
    if (too_old(zp)) {
      ++counters_.measurements_too_old;
      status[i] = EkfMeasurementStatus::kTooOld;
      continue;
    }
    from = std::min(from, store(zp, &status[i]));
    last_stored_utime = zp.utime;
  }
  if (from != kNone) replay(from);
}

}  // namespace nimble
