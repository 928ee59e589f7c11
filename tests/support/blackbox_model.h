#pragma once
/// Test support: a grey-box model written as a black box (thesis Eq 8.5 / 8.6), every entry of its
/// A and B a parameter. Header-only; the test links nimble_core.

#include <cstddef>

#include "core/model.h"

namespace nimble::test {

/// The black-box model with the entries of `ss` (A and B of `base`), trim and inputs of `base`.
inline DerivativeModel blackbox_of(const DerivativeModel& base, const StateSpace& ss) {
  DerivativeModel m = base;
  m.name = base.name + "_blackbox";
  m.structure = ss.states.size() == 4 ? Structure::kBlackbox4 : Structure::kBlackbox3;
  m.derivatives.clear();
  m.published_sigma.clear();
  m.published_eigenvalues.clear();
  const auto a_names = stability_derivative_names(m.structure);
  for (Eigen::Index i = 0; i < ss.A.rows(); ++i) {
    for (Eigen::Index k = 0; k < ss.A.cols(); ++k) m.derivatives[a_names[i * ss.A.cols() + k]] = ss.A(i, k);
  }
  for (std::size_t j = 0; j < base.inputs.size(); ++j) {
    const auto b_names = control_derivative_names(m.structure, base.inputs[j]);
    for (Eigen::Index i = 0; i < ss.B.rows(); ++i) m.derivatives[b_names[i]] = ss.B(i, static_cast<Eigen::Index>(j));
  }
  return m;
}

}  // namespace nimble::test
