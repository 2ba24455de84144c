/// @file shooting.cpp
/// @brief Multiple shooting residuals and their structured finite-difference Jacobian.
#include "tdcr/bvp/shooting.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace tdcr::bvp {

void ShootingProblem::junction(int i, const ShootingNodes& nodes, double* r) const {
  const int m = nodes.state_dimension();
  const double* left = nodes.end(i - 1);
  const double* right = nodes.start(i);
  for (int q = 0; q < m; ++q) r[q] = right[q] - left[q];
}

void ShootingProblem::state_scale(double* s) const {
  std::fill(s, s + state_dimension(), 1.0);
}

namespace {

// Residual blocks that read interval k: junctions i with i-1-c <= k <= i+c, i.e.
// i in [k-c, k+1+c] within [1, N-1], and the boundary block 0 if k <= c or k >= N-1-c.
bool boundary_reads(int k, int n, int c) { return k <= c || k >= n - 1 - c; }
int first_junction(int k, int c) { return std::max(1, k - c); }
int last_junction(int k, int n, int c) { return std::min(n - 1, k + 1 + c); }

}  // namespace

ShootingSystem::ShootingSystem(const ShootingProblem& problem, Integrator& integrator)
    : problem_(problem),
      integrator_(integrator),
      m_(problem.state_dimension()),
      n_(problem.intervals()),
      c_(problem.coupling()) {
  if (m_ < 1) throw std::invalid_argument("ShootingSystem: state dimension must be >= 1");
  if (n_ < 1) throw std::invalid_argument("ShootingSystem: need at least one interval");
  if (c_ < 0) throw std::invalid_argument("ShootingSystem: coupling must be >= 0");
  for (int k = 0; k < n_; ++k) {
    if (problem.ode(k).dimension() != m_)
      throw std::invalid_argument("ShootingSystem: ODE of interval " + std::to_string(k) +
                                  " has dimension " + std::to_string(problem.ode(k).dimension()) +
                                  ", expected " + std::to_string(m_));
    const double a = problem.node(k), b = problem.node(k + 1);
    if (!std::isfinite(a) || !std::isfinite(b) || a == b ||
        (k > 0 && (b - a) * (problem.node(1) - problem.node(0)) < 0.0))
      throw std::invalid_argument("ShootingSystem: nodes must be finite and strictly monotone");
  }
  // Jacobian structure: column (k, j) has the m rows of every residual block reading k.
  std::vector<std::pair<int, int>> entries;
  for (int k = 0; k < n_; ++k)
    for (int j = 0; j < m_; ++j) {
      const int col = k * m_ + j;
      auto add_block = [&](int b) {
        for (int q = 0; q < m_; ++q) entries.emplace_back(b * m_ + q, col);
      };
      if (boundary_reads(k, n_, c_)) add_block(0);
      for (int b = first_junction(k, c_); b <= last_junction(k, n_, c_); ++b) add_block(b);
    }
  pattern_ = SparsityPattern::from_triplets(n_ * m_, n_ * m_, entries);
  const size_t total = static_cast<size_t>(n_) * m_;
  starts_.assign(total, std::nan(""));
  ends_.assign(total, 0.0);
  pstarts_.assign(total, 0.0);
  pends_.assign(total, 0.0);
  rblock_.assign(m_, 0.0);
  scale_.assign(m_, 1.0);
  rscale_.assign(m_, 1.0);
  problem_.state_scale(scale_.data());
}

void ShootingSystem::eval_block(int block, const ShootingNodes& nodes, double* r) const {
  if (block == 0)
    problem_.boundary(nodes, r);
  else
    problem_.junction(block, nodes, r);
}

