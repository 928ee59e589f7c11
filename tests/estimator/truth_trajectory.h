#pragma once
/// Kinematically consistent truth trajectories for estimator tests and benchmarks.
///
/// The body rates are smooth analytic functions of time (roll doublets plus slow pitch and yaw
/// sinusoids), the specific force a smooth function of time and state (hover thrust that holds
/// altitude, linear drag, a slow forward acceleration). Attitude, body velocity and position are
/// integrated from them (RK4, step <= max_step_s):
///   q_dot = 1/2 q * (0, omega_b),   v_b_dot = f_b + R^T (0, 0, g) - omega_b x v_b,   r_dot = R v_b,
/// with R = R_body_to_ned(q). So the specific force that an ideal IMU reads, the attitude mocap
/// sees and the body velocity the EKF estimates all belong to one rigid-body motion.
///
/// Roll doublet (one entry of TruthProfile::roll_doublets): the roll rate is the derivative of three
/// raised-cosine steps of the roll angle, +A at t0, -2A at t0 + P/2 and +A at t0 + P, each lasting
/// ramp_s (<= P/2): phi goes 0 -> A -> -A -> 0. Peak roll rate A pi / ramp_s. "Main frequency" of the
/// doublet: 1/P.

#include <cmath>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "sensors/imu_model.h"
#include "sensors/mocap_emulator.h"

namespace nimble {

/// One roll doublet (see the header).
struct RollDoublet {
  /// Start time [s].
  double start_s = 0.0;
  /// Duration P of the doublet [s] (1 / main frequency).
  double period_s = 0.5;
  /// Roll amplitude A [rad]; the sign gives the direction of the first half.
  double amplitude_rad = 0.4;
  /// Duration of each roll ramp [s], <= period_s / 2.
  double ramp_s = 0.15;
};

/// Manoeuvre and vehicle-like dynamics of a truth trajectory.
struct TruthProfile {
  /// Roll doublets (may overlap; their rates add).
  std::vector<RollDoublet> roll_doublets;
  double pitch_rate_amplitude_radps = 0.3;  ///< q(t) = amplitude sin(2 pi f t + phase) [rad/s]
  double pitch_rate_frequency_hz = 0.7;     ///< f of q(t) [Hz]
  double pitch_rate_phase_rad = 0.0;        ///< phase of q(t) [rad]
  double yaw_rate_amplitude_radps = 0.3;    ///< r(t) = amplitude sin(2 pi f t + phase) [rad/s]
  double yaw_rate_frequency_hz = 0.3;       ///< f of r(t) [Hz]
  double yaw_rate_phase_rad = 0.0;          ///< phase of r(t) [rad]
  double forward_accel_amplitude_mps2 =
      0.5;  ///< forward specific-force command a(t) = amplitude sin(2 pi f t + phase) [m/s^2]
  double forward_accel_frequency_hz = 0.4;          ///< f of a(t) [Hz]
  double forward_accel_phase_rad = 0.0;             ///< phase of a(t) [rad]
  double drag_u_per_s = 1.0;                        ///< linear drag on u [1/s] (assumption)
  double drag_v_per_s = 1.95;                       ///< linear drag on v [1/s]: -Yv/m of set 1 (5.61e-2 / 0.02876 kg)
  double vertical_damping_per_s = 2.0;              ///< damping of the NED down velocity by the thrust [1/s]
  double gravity_mps2 = 9.81;                       ///< [m/s^2]
  double flap_frequency_radps = 2.0 * M_PI * 17.0;  ///< both wing pairs [rad/s]; thesis Table A.1: 17 Hz
  Eigen::Vector3d initial_position_ned_m = Eigen::Vector3d(0.0, 0.0, -1.5);  ///< [m]
  Eigen::Vector3d initial_euler_rad = Eigen::Vector3d::Zero();               ///< ZYX [rad]
  Eigen::Vector3d initial_velocity_body_mps = Eigen::Vector3d::Zero();       ///< [m/s]
  /// Largest RK4 step [s].
  double max_step_s = 5e-4;
};

/// A seeded random manoeuvre resembling the thesis's identification flights: roll doublets of
/// 20-30 deg with peak roll rates 6-10 rad/s (main frequencies about 1-3 Hz) every 1-2.5 s from
/// t = 1 s on, lateral speeds up to about 1 m/s, slow pitch (about +-5 deg) and yaw motion.
TruthProfile make_roll_doublet_profile(std::uint64_t seed, double duration_s);

/// Truth at one instant; mirrors truth_state_t.
struct TruthSample {
  std::int64_t utime = 0;                                               ///< [us]
  Eigen::Vector3d position_ned_m = Eigen::Vector3d::Zero();             ///< [m]
  Eigen::Vector3d velocity_body_mps = Eigen::Vector3d::Zero();          ///< [m/s]
  Eigen::Quaterniond q_body_to_ned = Eigen::Quaterniond::Identity();    ///< body -> NED
  Eigen::Vector3d euler_rad = Eigen::Vector3d::Zero();                  ///< ZYX [rad]
  Eigen::Vector3d omega_body_radps = Eigen::Vector3d::Zero();           ///< [rad/s]
  Eigen::Vector3d specific_force_body_mps2 = Eigen::Vector3d::Zero();   ///< [m/s^2]
  Eigen::Vector3d angular_accel_body_radps2 = Eigen::Vector3d::Zero();  ///< [rad/s^2]
  double flap_freq_left_radps = 0.0;                                    ///< [rad/s]
  double flap_freq_right_radps = 0.0;                                   ///< [rad/s]

  /// The IMU model's input at this instant.
  ImuTruthInput imu_input() const;
  /// The mocap emulator's input at this instant.
  MocapTruthInput mocap_input() const;
};

/// Integrates a TruthProfile forward in time.
class TruthTrajectory {
 public:
  /// @throws std::invalid_argument if a doublet has ramp_s <= 0 or ramp_s > period_s / 2, or max_step_s <= 0.
  explicit TruthTrajectory(const TruthProfile& profile, std::int64_t start_utime = 0);

  /// Integrates to `utime` (>= the current time; an earlier time returns the current sample).
  const TruthSample& advance_to(std::int64_t utime);
  /// Sample at the current time.
  const TruthSample& current() const { return sample_; }
  /// Body rates of the profile at time t_s [rad/s].
  Eigen::Vector3d omega_at(double t_s) const;

 private:
  struct Derivative {
    Eigen::Vector4d q_dot;
    Eigen::Vector3d v_dot;
    Eigen::Vector3d r_dot;
  };
  Eigen::Vector3d specific_force(double t_s, const Eigen::Quaterniond& q, const Eigen::Vector3d& v_b) const;
  Derivative derivative(double t_s, const Eigen::Vector4d& q_wxyz, const Eigen::Vector3d& v_b) const;
  void rk4_step(double h_s);
  void fill_sample();

  TruthProfile profile_;
  double t_s_ = 0.0;
  std::int64_t utime_ = 0;
  Eigen::Vector4d q_wxyz_;
  Eigen::Vector3d v_b_, r_ned_;
  TruthSample sample_;
};

}  // namespace nimble
