#include "estimator/ekf_model.h"

#include <cmath>
#include <cstring>

#include "core/attitude.h"

namespace nimble {
namespace {

/// Trigonometric terms and corrected inputs shared by f, F and G.
struct Terms {
  double sf, cf, st, ct, tt;
  double p, q, r, ax, ay, az;
  double u, v, w;
};

Terms terms(const EkfState& x, const EkfInput& u_m, const EkfModelParams& params) {
  Terms t;
  t.sf = std::sin(x[kPhi]);
  t.cf = std::cos(x[kPhi]);
  t.st = std::sin(x[kTheta]);
  const double c = std::cos(x[kTheta]);
  t.ct = std::fabs(c) >= params.min_abs_cos_theta ? c : std::copysign(params.min_abs_cos_theta, c);
  t.tt = t.st / t.ct;
  t.p = u_m[0] - x[kBiasP];
  t.q = u_m[1] - x[kBiasQ];
  t.r = u_m[2] - x[kBiasR];
  t.ax = u_m[3] - x[kBiasAx];
  t.ay = u_m[4] - x[kBiasAy];
  t.az = u_m[5] - x[kBiasAz];
  t.u = x[kU];
  t.v = x[kV];
  t.w = x[kW];
  return t;
}

}  // namespace

namespace {

EkfState derivative_from(const Terms& t, const EkfModelParams& params) {
  const double g = params.gravity_mps2;
  const double qs_rc = t.q * t.sf + t.r * t.cf;
  EkfState xd = EkfState::Zero();
  xd[kPhi] = t.p + qs_rc * t.tt;
  xd[kTheta] = t.q * t.cf - t.r * t.sf;
  xd[kPsi] = qs_rc / t.ct;
  xd[kU] = t.ax - g * t.st - (t.q * t.w - t.r * t.v);
  xd[kV] = t.ay + g * t.ct * t.sf - (t.r * t.u - t.p * t.w);
  xd[kW] = t.az + g * t.ct * t.cf - (t.p * t.v - t.q * t.u);
  return xd;
}

/// The non-zero rows of F: A = F(0:6, 0:6), B = F(0:6, 6:12). Column indices of B are offset by 6.
void jacobian_from(const Terms& t, const EkfModelParams& params, EkfLinearisation::Block* A_out,
                   EkfLinearisation::Block* B_out) {
  EkfLinearisation::Block& A = *A_out;
  EkfLinearisation::Block& B = *B_out;
  constexpr int b = 6;  // column offset of the biases
  const double g = params.gravity_mps2;
  const double qs_rc = t.q * t.sf + t.r * t.cf;  // q sin(phi) + r cos(phi)
  const double qc_rs = t.q * t.cf - t.r * t.sf;  // d/dphi of the above
  const double ct2 = t.ct * t.ct;
  // Zeroed as bytes: Eigen's setZero() here compiled to a scalar fill loop, a visible share of
  // each propagation step (all-zero bytes are +0.0).
  std::memset(A.data(), 0, sizeof(double) * 36);
  std::memset(B.data(), 0, sizeof(double) * 36);
  // phi_dot
  A(kPhi, kPhi) = qc_rs * t.tt;
  A(kPhi, kTheta) = qs_rc / ct2;
  B(kPhi, kBiasP - b) = -1.0;
  B(kPhi, kBiasQ - b) = -t.sf * t.tt;
  B(kPhi, kBiasR - b) = -t.cf * t.tt;
  // theta_dot
  A(kTheta, kPhi) = -qs_rc;
  B(kTheta, kBiasQ - b) = -t.cf;
  B(kTheta, kBiasR - b) = t.sf;
  // psi_dot
  A(kPsi, kPhi) = qc_rs / t.ct;
  A(kPsi, kTheta) = qs_rc * t.st / ct2;
  B(kPsi, kBiasQ - b) = -t.sf / t.ct;
  B(kPsi, kBiasR - b) = -t.cf / t.ct;
  // u_dot = ax - g st - q w + r v
  A(kU, kTheta) = -g * t.ct;
  A(kU, kV) = t.r;
  A(kU, kW) = -t.q;
  B(kU, kBiasQ - b) = t.w;
  B(kU, kBiasR - b) = -t.v;
  B(kU, kBiasAx - b) = -1.0;
  // v_dot = ay + g ct sf - r u + p w
  A(kV, kPhi) = g * t.ct * t.cf;
  A(kV, kTheta) = -g * t.st * t.sf;
  A(kV, kU) = -t.r;
  A(kV, kW) = t.p;
  B(kV, kBiasP - b) = -t.w;
  B(kV, kBiasR - b) = t.u;
  B(kV, kBiasAy - b) = -1.0;
  // w_dot = az + g ct cf - p v + q u
  A(kW, kPhi) = -g * t.ct * t.sf;
  A(kW, kTheta) = -g * t.st * t.cf;
  A(kW, kU) = t.q;
  A(kW, kV) = -t.p;
  B(kW, kBiasP - b) = t.v;
  B(kW, kBiasQ - b) = -t.u;
  B(kW, kBiasAz - b) = -1.0;
}

}  // namespace

EkfLinearisation ekf_linearise(const EkfState& x, const EkfInput& u_m, const EkfModelParams& params) {
  const Terms t = terms(x, u_m, params);
  EkfLinearisation lin;
  lin.x_dot = derivative_from(t, params);
  jacobian_from(t, params, &lin.A, &lin.B);
  return lin;
}

EkfState ekf_process_derivative(const EkfState& x, const EkfInput& u_m, const EkfModelParams& params) {
  return derivative_from(terms(x, u_m, params), params);
}

EkfCovariance ekf_process_jacobian(const EkfState& x, const EkfInput& u_m, const EkfModelParams& params) {
  EkfLinearisation::Block A, B;
  jacobian_from(terms(x, u_m, params), params, &A, &B);
  EkfCovariance F = EkfCovariance::Zero();
  F.topLeftCorner<6, 6>() = A;
  F.topRightCorner<6, 6>() = B;
  return F;
}

EkfInputJacobian ekf_input_jacobian(const EkfState& x, const EkfInput& u_m, const EkfModelParams& params) {
  // f depends on u_m only through (u_m - b): G = -df/db.
  return -ekf_process_jacobian(x, u_m, params).rightCols<kEkfInputDim>();
}

EkfState ekf_discrete_step(const EkfState& x, const EkfInput& u0, const EkfInput& u1, double dt_s,
                           const EkfModelParams& params) {
  const EkfState k0 = ekf_process_derivative(x, u0, params);
  const EkfState x1 = x + dt_s * k0;
  const EkfState k1 = ekf_process_derivative(x1, u1, params);
  return x + 0.5 * dt_s * (k0 + k1);
}

EkfCovariance ekf_discrete_jacobian(const EkfState& x, const EkfInput& u0, const EkfInput& u1, double dt_s,
                                    const EkfModelParams& params, EkfCovariance* F0_out, EkfCovariance* F1_out,
                                    EkfState* x1_out) {
  const EkfState x1 = x + dt_s * ekf_process_derivative(x, u0, params);
  const EkfCovariance F0 = ekf_process_jacobian(x, u0, params);
  const EkfCovariance F1 = ekf_process_jacobian(x1, u1, params);
  EkfCovariance Phi = EkfCovariance::Identity();
  Phi.noalias() += 0.5 * dt_s * (F0 + F1);
  Phi.noalias() += (0.5 * dt_s * dt_s) * (F1 * F0);
  if (F0_out) *F0_out = F0;
  if (F1_out) *F1_out = F1;
  if (x1_out) *x1_out = x1;
  return Phi;
}

Eigen::VectorXd ekf_measurement(const EkfState& x, int dim) { return x.head(dim); }

Eigen::MatrixXd ekf_measurement_jacobian(const EkfState& /*x*/, int dim) {
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(dim, kEkfStateDim);
  H.leftCols(dim).setIdentity();
  return H;
}

void ekf_wrap_angles(EkfState* x) {
  (*x)[kPhi] = wrap_angle_rad((*x)[kPhi]);
  (*x)[kPsi] = wrap_angle_rad((*x)[kPsi]);
}

}  // namespace nimble
