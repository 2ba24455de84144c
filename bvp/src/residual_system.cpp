/// @file residual_system.cpp
/// @brief Sparsity patterns, column colouring and finite-difference Jacobians.
#include "tdcr/bvp/residual_system.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace tdcr::bvp {

SparsityPattern SparsityPattern::dense(int n) {
  if (n < 0) throw std::invalid_argument("SparsityPattern::dense: negative size");
  SparsityPattern p;
  p.rows = p.cols = n;
  p.col_ptr.resize(static_cast<size_t>(n) + 1);
  p.row_idx.resize(static_cast<size_t>(n) * static_cast<size_t>(n));
  for (int j = 0; j <= n; ++j) p.col_ptr[j] = j * n;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) p.row_idx[static_cast<size_t>(j) * n + i] = i;
  return p;
}

SparsityPattern SparsityPattern::from_triplets(int rows, int cols,
                                               const std::vector<std::pair<int, int>>& entries) {
  if (rows < 0 || cols < 0)
    throw std::invalid_argument("SparsityPattern::from_triplets: negative size");
  // Bucket the entries by column (counting sort, linear in nnz), then sort and deduplicate the
  // rows of each column: CSC order. A global sort of the pairs cost 20 % of a first CCsub solve
  // with 3000 banded unknowns.
  for (const auto& [r, c] : entries)
    if (r < 0 || r >= rows || c < 0 || c >= cols)
      throw std::invalid_argument("SparsityPattern::from_triplets: entry (" + std::to_string(r) +
                                  ", " + std::to_string(c) + ") outside " +
                                  std::to_string(rows) + "x" + std::to_string(cols));
  std::vector<int> start(static_cast<size_t>(cols) + 1, 0);
  for (const auto& e : entries) ++start[e.second + 1];
  for (int j = 0; j < cols; ++j) start[j + 1] += start[j];
  std::vector<int> rows_by_col(entries.size());
  {
    std::vector<int> next(start.begin(), start.end() - 1);
    for (const auto& [r, c] : entries) rows_by_col[next[c]++] = r;
  }
  SparsityPattern p;
  p.rows = rows;
  p.cols = cols;
  p.col_ptr.assign(static_cast<size_t>(cols) + 1, 0);
  p.row_idx.reserve(entries.size());
  for (int j = 0; j < cols; ++j) {
    const auto first = rows_by_col.begin() + start[j], last = rows_by_col.begin() + start[j + 1];
    std::sort(first, last);
    p.row_idx.insert(p.row_idx.end(), first, std::unique(first, last));
    p.col_ptr[j + 1] = static_cast<int>(p.row_idx.size());
  }
  return p;
}

int SparsityPattern::index_of(int row, int col) const {
  if (col < 0 || col >= cols) return -1;
  const auto first = row_idx.begin() + col_ptr[col];
  const auto last = row_idx.begin() + col_ptr[col + 1];
  const auto it = std::lower_bound(first, last, row);
  if (it == last || *it != row) return -1;
  return static_cast<int>(it - row_idx.begin());
}

bool SparsityPattern::valid() const {
  if (rows < 0 || cols < 0) return false;
  if (col_ptr.size() != static_cast<size_t>(cols) + 1 || col_ptr[0] != 0) return false;
  if (static_cast<size_t>(col_ptr.back()) != row_idx.size()) return false;
  for (int j = 0; j < cols; ++j) {
    if (col_ptr[j + 1] < col_ptr[j]) return false;
    for (int k = col_ptr[j]; k < col_ptr[j + 1]; ++k) {
      if (row_idx[k] < 0 || row_idx[k] >= rows) return false;
      if (k > col_ptr[j] && row_idx[k] <= row_idx[k - 1]) return false;
    }
  }
  return true;
}

std::vector<int> column_groups(const SparsityPattern& pattern, int* num_groups) {
  if (!pattern.valid()) throw std::invalid_argument("column_groups: invalid sparsity pattern");
  const int m = pattern.rows, n = pattern.cols;
  // Row-wise view (the transpose) to find, for each column, the columns it shares a row with.
  std::vector<int> row_ptr(static_cast<size_t>(m) + 1, 0), col_of(pattern.row_idx.size());
  for (int r : pattern.row_idx) ++row_ptr[r + 1];
  for (int i = 0; i < m; ++i) row_ptr[i + 1] += row_ptr[i];
  {
    std::vector<int> next(row_ptr.begin(), row_ptr.end() - 1);
    for (int j = 0; j < n; ++j)
      for (int k = pattern.col_ptr[j]; k < pattern.col_ptr[j + 1]; ++k)
        col_of[next[pattern.row_idx[k]]++] = j;
  }
  std::vector<int> group(static_cast<size_t>(n), -1);
  // forbidden[g] == j marks group g as taken by a neighbour of column j (no clearing needed).
  std::vector<int> forbidden;
  int groups = 0;
  for (int j = 0; j < n; ++j) {
    for (int k = pattern.col_ptr[j]; k < pattern.col_ptr[j + 1]; ++k) {
      const int r = pattern.row_idx[k];
      for (int q = row_ptr[r]; q < row_ptr[r + 1]; ++q) {
        const int g = group[col_of[q]];
        if (g >= 0) forbidden[g] = j;
      }
    }
    int g = 0;
    while (g < groups && forbidden[g] == j) ++g;
    if (g == groups) {
      ++groups;
      forbidden.push_back(-1);
    }
    group[j] = g;
  }
  if (num_groups) *num_groups = groups;
  return group;
}

