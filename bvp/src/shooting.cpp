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

void ShootingProblem::start_state(int k, const double* x, double* y) const {
  std::copy(x, x + unknown_dimension(k), y);
}

std::pair<int, int> ShootingProblem::dependent_rows(int block, int k, int j) const {
  (void)k;
  (void)j;
  return {0, unknown_dimension(block)};
}

double ShootingProblem::increment(int k, int j, double value, double scale, double noise) const {
  (void)k;
  (void)j;
  return finite_difference_step(value, scale, noise);
}

namespace {

// Residual blocks that read interval k: junctions i with i-1-c <= k <= i+c, i.e.
// i in [k-c, k+1+c] within [1, N-1], and the boundary block 0 if k <= c or k >= N-1-c.
bool boundary_reads(int k, int n, int c) { return k <= c || k >= n - 1 - c; }
int first_junction(int k, int c) { return std::max(1, k - c); }
int last_junction(int k, int n, int c) { return std::min(n - 1, k + 1 + c); }

}  // namespace

std::shared_ptr<const ShootingStructure> ShootingStructure::of(const ShootingProblem& problem) {
  const int m = problem.state_dimension(), n = problem.intervals(), c = problem.coupling();
  if (m < 1) throw std::invalid_argument("ShootingSystem: state dimension must be >= 1");
  if (n < 1) throw std::invalid_argument("ShootingSystem: need at least one interval");
  if (c < 0) throw std::invalid_argument("ShootingSystem: coupling must be >= 0");
  auto s = std::make_shared<ShootingStructure>();
  s->offset.assign(n + 1, 0);
  for (int k = 0; k < n; ++k) {
    const int d = problem.unknown_dimension(k);
    if (d < 0 || d > m)
      throw std::invalid_argument("ShootingSystem: node " + std::to_string(k) + " has " + std::to_string(d) +
                                  " unknowns, expected 0.." + std::to_string(m));
    s->offset[k + 1] = s->offset[k] + d;
  }
  const std::vector<int>& off = s->offset;
  const int size = off[n];
  s->row_block.resize(size);
  for (int b = 0; b < n; ++b) std::fill(s->row_block.begin() + off[b], s->row_block.begin() + off[b + 1], b);
  // Column (k, j) holds the rows of every block reading node k that depend on unknown j, in
  // CSC order directly (blocks visited in ascending order, rows ascending within a block).
  SparsityPattern& p = s->pattern;
  p.rows = p.cols = size;
  p.col_ptr.assign(1, 0);
  p.col_ptr.reserve(size + 1);
  auto add_rows = [&](int b, int k, int j) {
    const std::pair<int, int> r = problem.dependent_rows(b, k, j);
    const int rows = off[b + 1] - off[b];
    for (int q = std::max(0, r.first); q < std::min(rows, r.second); ++q) p.row_idx.push_back(off[b] + q);
  };
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < off[k + 1] - off[k]; ++j) {
      if (boundary_reads(k, n, c)) add_rows(0, k, j);
      for (int b = first_junction(k, c); b <= last_junction(k, n, c); ++b) add_rows(b, k, j);
      p.col_ptr.push_back(static_cast<int>(p.row_idx.size()));
    }
  return s;
}

ShootingSystem::ShootingSystem(ShootingProblem& problem, Integrator& integrator,
                               std::shared_ptr<const ShootingStructure> structure)
    : problem_(problem),
      mutable_problem_(&problem),
      integrator_(&integrator),
      m_(problem.state_dimension()),
      n_(problem.intervals()),
      structure_(structure ? std::move(structure) : ShootingStructure::of(problem)) {
  check_problem();
}

ShootingSystem::ShootingSystem(const ShootingProblem& problem, Integrator& integrator)
    : problem_(problem),
      integrator_(&integrator),
      m_(problem.state_dimension()),
      n_(problem.intervals()),
      structure_(ShootingStructure::of(problem)) {
  check_problem();
}

