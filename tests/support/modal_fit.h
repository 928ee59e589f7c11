#pragma once
/// Modes of a recorded free response by the matrix pencil method (Hua & Sarkar, IEEE Trans.
/// Acoust. Speech Signal Process. 38(5), 1990): y[k] = sum_i c_i z_i^k is fitted with M modes
/// from the SVD of the Hankel matrix of the record; s_i = ln(z_i) / dt. Robust to measurement
/// noise, and it needs no initial guess. Header-only, on Eigen.

#include <complex>
#include <stdexcept>
#include <vector>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

namespace nimble::test {

/// The M modes of `y` (sampled every dt_s) as continuous poles s [1/s].
/// @throws std::invalid_argument if the record is shorter than 3 (M + 1) samples.
inline std::vector<std::complex<double>> matrix_pencil_modes(const std::vector<double>& y, double dt_s, int modes) {
  const int n = static_cast<int>(y.size());
  const int pencil = n / 3;  // the pencil parameter L: N/3 to N/2 is least sensitive to noise
  if (modes < 1 || pencil < modes + 1) throw std::invalid_argument("matrix pencil: record too short for the modes");
  Eigen::MatrixXd hankel(n - pencil, pencil + 1);
  for (int i = 0; i < n - pencil; ++i) {
    for (int j = 0; j <= pencil; ++j) hankel(i, j) = y[static_cast<std::size_t>(i + j)];
  }
  const Eigen::BDCSVD<Eigen::MatrixXd> svd(hankel, Eigen::ComputeThinV);
  const Eigen::MatrixXd v = svd.matrixV().leftCols(modes);
  const Eigen::MatrixXd shift =
      v.topRows(pencil).completeOrthogonalDecomposition().pseudoInverse() * v.bottomRows(pencil);
  const Eigen::VectorXcd z = shift.eigenvalues();
  std::vector<std::complex<double>> s;
  for (Eigen::Index i = 0; i < z.size(); ++i) s.push_back(std::log(z(i)) / dt_s);
  return s;
}

}  // namespace nimble::test