bool valid_column_groups(const SparsityPattern& pattern, const std::vector<int>& groups) {
  if (!pattern.valid() || groups.size() != static_cast<size_t>(pattern.cols)) return false;
  // owner[r * G + g]: would need G per row; instead mark, per row, the groups seen.
  std::vector<std::vector<int>> seen(static_cast<size_t>(pattern.rows));
  for (int j = 0; j < pattern.cols; ++j) {
    if (groups[j] < 0) return false;
    for (int k = pattern.col_ptr[j]; k < pattern.col_ptr[j + 1]; ++k) {
      std::vector<int>& row = seen[pattern.row_idx[k]];
      if (std::find(row.begin(), row.end(), groups[j]) != row.end()) return false;
      row.push_back(groups[j]);
    }
  }
  return true;
}

double ResidualSystem::relative_noise() const { return std::numeric_limits<double>::epsilon(); }

void FiniteDifferenceWorkspace::prepare(int n) {
  if (x_pert.size() != n) {
    x_pert.resize(n);
    f_pert.resize(n);
    uscale.resize(n);
    step.resize(n);
  }
}

void FiniteDifferenceWorkspace::prepare(const SparsityPattern& pattern) {
  prepare(pattern, column_groups(pattern));
}

void FiniteDifferenceWorkspace::prepare(const SparsityPattern& pattern, const std::vector<int>& g) {
  if (g.size() != static_cast<size_t>(pattern.cols))
    throw std::invalid_argument("FiniteDifferenceWorkspace::prepare: one group per column expected");
  prepare(pattern.cols);
  num_groups = g.empty() ? 0 : *std::max_element(g.begin(), g.end()) + 1;
  group_ptr.assign(static_cast<size_t>(num_groups) + 1, 0);
  for (int id : g) ++group_ptr[id + 1];
  for (int k = 0; k < num_groups; ++k) group_ptr[k + 1] += group_ptr[k];
  group_cols.resize(g.size());
  std::vector<int> next(group_ptr.begin(), group_ptr.end() - 1);
  for (int j = 0; j < static_cast<int>(g.size()); ++j) group_cols[next[g[j]]++] = j;
}

namespace {

bool all_finite(const Eigen::Ref<const Eigen::VectorXd>& v) { return v.allFinite(); }

double fd_factor(const ResidualSystem& system) {
  return std::sqrt(std::max(std::numeric_limits<double>::epsilon(), system.relative_noise()));
}

// Increment relative to |x|, but never below the typical size 1/uscale so that a zero unknown
// still gets a meaningful step. The step actually taken is recomputed as (x + h) - x so that
// the representable difference is the one divided by.
double fd_increment(double xj, double uscale_j, double factor) {
  const double typical = (uscale_j > 0.0 && std::isfinite(uscale_j)) ? 1.0 / uscale_j : 1.0;
  const double h = factor * std::max(std::abs(xj), typical);
  return (xj + h) - xj;
}

}  // namespace

double finite_difference_step(double x, double uscale, double relative_noise) {
  return fd_increment(
      x, uscale, std::sqrt(std::max(std::numeric_limits<double>::epsilon(), relative_noise)));
}

bool finite_difference_jacobian(ResidualSystem& system, const Eigen::Ref<const Eigen::VectorXd>& x,
                                const Eigen::Ref<const Eigen::VectorXd>& f,
                                Eigen::Ref<Eigen::MatrixXd> J,
                                FiniteDifferenceWorkspace* workspace) {
  FiniteDifferenceWorkspace local;
  FiniteDifferenceWorkspace& ws = workspace ? *workspace : local;
  const int n = static_cast<int>(x.size());
  ws.prepare(n);
  system.unknown_scale(ws.uscale);
  const double factor = fd_factor(system);
  ws.x_pert = x;
  for (int j = 0; j < n; ++j) {
    const double h = fd_increment(x[j], ws.uscale[j], factor);
    ws.x_pert[j] = x[j] + h;
    ++ws.evaluations;
    const bool ok = system.residual(ws.x_pert, ws.f_pert);
    ws.x_pert[j] = x[j];
    if (!ok || !all_finite(ws.f_pert)) return false;
    J.col(j) = (ws.f_pert - f) / h;
  }
  return true;
}

