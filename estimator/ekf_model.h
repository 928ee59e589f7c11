#pragma once
/// Process and measurement model of the attitude/velocity EKF (thesis Section 8.1, Eq 8.1).
///
/// State x (12): [phi theta psi | u v w | b_p b_q b_r | b_ax b_ay b_az]
///   ZYX Euler angles of the body relative to NED [rad]; velocity relative to the world in body
///   axes [m/s]; gyro bias [rad/s]; accelerometer bias [m/s^2].
/// Input u_m (6): IMU sample [p_m q_m r_m | a_xm a_ym a_zm], gyro [rad/s] and specific force
///   [m/s^2] in body axes (specific force about (0, 0, -g) at rest).
/// Corrected rates and specific force: (p, q, r) = gyro - b_gyro, (a_x, a_y, a_z) = accel - b_accel.
///
/// Continuous-time model x_dot = f(x, u_m):
///   phi_dot   = p + (q sin(phi) + r cos(phi)) tan(theta)
///   theta_dot = q cos(phi) - r sin(phi)
///   psi_dot   = (q sin(phi) + r cos(phi)) / cos(theta)
///   u_dot     = a_x - g sin(theta)               - (q w - r v)
///   v_dot     = a_y + g cos(theta) sin(phi)      - (r u - p w)
///   w_dot     = a_z + g cos(theta) cos(phi)      - (p v - q u)
///   b_dot     = 0 (+ random walk noise)
/// i.e. v_b_dot = f_b + R_body_to_world^T (0, 0, g) - omega x v_b, with specific force f_b.
/// cos(theta) is kept at least min_abs_cos_theta in magnitude (sign kept) so that the model stays
/// finite at the pitch singularity; the filter is meant for |theta| < 90 deg.
///
/// Noise: the IMU reads u_m = u_true + b + n, n white; f depends on n exactly as on -b, so the
/// input-noise Jacobian is G = df/du_m = -df/db (columns 6..11 of F with the sign flipped).
///
/// Measurement z = h(x): z = [phi theta psi u v w] (6) or [phi theta psi] (3, attitude only);
/// H = [I 0]. Angle innovations are wrapped into (-pi, pi].

#include <Eigen/Core>

namespace nimble {

/// Number of EKF states.
constexpr int kEkfStateDim = 12;
/// Number of EKF inputs (IMU channels).
constexpr int kEkfInputDim = 6;

/// Index of each state in the state vector.
enum EkfStateIndex : int {
  kPhi = 0,
  kTheta = 1,
  kPsi = 2,
  kU = 3,
  kV = 4,
  kW = 5,
  kBiasP = 6,
  kBiasQ = 7,
  kBiasR = 8,
  kBiasAx = 9,
  kBiasAy = 10,
  kBiasAz = 11,
};

using EkfState = Eigen::Matrix<double, kEkfStateDim, 1>;
using EkfCovariance = Eigen::Matrix<double, kEkfStateDim, kEkfStateDim>;
using EkfInput = Eigen::Matrix<double, kEkfInputDim, 1>;
using EkfInputJacobian = Eigen::Matrix<double, kEkfStateDim, kEkfInputDim>;

/// Constants of the process model.
struct EkfModelParams {
  /// Gravitational acceleration [m/s^2].
  double gravity_mps2 = 9.81;
  /// Smallest |cos(theta)| used in the Euler kinematics [-] (see header).
  double min_abs_cos_theta = 1e-3;
};

/// f and its Jacobian at one point (x, u_m), sharing one evaluation of the trigonometry.
/// The bias rows of F are zero, so F = [A B; 0 0] in 6x6 blocks: A = d(attitude, velocity)_dot /
/// d(attitude, velocity), B = the same derivative by the biases (and G = df/du_m = [-B; 0]).
struct EkfLinearisation {
  using Block = Eigen::Matrix<double, 6, 6>;
  EkfState x_dot;
  Block A, B;
};

/// f(x, u_m) and its Jacobian blocks (above). Exactly the values of ekf_process_derivative() and
/// ekf_process_jacobian(), computed once.
EkfLinearisation ekf_linearise(const EkfState& x, const EkfInput& u_m, const EkfModelParams& params);

/// x_dot = f(x, u_m) (header). Units of x_dot: rad/s, m/s^2, and 0 for the biases.
EkfState ekf_process_derivative(const EkfState& x, const EkfInput& u_m, const EkfModelParams& params);

/// Analytic Jacobian F = df/dx at (x, u_m).
EkfCovariance ekf_process_jacobian(const EkfState& x, const EkfInput& u_m, const EkfModelParams& params);

/// Analytic Jacobian G = df/du_m at (x, u_m) (12 x 6).
EkfInputJacobian ekf_input_jacobian(const EkfState& x, const EkfInput& u_m, const EkfModelParams& params);

/// One step of the discrete propagation over dt_s from input u0 (at the start) to u1 (at the end),
/// Heun's method (explicit trapezoidal rule, second order, inputs taken as linear in time):
///   k0 = f(x, u0),  x1 = x + dt k0,  k1 = f(x1, u1),  x+ = x + dt/2 (k0 + k1).
/// Angles are not wrapped here.
EkfState ekf_discrete_step(const EkfState& x, const EkfInput& u0, const EkfInput& u1, double dt_s,
                           const EkfModelParams& params);

/// Exact Jacobian of ekf_discrete_step() with respect to x:
///   Phi = I + dt/2 (F0 + F1 (I + dt F0)),  F0 = F(x, u0),  F1 = F(x1, u1).
/// If `F0_out` / `F1_out` / `x1_out` are given they receive F0, F1 and x1 (reused for the noise).
EkfCovariance ekf_discrete_jacobian(const EkfState& x, const EkfInput& u0, const EkfInput& u1, double dt_s,
                                    const EkfModelParams& params, EkfCovariance* F0_out = nullptr,
                                    EkfCovariance* F1_out = nullptr, EkfState* x1_out = nullptr);

/// Measurement function: the first `dim` states (dim = 3: attitude; dim = 6: attitude and velocity).
Eigen::VectorXd ekf_measurement(const EkfState& x, int dim);

/// Measurement Jacobian H = dh/dx (dim x 12) = [I_dim 0].
Eigen::MatrixXd ekf_measurement_jacobian(const EkfState& x, int dim);

/// Wraps the angle states phi and psi of `x` into (-pi, pi].
void ekf_wrap_angles(EkfState* x);

}  // namespace nimble