void ShootingSystem::check_problem() {
  offset_ = structure_->offset.data();
  if (static_cast<int>(structure_->offset.size()) != n_ + 1)
    throw std::invalid_argument("ShootingSystem: the structure is of another problem");
  for (int k = 0; k < n_; ++k) {
    if (problem_.ode(k).dimension() != m_)
      throw std::invalid_argument("ShootingSystem: ODE of interval " + std::to_string(k) +
                                  " has dimension " + std::to_string(problem_.ode(k).dimension()) +
                                  ", expected " + std::to_string(m_));
    const double a = problem_.node(k), b = problem_.node(k + 1);
    if (!std::isfinite(a) || !std::isfinite(b) || a == b ||
        (k > 0 && (b - a) * (problem_.node(1) - problem_.node(0)) < 0.0))
      throw std::invalid_argument("ShootingSystem: nodes must be finite and strictly monotone");
    if (offset_[k + 1] - offset_[k] != problem_.unknown_dimension(k))
      throw std::invalid_argument("ShootingSystem: the structure is of another problem");
  }
  size_ = offset_[n_];
  const size_t total = static_cast<size_t>(n_) * m_;
  x_.assign(size_, 0.0);
  starts_.assign(total, 0.0);
  ends_.assign(total, 0.0);
  pstarts_.assign(total, 0.0);
  pends_.assign(total, 0.0);
  xnode_.assign(m_, 0.0);
  dy_.assign(m_, 0.0);
  rblock_.assign(m_, 0.0);
  sbuf_.assign(m_, 1.0);
  scale_.assign(size_, 1.0);
  refresh_scale();
}

void ShootingSystem::set_structure(std::shared_ptr<const ShootingStructure> structure) {
  if (!structure || structure->offset != structure_->offset)
    throw std::invalid_argument("ShootingSystem::set_structure: the structure has another layout");
  structure_ = std::move(structure);
  offset_ = structure_->offset.data();
}

// Through an m-sized buffer: a problem need not override the scales of nodes with d_k = m.
void ShootingSystem::refresh_scale() const {
  for (int k = 0; k < n_; ++k) {
    problem_.unknown_scale(k, sbuf_.data());
    std::copy(sbuf_.begin(), sbuf_.begin() + (offset_[k + 1] - offset_[k]), scale_.begin() + offset_[k]);
  }
}

void ShootingSystem::eval_block(int block, const ShootingNodes& nodes, double* r) const {
  if (block == 0)
    problem_.boundary(nodes, r);
  else
    problem_.junction(block, nodes, r);
}

bool ShootingSystem::integrate_all(const Eigen::Ref<const Eigen::VectorXd>& x) {
  cached_ = false;
  std::copy(x.data(), x.data() + size_, x_.begin());
  for (int k = 0; k < n_; ++k) {
    double* y0 = starts_.data() + static_cast<size_t>(k) * m_;
    double* y = ends_.data() + static_cast<size_t>(k) * m_;
    problem_.start_state(k, x.data() + offset_[k], y0);
    std::copy(y0, y0 + m_, y);
    ++integrations_;
    if (!integrator_->integrate(problem_.ode(k), problem_.node(k), problem_.node(k + 1), y)) return false;
  }
  cached_ = true;
  return true;
}

bool ShootingSystem::evaluate(const Eigen::Ref<const Eigen::VectorXd>& x) {
  if (x.size() != size()) throw std::invalid_argument("ShootingSystem::evaluate: wrong size");
  // The trajectory of x may be cached from the last residual() at x (a final check, then a
  // stability test: VCref's), as sparse_jacobian() relies on too.
  if (cached_ && std::equal(x_.begin(), x_.end(), x.data())) return true;
  return integrate_all(x);
}

void ShootingSystem::rebase(Eigen::Ref<Eigen::VectorXd> x) {
  if (!mutable_problem_) throw std::logic_error("ShootingSystem::rebase: built from a const problem");
  if (x.size() != size()) throw std::invalid_argument("ShootingSystem::rebase: wrong size");
  for (int k = 0; k < n_; ++k) mutable_problem_->rebase(k, x.data() + offset_[k]);
  cached_ = false;
}

bool ShootingSystem::residual(const Eigen::Ref<const Eigen::VectorXd>& x,
                              Eigen::Ref<Eigen::VectorXd> f) {
  if (!integrate_all(x)) return false;
  const ShootingNodes nodes = this->nodes();
  for (int b = 0; b < n_; ++b) eval_block(b, nodes, f.data() + offset_[b]);
  return true;
}