bool ShootingSystem::integrate_all(const Eigen::Ref<const Eigen::VectorXd>& x) {
  std::copy(x.data(), x.data() + x.size(), starts_.begin());
  for (int k = 0; k < n_; ++k) {
    double* y = ends_.data() + static_cast<size_t>(k) * m_;
    std::copy(starts_.begin() + static_cast<long>(k) * m_,
              starts_.begin() + static_cast<long>(k + 1) * m_, y);
    ++integrations_;
    if (!integrator_.integrate(problem_.ode(k), problem_.node(k), problem_.node(k + 1), y)) {
      starts_[0] = std::nan("");  // invalidate the cached trajectory
      return false;
    }
  }
  return true;
}

bool ShootingSystem::evaluate(const Eigen::Ref<const Eigen::VectorXd>& x) {
  if (x.size() != size()) throw std::invalid_argument("ShootingSystem::evaluate: wrong size");
  return integrate_all(x);
}

bool ShootingSystem::residual(const Eigen::Ref<const Eigen::VectorXd>& x,
                              Eigen::Ref<Eigen::VectorXd> f) {
  if (!integrate_all(x)) return false;
  const ShootingNodes nodes = this->nodes();
  for (int b = 0; b < n_; ++b) eval_block(b, nodes, f.data() + static_cast<long>(b) * m_);
  return true;
}

bool ShootingSystem::sparse_jacobian(const Eigen::Ref<const Eigen::VectorXd>& x,
                                     const Eigen::Ref<const Eigen::VectorXd>& f,
                                     double* values) {
  // The trajectory of x is normally cached from KINSOL's last residual call at x.
  if (!std::equal(starts_.begin(), starts_.end(), x.data()) && !integrate_all(x)) return false;
  std::copy(starts_.begin(), starts_.end(), pstarts_.begin());
  std::copy(ends_.begin(), ends_.end(), pends_.begin());
  const ShootingNodes perturbed(pstarts_.data(), pends_.data(), m_, n_);
  const double noise = integrator_.relative_noise();
  for (int k = 0; k < n_; ++k) {
    const size_t off = static_cast<size_t>(k) * m_;
    for (int j = 0; j < m_; ++j) {
      const int col = k * m_ + j;
      const double h = finite_difference_step(starts_[off + j], scale_[j], noise);
      pstarts_[off + j] = starts_[off + j] + h;
      std::copy(pstarts_.begin() + off, pstarts_.begin() + off + m_, pends_.begin() + off);
      ++integrations_;
      const bool ok = integrator_.integrate(problem_.ode(k), problem_.node(k),
                                            problem_.node(k + 1), pends_.data() + off);
      if (ok) {
        // Rows of this column come in whole blocks of m, sorted by block.
        const double inv_h = 1.0 / h;
        for (int idx = pattern_.col_ptr[col]; idx < pattern_.col_ptr[col + 1]; idx += m_) {
          const int b = pattern_.row_idx[idx] / m_;
          eval_block(b, perturbed, rblock_.data());
          for (int q = 0; q < m_; ++q) {
            const double d = (rblock_[q] - f[b * m_ + q]) * inv_h;
            if (!std::isfinite(d)) return false;
            values[idx + q] = d;
          }
        }
      }
      pstarts_[off + j] = starts_[off + j];
      std::copy(ends_.begin() + off, ends_.begin() + off + m_, pends_.begin() + off);
      if (!ok) return false;
    }
  }
  return true;
}

void ShootingSystem::residual_scale(Eigen::Ref<Eigen::VectorXd> s) const {
  problem_.residual_scale(rscale_.data());
  const Eigen::Map<const Eigen::VectorXd> block(rscale_.data(), m_);
  for (int b = 0; b < n_; ++b) s.segment(b * m_, m_) = block;
}

void ShootingSystem::unknown_scale(Eigen::Ref<Eigen::VectorXd> s) const {
  // Refreshed here (once per solve) so that a problem may change its scales between solves.
  problem_.state_scale(scale_.data());
  const Eigen::Map<const Eigen::VectorXd> block(scale_.data(), m_);
  for (int k = 0; k < n_; ++k) s.segment(k * m_, m_) = block;
}

double ShootingSystem::relative_noise() const { return integrator_.relative_noise(); }

}  // namespace tdcr::bvp