bool finite_difference_sparse_jacobian(ResidualSystem& system,
                                       const Eigen::Ref<const Eigen::VectorXd>& x,
                                       const Eigen::Ref<const Eigen::VectorXd>& f,
                                       const SparsityPattern& pattern, double* values,
                                       FiniteDifferenceWorkspace* workspace) {
  FiniteDifferenceWorkspace local;
  FiniteDifferenceWorkspace& ws = workspace ? *workspace : local;
  if (!workspace || ws.num_groups == 0 ||
      ws.group_cols.size() != static_cast<size_t>(pattern.cols))
    ws.prepare(pattern);
  system.unknown_scale(ws.uscale);
  const double factor = fd_factor(system);
  ws.x_pert = x;
  for (int g = 0; g < ws.num_groups; ++g) {
    const int first = ws.group_ptr[g], last = ws.group_ptr[g + 1];
    for (int q = first; q < last; ++q) {
      const int j = ws.group_cols[q];
      ws.step[j] = fd_increment(x[j], ws.uscale[j], factor);
      ws.x_pert[j] = x[j] + ws.step[j];
    }
    ++ws.evaluations;
    const bool ok = system.residual(ws.x_pert, ws.f_pert);
    for (int q = first; q < last; ++q) ws.x_pert[ws.group_cols[q]] = x[ws.group_cols[q]];
    if (!ok || !all_finite(ws.f_pert)) return false;
    // Columns of one group share no row, so each changed residual belongs to exactly one column.
    for (int q = first; q < last; ++q) {
      const int j = ws.group_cols[q];
      const double inv_h = 1.0 / ws.step[j];
      for (int k = pattern.col_ptr[j]; k < pattern.col_ptr[j + 1]; ++k) {
        const int i = pattern.row_idx[k];
        values[k] = (ws.f_pert[i] - f[i]) * inv_h;
      }
    }
  }
  return true;
}

bool analytic_jacobian_dense(ResidualSystem& system, const Eigen::Ref<const Eigen::VectorXd>& x,
                             const Eigen::Ref<const Eigen::VectorXd>& f,
                             Eigen::Ref<Eigen::MatrixXd> J) {
  if (!system.has_jacobian()) return false;
  const SparsityPattern* p = system.sparsity();
  if (!p) return system.jacobian(x, f, J);
  std::vector<double> values(static_cast<size_t>(p->nnz()), 0.0);
  if (!system.sparse_jacobian(x, f, values.data())) return false;
  J.setZero();
  for (int j = 0; j < p->cols; ++j)
    for (int k = p->col_ptr[j]; k < p->col_ptr[j + 1]; ++k) J(p->row_idx[k], j) = values[k];
  return true;
}

JacobianCheck check_jacobian(ResidualSystem& system, const Eigen::Ref<const Eigen::VectorXd>& x) {
  JacobianCheck out;
  const int n = system.size();
  Eigen::VectorXd f(n), fp(n), fm(n), xp = x, uscale(n);
  if (!system.residual(x, f) || !f.allFinite()) return out;
  out.analytic.setZero(n, n);
  if (!analytic_jacobian_dense(system, x, f, out.analytic)) return out;
  system.unknown_scale(uscale);
  out.numeric.resize(n, n);
  const double factor =
      std::cbrt(std::max(std::numeric_limits<double>::epsilon(), system.relative_noise()));
  for (int j = 0; j < n; ++j) {
    const double h = fd_increment(x[j], uscale[j], factor);
    xp[j] = x[j] + h;
    const bool okp = system.residual(xp, fp);
    xp[j] = x[j] - h;
    const bool okm = system.residual(xp, fm);
    xp[j] = x[j];
    if (!okp || !okm || !fp.allFinite() || !fm.allFinite()) return out;
    out.numeric.col(j) = (fp - fm) / (2.0 * h);
  }
  const double floor = 1e-8 * std::max(out.analytic.cwiseAbs().maxCoeff(),
                                       out.numeric.cwiseAbs().maxCoeff());
  out.evaluated = true;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const double a = out.analytic(i, j), d = out.numeric(i, j);
      const double denom = std::max({std::abs(a), std::abs(d), floor});
      const double err = denom > 0.0 ? std::abs(a - d) / denom : 0.0;
      if (!(err <= out.max_relative_error)) {  // also catches NaN
        out.max_relative_error = std::isfinite(err) ? err : std::numeric_limits<double>::infinity();
        out.worst_row = i;
        out.worst_col = j;
      }
    }
  return out;
}

}  // namespace tdcr::bvp
