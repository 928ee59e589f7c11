#include "turbulence/linear_system.h"

#include <algorithm>
#include <stdexcept>

namespace nimble::turbulence {
namespace {

void check_size(const char* what, const Eigen::MatrixXd& M, Eigen::Index rows, Eigen::Index cols) {
  if (M.rows() != rows || M.cols() != cols) {
    throw std::invalid_argument(std::string("LinearSystem: ") + what + " is " + std::to_string(M.rows()) + "x" +
                                std::to_string(M.cols()) + ", expected " + std::to_string(rows) + "x" +
                                std::to_string(cols));
  }
}

void check_names(const char* what, const std::vector<std::string>& names, Eigen::Index n) {
  if (!names.empty() && static_cast<Eigen::Index>(names.size()) != n) {
    throw std::invalid_argument(std::string("LinearSystem: ") + std::to_string(names.size()) + " " + what +
                                " names for dimension " + std::to_string(n));
  }
}

}  // namespace

void LinearSystem::validate() const {
  const Eigen::Index n = A.rows();
  const Eigen::Index m = B.cols();
  const Eigen::Index p = C.rows();
  check_size("A", A, n, n);
  check_size("B", B, n, m);
  check_size("C", C, p, n);
  check_size("D", D, p, m);
  check_names("state", states, n);
  check_names("input", inputs, m);
  check_names("output", outputs, p);
}

Eigen::Index index_of(const std::vector<std::string>& names, const std::string& name) {
  const auto it = std::find(names.begin(), names.end(), name);
  if (it == names.end()) {
    std::string list;
    for (const auto& s : names) list += (list.empty() ? "" : ", ") + s;
    throw std::invalid_argument("'" + name + "' is not one of: " + list);
  }
  return static_cast<Eigen::Index>(it - names.begin());
}

Eigen::MatrixXcd frequency_response(const LinearSystem& sys, double omega_radps) {
  Eigen::MatrixXcd M = -sys.A.cast<std::complex<double>>();
  M.diagonal().array() += std::complex<double>(0.0, omega_radps);
  const Eigen::PartialPivLU<Eigen::MatrixXcd> lu(M);
  if (sys.n_states() > 0 && !(lu.rcond() > 1e-14)) {
    throw std::invalid_argument("frequency_response: i*" + std::to_string(omega_radps) + " is an eigenvalue of A");
  }
  return sys.C.cast<std::complex<double>>() * lu.solve(sys.B.cast<std::complex<double>>()) +
         sys.D.cast<std::complex<double>>();
}

LinearSystem close_state_feedback(const LinearSystem& sys, const std::string& input, const Eigen::RowVectorXd& K) {
  sys.validate();
  if (K.size() != sys.n_states()) {
    throw std::invalid_argument("close_state_feedback: K has " + std::to_string(K.size()) + " columns, the system " +
                                std::to_string(sys.n_states()) + " states");
  }
  const Eigen::Index j = index_of(sys.inputs, input);
  LinearSystem out = sys;
  out.A -= sys.B.col(j) * K;
  out.C -= sys.D.col(j) * K;
  return out;
}

std::vector<std::complex<double>> eigenvalues(const Eigen::MatrixXd& A) {
  const Eigen::EigenSolver<Eigen::MatrixXd> es(A, false);
  std::vector<std::complex<double>> out;
  for (Eigen::Index i = 0; i < es.eigenvalues().size(); ++i) out.push_back(es.eigenvalues()[i]);
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) {
    return a.real() != b.real() ? a.real() > b.real() : a.imag() > b.imag();
  });
  return out;
}

}  // namespace nimble::turbulence