bool ShootingSystem::sparse_jacobian(const Eigen::Ref<const Eigen::VectorXd>& x,
                                     const Eigen::Ref<const Eigen::VectorXd>& f,
                                     double* values) {
  // The trajectory of x is normally cached from KINSOL's last residual call at x.
  if (!(cached_ && std::equal(x_.begin(), x_.end(), x.data())) && !integrate_all(x)) return false;
  std::copy(starts_.begin(), starts_.end(), pstarts_.begin());
  std::copy(ends_.begin(), ends_.end(), pends_.begin());
  const ShootingNodes perturbed(pstarts_.data(), pends_.data(), m_, n_);
  const SparsityPattern& pattern = structure_->pattern;
  const int* row_block = structure_->row_block.data();
  const double noise = integrator_->relative_noise();
  // The problem may linearise terms about the trajectory of x (starts_, ends_, unchanged below)
  // until the loop ends, however it ends.
  struct Linearization {
    const ShootingProblem& problem;
    ~Linearization() { problem.end_linearization(); }
  } linearization{problem_};
  problem_.begin_linearization(nodes());
  for (int k = 0; k < n_; ++k) {
    const size_t off = static_cast<size_t>(k) * m_;
    const double* y0 = starts_.data() + off;
    const double* e0 = ends_.data() + off;
    double* py = pstarts_.data() + off;
    double* pe = pends_.data() + off;
    const int d = offset_[k + 1] - offset_[k];
    const bool linear = problem_.linearize_shot(k, *integrator_, y0, e0);
    std::copy(x.data() + offset_[k], x.data() + offset_[k + 1], xnode_.begin());
    for (int j = 0; j < d; ++j) {
      const int col = offset_[k] + j;
      int idx = pattern.col_ptr[col];
      const int end = pattern.col_ptr[col + 1];
      if (idx == end) continue;
      // The step actually taken, x + h - x: for a position near L perturbed by h ~ L / N * 1e-7
      // the rounding of x + h is a relative error of ~ N * 1e-9 in the column, and a different
      // one in every binade of x.
      xnode_[j] = x[col] + problem_.increment(k, j, xnode_[j], scale_[col], noise);
      const double h = xnode_[j] - x[col];
      problem_.start_state(k, xnode_.data(), py);
      bool ok = true;
      if (problem_.shifts_end(k, j)) {
        for (int q = 0; q < m_; ++q) pe[q] = e0[q] + (py[q] - y0[q]);
      } else if (linear) {
        for (int q = 0; q < m_; ++q) dy_[q] = py[q] - y0[q];
        problem_.shot_tangent(k, dy_.data(), pe);
        for (int q = 0; q < m_; ++q) pe[q] += e0[q];
      } else {
        for (int q = 0; q < m_; ++q) pe[q] = py[q];
        ++integrations_;
        ok = integrator_->integrate(problem_.ode(k), problem_.node(k), problem_.node(k + 1), pe);
      }
      if (ok) {
        // Rows of this column ascend, block by block: evaluate each block once.
        const double inv_h = 1.0 / h;
        double sum = 0.0;
        while (idx < end) {
          const int b = row_block[pattern.row_idx[idx]];
          eval_block(b, perturbed, rblock_.data());
          const double* r = rblock_.data() - offset_[b];
          for (const int last = offset_[b + 1]; idx < end && pattern.row_idx[idx] < last; ++idx) {
            const int row = pattern.row_idx[idx];
            values[idx] = (r[row] - f[row]) * inv_h;
            sum += values[idx];
          }
        }
        ok = std::isfinite(sum);  // false if any entry is not finite
      }
      xnode_[j] = x[col];
      for (int q = 0; q < m_; ++q) {
        py[q] = y0[q];
        pe[q] = e0[q];
      }
      if (!ok) return false;
    }
  }
  return true;
}

void ShootingSystem::residual_scale(Eigen::Ref<Eigen::VectorXd> s) const {
  for (int b = 0; b < n_; ++b) {
    problem_.block_scale(b, sbuf_.data());
    std::copy(sbuf_.begin(), sbuf_.begin() + (offset_[b + 1] - offset_[b]), s.data() + offset_[b]);
  }
}

void ShootingSystem::unknown_scale(Eigen::Ref<Eigen::VectorXd> s) const {
  // Refreshed here (once per solve) so that a problem may change its scales between solves.
  refresh_scale();
  std::copy(scale_.begin(), scale_.end(), s.data());
}

double ShootingSystem::relative_noise() const { return integrator_->relative_noise(); }

}  // namespace tdcr::bvp
