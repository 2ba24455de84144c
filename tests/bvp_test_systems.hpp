// Test problems with known answers shared by the bvp tests (one definition each).
#pragma once

#include <cmath>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "tdcr/bvp/residual_system.hpp"

namespace bvp_test {

using tdcr::bvp::SparsityPattern;

/// The n x n tridiagonal pattern.
inline SparsityPattern tridiagonal(int n) {
  std::vector<std::pair<int, int>> e;
  for (int i = 0; i < n; ++i) {
    e.emplace_back(i, i);
    if (i > 0) e.emplace_back(i, i - 1);
    if (i + 1 < n) e.emplace_back(i, i + 1);
  }
  return SparsityPattern::from_triplets(n, n, e);
}

/// Bratu: u'' + lambda e^u = 0 on (0, 1), u(0) = u(1) = 0; central differences scaled by h^2:
/// F_i = u_{i-1} - 2 u_i + u_{i+1} + h^2 lambda exp(u_i). Tridiagonal Jacobian, analytic on
/// request; counts its residual evaluations.
class Bratu : public tdcr::bvp::ResidualSystem {
 public:
  Bratu(int n, double lambda, bool analytic)
      : lambda(lambda), n_(n), h_(1.0 / (n + 1)), analytic_(analytic), p_(tridiagonal(n)) {}
  int size() const override { return n_; }
  bool residual(const Eigen::Ref<const Eigen::VectorXd>& u, Eigen::Ref<Eigen::VectorXd> f) override {
    ++evaluations;
    for (int i = 0; i < n_; ++i) {
      const double left = i > 0 ? u[i - 1] : 0.0, right = i + 1 < n_ ? u[i + 1] : 0.0;
      f[i] = left - 2.0 * u[i] + right + h_ * h_ * lambda * std::exp(u[i]);
    }
    return true;
  }
  const SparsityPattern* sparsity() const override { return &p_; }
  bool has_jacobian() const override { return analytic_; }
  bool sparse_jacobian(const Eigen::Ref<const Eigen::VectorXd>& u, const Eigen::Ref<const Eigen::VectorXd>&,
                       double* v) override {
    for (int j = 0; j < n_; ++j)
      for (int k = p_.col_ptr[j]; k < p_.col_ptr[j + 1]; ++k)
        v[k] = (p_.row_idx[k] == j) ? -2.0 + h_ * h_ * lambda * std::exp(u[j]) : 1.0;
    return true;
  }
  /// h^2-scaled residuals are O(h^2); scale them back to O(1) so fnormtol means what it says.
  void residual_scale(Eigen::Ref<Eigen::VectorXd> s) const override { s.setConstant(1.0 / (h_ * h_)); }
  double h() const { return h_; }

  double lambda;        ///< The load parameter.
  int evaluations = 0;  ///< Residual evaluations so far.

 private:
  int n_;
  double h_;
  bool analytic_;
  SparsityPattern p_;
};

}  // namespace bvp_test
