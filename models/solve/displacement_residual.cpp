// Displacement input's residual system (displacement_input.hpp): the model's residuals bordered
// by the driven tendons' rows, their Jacobian, the Newton options, and the answer's outputs,
// stability and infeasibility read through the model's problem at the driven tensions.
#include "solve/displacement_input.hpp"

#include <algorithm>
#include <string>

#include "tdcr/core/error.hpp"

namespace tdcr::detail {

bool DisplacementProblem::apply(const Eigen::Ref<const Eigen::VectorXd>& tau) {
  for (int i = 0; i < k_; ++i) T_[i] = taut_[static_cast<std::size_t>(i)] ? ts_[i] * tau[i] : 0.0;
  if (applied_valid_ && T_ == applied_) return true;
  if (!inner_->set_driven_tensions(index_, T_)) return false;
  applied_ = T_;
  applied_valid_ = true;
  return true;
}

void DisplacementProblem::driven_rows(const Eigen::Ref<const Eigen::VectorXd>& tau,
                                      Eigen::Ref<Eigen::VectorXd> r) const {
  for (int i = 0; i < k_; ++i)
    r[i] = taut_[static_cast<std::size_t>(i)]
               ? (pulls_[index_[i]] + stretch_[i] * ts_[i] * tau[i] - target(i)) / r_[i] + compliance_ * tau[i]
               : tau[i];
}

bool DisplacementProblem::residual(const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> f) {
  if (!apply(y.tail(k_))) return false;
  if (!sys_->residual(y.head(n_), f.head(n_))) return false;
  x_ = y.head(n_);
  if (!inner_->tendon_pulls(x_, pulls_)) return false;
  driven_rows(y.tail(k_), f.tail(k_));
  return f.allFinite();
}

bool DisplacementProblem::final_residual(const Eigen::VectorXd& y, Eigen::Ref<Eigen::VectorXd> f) {
  if (!apply(y.tail(k_))) return false;
  x_ = y.head(n_);
  if (!inner_->final_residual(x_, f.head(n_))) return false;
  if (!inner_->tendon_pulls(x_, pulls_)) return false;
  driven_rows(y.tail(k_), f.tail(k_));
  return f.allFinite();
}

bool DisplacementProblem::border(const Eigen::Ref<const Eigen::VectorXd>& y, const Eigen::Ref<const Eigen::VectorXd>& f,
                                 Eigen::Ref<Eigen::MatrixXd>* Jxx) {
  const double noise = sys_->relative_noise();
  Eigen::VectorXd tau = y.tail(k_);
  x_ = y.head(n_);
  if (!apply(tau) || !inner_->tendon_pulls(x_, pulls_)) return false;
  const Eigen::VectorXd p0 = pulls_;
  // dF/dtau and d rows / dtau: one inner residual and one pull per taut tendon (the pulls move
  // with the tensions at fixed unknowns where the unknowns do not fix the shape: VC's base wrench).
  col_.setZero(n_, k_);
  tt_.setZero(k_, k_);
  fp_.resize(n_);
  for (int j = 0; j < k_; ++j) {
    if (taut_[static_cast<std::size_t>(j)]) {  // a slack tendon's tension is held at zero
      const double h = bvp::finite_difference_step(tau[j], 1.0, noise);
      tau[j] += h;
      if (!apply(tau) || !sys_->residual(x_, fp_) || !inner_->tendon_pulls(x_, dp_)) return false;
      col_.col(j) = (fp_ - f.head(n_)) / h;
      for (int i = 0; i < k_; ++i)
        if (taut_[static_cast<std::size_t>(i)]) tt_(i, j) = (dp_[index_[i]] - p0[index_[i]]) / (h * r_[i]);
      tau[j] = y[n_ + j];
    }
    tt_(j, j) += taut_[static_cast<std::size_t>(j)] ? stretch_[j] * ts_[j] / r_[j] + compliance_ : 1.0;
  }
  if (!apply(tau)) return false;
  // d rows / dx: the pulls with each unknown moved; with Jxx, also the model's residual there
  // (its forward-difference Jacobian from the same evaluations: VC's shots record the tendon
  // lengths, so its pulls come with its residual).
  Eigen::VectorXd uscale(n_);
  sys_->unknown_scale(uscale);
  row_.setZero(k_, n_);
  for (int j = 0; j < n_; ++j) {
    const double h = bvp::finite_difference_step(x_[j], uscale[j], noise);
    const double xj = x_[j];
    x_[j] = xj + h;
    bool ok = true;
    if (Jxx) {
      ok = sys_->residual(x_, fp_);
      if (ok) Jxx->col(j) = (fp_ - f.head(n_)) / h;
    }
    ok = ok && inner_->tendon_pulls(x_, dp_);
    x_[j] = xj;
    if (!ok) return false;
    for (int i = 0; i < k_; ++i)
      if (taut_[static_cast<std::size_t>(i)]) row_(i, j) = (dp_[index_[i]] - p0[index_[i]]) / (h * r_[i]);
  }
  pulls_ = p0;
  return col_.allFinite() && row_.allFinite() && tt_.allFinite();
}

bool DisplacementProblem::jacobian(const Eigen::Ref<const Eigen::VectorXd>& y, const Eigen::Ref<const Eigen::VectorXd>& f,
                                   Eigen::Ref<Eigen::MatrixXd> J) {
  if (!apply(y.tail(k_))) return false;
  x_ = y.head(n_);
  J.setZero();
  Eigen::Ref<Eigen::MatrixXd> Jxx = J.topLeftCorner(n_, n_);
  if (sys_->has_jacobian()) {
    if (!bvp::analytic_jacobian_dense(*sys_, x_, f.head(n_), Jxx) || !border(y, f, nullptr)) return false;
  } else if (!border(y, f, &Jxx)) {  // forward differences with the pulls'
    return false;
  }
  J.topRightCorner(n_, k_) = col_;
  J.bottomLeftCorner(k_, n_) = row_;
  J.bottomRightCorner(k_, k_) = tt_;
  return J.allFinite();
}

bool DisplacementProblem::sparse_jacobian(const Eigen::Ref<const Eigen::VectorXd>& y,
                                          const Eigen::Ref<const Eigen::VectorXd>& f, double* values) {
  if (!apply(y.tail(k_))) return false;
  x_ = y.head(n_);
  const bvp::SparsityPattern& p = *sys_->sparsity();
  const bool ok = sys_->has_jacobian()
                      ? sys_->sparse_jacobian(x_, f.head(n_), inner_values_.data())
                      : bvp::finite_difference_sparse_jacobian(*sys_, x_, f.head(n_), p, inner_values_.data(), &fd_);
  if (!ok || !border(y, f, nullptr)) return false;
  std::fill(values, values + pattern_.nnz(), 0.0);
  for (std::size_t q = 0; q < inner_pos_.size(); ++q) values[inner_pos_[q]] = inner_values_[q];
  for (int j = 0; j < n_; ++j) {
    const int end = pattern_.col_ptr[static_cast<std::size_t>(j) + 1];
    for (int i = 0; i < k_; ++i) values[end - k_ + i] = row_(i, j);
  }
  for (int j = 0; j < k_; ++j) {
    const int start = pattern_.col_ptr[static_cast<std::size_t>(n_ + j)];
    for (int i = 0; i < n_; ++i) values[start + i] = col_(i, j);
    for (int i = 0; i < k_; ++i) values[start + n_ + i] = tt_(i, j);
  }
  return true;
}

void DisplacementProblem::residual_scale(Eigen::Ref<Eigen::VectorXd> s) const {
  sys_->residual_scale(s.head(n_));
  s.tail(k_).setOnes();
}

void DisplacementProblem::unknown_scale(Eigen::Ref<Eigen::VectorXd> s) const {
  sys_->unknown_scale(s.head(n_));
  s.tail(k_).setOnes();
}

double DisplacementProblem::relative_noise() const { return sys_->relative_noise(); }

void DisplacementProblem::set_parameter(double lambda) {
  lambda_ = lambda;
  sys_->set_parameter(start_.size() > 0 ? 1.0 : lambda);
}

void DisplacementProblem::accept_step(Eigen::VectorXd& y) {
  x_ = y.head(n_);
  sys_->accept_step(x_);
  y.head(n_) = x_;
}

bool DisplacementProblem::recenter(Eigen::Ref<Eigen::VectorXd> y) { return sys_->recenter(y.head(n_)); }

void DisplacementProblem::adjust(bvp::NewtonOptions& options) const {
  inner_->adjust(options);
  if (!sparse_ && options.linear_solver == bvp::LinearSolverKind::SparseKLU)
    options.linear_solver = bvp::LinearSolverKind::Dense;
}

void DisplacementProblem::adjust_warm(bvp::NewtonOptions& options, bool same_input) const {
  constexpr int kReuseSetupCalls = 10;
  constexpr int kStaleAfterIterations = 3;
  options.reuse_jacobian = same_input || last_iterations_ <= kStaleAfterIterations;
  options.max_setup_calls = kReuseSetupCalls;
}

void DisplacementProblem::extract(const Eigen::VectorXd& y, bool evaluated, Solution& solution) {
  last_iterations_ = solution.summary.iterations;
  Eigen::VectorXd tau = y.tail(k_);
  for (int i = 0; i < k_; ++i)
    if (!taut_[static_cast<std::size_t>(i)]) tau[i] = 0.0;
  apply(tau);
  x_ = y.head(n_);
  solution.unknowns = x_;
  inner_->extract(x_, evaluated, solution);
  solution.tendon_slack.assign(solution.tensions.size(), false);
  std::string slack;
  for (int i = 0; i < k_; ++i) {
    const auto k = static_cast<std::size_t>(index_[i]);
    if (k >= solution.tensions.size()) continue;
    const bool taut = taut_[static_cast<std::size_t>(i)];
    solution.tensions[k] = taut ? std::max(0.0, ts_[i] * tau[i]) : 0.0;
    solution.tendon_slack[k] = !taut;
    if (!taut) slack += (slack.empty() ? "" : ", ") + std::to_string(k);
  }
  solution.summary.message += "; displacement input: " + std::to_string(k_) + " driven tendons, slack: " +
                              (slack.empty() ? "none" : slack);
}

Stability DisplacementProblem::stability(const Eigen::VectorXd& y, double load_factor) {
  if (!apply(y.tail(k_))) return Stability{};
  return held_tensions(inner_->stability(y.head(n_), load_factor));
}

Stability DisplacementProblem::direct_stability(const Eigen::VectorXd& y, double load_factor) {
  if (!apply(y.tail(k_))) return Stability{};
  return held_tensions(inner_->direct_stability(y.head(n_), load_factor));
}

Stability DisplacementProblem::held_tensions(Stability s) const {
  // The test holds the driven tensions fixed. A tendon held at its length instead only adds a
  // constraint, which cannot make a stable equilibrium unstable, but can stabilise an unstable
  // one: stable stays stable, unstable is not decided.
  if (s.status == StabilityStatus::Unstable) {
    s.status = StabilityStatus::Undetermined;
    s.method += " (unstable at the answer's tensions held fixed; the displacement-driven tendons, held at their "
                "lengths, may stabilise it: not decided)";
  } else if (s.status == StabilityStatus::Stable) {
    s.method += " (at the answer's tensions held fixed; the displacement-driven tendons held at their lengths can "
                "only stiffen it)";
  }
  return s;
}

bool DisplacementProblem::infeasibility(const Eigen::VectorXd& y, double threshold, std::string& why) {
  if (!apply(y.tail(k_))) return false;
  return inner_->infeasibility(y.head(n_), threshold, why);
}

}  // namespace tdcr::detail
