/// @file bordered_system.cpp
/// @brief The bordered system of pseudo-arclength continuation and its augmented Jacobian.
#include "bordered_system.hpp"

#include <algorithm>
#include <cmath>

namespace tdcr::bvp::detail {

BorderedSystem::BorderedSystem(ParameterizedSystem& inner, double lambda_scale, SparseLu& tangent_lu)
    : inner_(inner), n_(inner.size()), inner_pattern_(inner.sparsity()), klu_(tangent_lu) {
  sparse_ = inner_pattern_ != nullptr;
  const int n = n_;
  w_.resize(n + 1);
  inner_.unknown_scale(w_.head(n));
  w_[n] = 1.0 / lambda_scale;
  w_inv_ = w_.cwiseInverse();
  tw_ = Eigen::VectorXd::Zero(n + 1);
  tw_saved_ = tw_;
  y_pred_ = Eigen::VectorXd::Zero(n + 1);
  fs_.resize(n + 1);
  inner_.residual_scale(fs_.head(n));
  fs_[n] = 1.0;
  f_.resize(n + 1);
  f_pert_.resize(n);
  col_.resize(n);
  rhs_ = Eigen::VectorXd::Zero(n + 1);
  rhs_[n] = 1.0;
  if (!sparse_) {
    M_.resize(n + 1, n + 1);
    lu_ = Eigen::PartialPivLU<Eigen::MatrixXd>(n + 1);
    visited_.assign(static_cast<size_t>(n) + 1, 0);
    fd_.prepare(n);
    return;
  }
  // Bordered pattern: every inner column gains the border row n (last, so rows stay sorted);
  // column n (dF/dlambda and the border entry) is full.
  const SparsityPattern& p = *inner_pattern_;
  fd_.prepare(p);
  inner_values_.assign(static_cast<size_t>(p.nnz()), 0.0);
  inner_pos_.resize(static_cast<size_t>(p.nnz()));
  pattern_.rows = pattern_.cols = n + 1;
  pattern_.col_ptr.resize(static_cast<size_t>(n) + 2);
  pattern_.row_idx.clear();
  pattern_.row_idx.reserve(static_cast<size_t>(p.nnz()) + 2 * static_cast<size_t>(n) + 1);
  pattern_.col_ptr[0] = 0;
  for (int j = 0; j < n; ++j) {
    for (int k = p.col_ptr[j]; k < p.col_ptr[j + 1]; ++k) {
      inner_pos_[k] = static_cast<int>(pattern_.row_idx.size());
      pattern_.row_idx.push_back(p.row_idx[k]);
    }
    pattern_.row_idx.push_back(n);
    pattern_.col_ptr[j + 1] = static_cast<int>(pattern_.row_idx.size());
  }
  for (int i = 0; i <= n; ++i) pattern_.row_idx.push_back(i);
  pattern_.col_ptr[n + 1] = static_cast<int>(pattern_.row_idx.size());
  values_.assign(static_cast<size_t>(pattern_.nnz()), 0.0);
}

void BorderedSystem::set_border(const Eigen::VectorXd& t, const Eigen::VectorXd& y_pred) {
  tw_ = t.cwiseProduct(w_);
  y_pred_ = y_pred;
}

void BorderedSystem::residual_scale(Eigen::Ref<Eigen::VectorXd> s) const { s = fs_; }

bool BorderedSystem::residual(const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> g) {
  inner_.set_parameter(y[n_]);
  ++inner_evaluations;
  if (!inner_.residual(y.head(n_), g.head(n_))) return false;
  g[n_] = tw_.dot(y - y_pred_);
  return std::isfinite(g[n_]);
}

bool BorderedSystem::lambda_column(const Eigen::Ref<const Eigen::VectorXd>& y,
                                   const Eigen::Ref<const Eigen::VectorXd>& g) {
  const double lambda = y[n_];
  const double h = finite_difference_step(lambda, w_[n_], inner_.relative_noise());
  inner_.set_parameter(lambda + h);
  ++inner_evaluations;
  const bool ok = inner_.residual(y.head(n_), f_pert_) && f_pert_.allFinite();
  inner_.set_parameter(lambda);
  if (ok) col_ = (f_pert_ - g.head(n_)) / h;
  return ok;
}

bool BorderedSystem::inner_block(const Eigen::Ref<const Eigen::VectorXd>& y,
                                 const Eigen::Ref<const Eigen::VectorXd>& g) {
  // Only the sparse case lands here; the dense inner block is written straight into J.
  const int before = fd_.evaluations;
  const bool ok = inner_.has_jacobian()
                      ? inner_.sparse_jacobian(y.head(n_), g.head(n_), inner_values_.data())
                      : finite_difference_sparse_jacobian(inner_, y.head(n_), g.head(n_), *inner_pattern_,
                                                          inner_values_.data(), &fd_);
  inner_evaluations += fd_.evaluations - before;
  return ok;
}

bool BorderedSystem::jacobian(const Eigen::Ref<const Eigen::VectorXd>& y,
                              const Eigen::Ref<const Eigen::VectorXd>& g, Eigen::Ref<Eigen::MatrixXd> J) {
  ++jacobian_evaluations;
  inner_.set_parameter(y[n_]);
  const int before = fd_.evaluations;
  const bool ok = inner_.has_jacobian()
                      ? inner_.jacobian(y.head(n_), g.head(n_), J.topLeftCorner(n_, n_))
                      : finite_difference_jacobian(inner_, y.head(n_), g.head(n_), J.topLeftCorner(n_, n_), &fd_);
  inner_evaluations += fd_.evaluations - before;
  if (!ok || !lambda_column(y, g)) return false;
  J.col(n_).head(n_) = col_;
  J.row(n_) = tw_.transpose();
  return true;
}

bool BorderedSystem::sparse_jacobian(const Eigen::Ref<const Eigen::VectorXd>& y,
                                     const Eigen::Ref<const Eigen::VectorXd>& g, double* values) {
  ++jacobian_evaluations;
  inner_.set_parameter(y[n_]);
  if (!inner_block(y, g) || !lambda_column(y, g)) return false;
  for (size_t k = 0; k < inner_values_.size(); ++k) values[inner_pos_[k]] = inner_values_[k];
  for (int j = 0; j < n_; ++j) values[pattern_.col_ptr[j + 1] - 1] = tw_[j];
  const int last = pattern_.col_ptr[n_];
  for (int i = 0; i < n_; ++i) values[last + i] = col_[i];
  values[last + n_] = tw_[n_];
  return true;
}

bool BorderedSystem::tangent(const Eigen::VectorXd& y, const Eigen::VectorXd& border, Eigen::VectorXd& t,
                             int& det_sign, double& det_log) {
  inner_.set_parameter(y[n_]);
  ++inner_evaluations;
  if (!inner_.residual(y.head(n_), f_.head(n_)) || !f_.head(n_).allFinite()) return false;
  f_[n_] = 0.0;
  // The Jacobian's border row is tw_ = t W; use the requested border for this factorisation.
  tw_saved_ = tw_;
  tw_ = border.cwiseProduct(w_);
  const bool ok = sparse_ ? sparse_jacobian(y, f_, values_.data()) : jacobian(y, f_, M_);
  tw_ = tw_saved_;
  if (!ok || !(sparse_ ? sparse_tangent(t, det_sign, det_log) : dense_tangent(t, det_sign, det_log))) return false;
  const double norm = t.norm();
  if (!(norm > 0.0) || !std::isfinite(norm)) return false;
  t /= norm;
  return true;
}

// Scaled columns (dF/dz = dF/dy W^-1; the border row becomes `border`), scaled rows.
bool BorderedSystem::dense_tangent(Eigen::VectorXd& t, int& det_sign, double& det_log) {
  const Eigen::Index n1 = n_ + 1;
  M_.array().colwise() *= fs_.array();
  M_.array().rowwise() *= w_inv_.transpose().array();
  lu_.compute(M_);
  // Parity of the row permutation: a cycle of length L is L - 1 transpositions
  // (permutationP().determinant() would allocate its own mask).
  det_sign = 1;
  const auto& perm = lu_.permutationP().indices();
  std::fill(visited_.begin(), visited_.end(), 0);
  for (Eigen::Index i = 0; i < n1; ++i) {
    if (visited_[i]) continue;
    for (Eigen::Index k = perm[i]; k != i; k = perm[k]) {
      visited_[k] = 1;
      det_sign = -det_sign;
    }
    visited_[i] = 1;
  }
  det_log = 0.0;
  const auto d = lu_.matrixLU().diagonal();
  for (Eigen::Index i = 0; i < n1; ++i) {
    if (d[i] < 0.0) det_sign = -det_sign;
    if (d[i] == 0.0) det_sign = 0;
    det_log += std::log(std::abs(d[i]));
  }
  t = lu_.solve(rhs_);
  return true;
}

// The same scaling on the bordered pattern, then KLU (analysis and pivot order reused).
bool BorderedSystem::sparse_tangent(Eigen::VectorXd& t, int& det_sign, double& det_log) {
  const int n1 = n_ + 1;
  for (int j = 0; j < n1; ++j)
    for (int k = pattern_.col_ptr[j]; k < pattern_.col_ptr[j + 1]; ++k)
      values_[k] *= fs_[pattern_.row_idx[k]] * w_inv_[j];
  if (klu_.factorize(pattern_, values_.data()) != SparseLu::Status::Success) return false;
  if (!klu_.determinant(det_sign, det_log)) return false;
  t = rhs_;
  return klu_.solve(t.data());
}

}  // namespace tdcr::bvp::detail
