// The structured Newton step of the lumped models (LumpedProblem::setup_newton_step and
// solve_newton_step): the recursive form's Jacobian, as structured_jacobian() computes it, is
//
//   J = blockdiag(G_j) + (block upper part of E W) + (block lower part of D Om)
//
// with E_j (m x 6) the residuals' response to a change of the distal wrench, W_k (6 x m) the
// wrench change a column of subsegment k causes, D_j (m x 3) the response to a rotation of
// everything distal and Om_k (3 x m) the rotation a column causes. Block j of J d is
//
//   G_j d_j + E_j s_j + D_j t_j,   s_j = sum_{k>j} W_k d_k,   t_j = sum_{k<j} Om_k d_k,
//
// and the partial sums obey s_j = s_{j+1} + W_{j+1} d_{j+1}, t_j = t_{j-1} + Om_{j-1} d_{j-1}.
// With (d_j, s_j, t_j) as unknowns the system J d = b is block-banded: (m + 9) J unknowns
// ((m + 6) J without external loads, where D = 0), factored by KLU in O(J). The iterates are
// those of the recursive form with its dense Jacobian (up to rounding), at a cost linear in the
// number of subsegments.
#include <utility>
#include <vector>

#include "lumped/lumped_problem.hpp"

namespace tdcr::detail {

void LumpedProblem::build_structured_pattern() {
  const int m = body_.per_subsegment, J = active();
  const bool ext = jac_external_;
  const int K = m + 6 + (ext ? 3 : 0);
  std::vector<std::pair<int, int>> e;  // (row, column) in the order setup_newton_step fills
  for (int j = 0; j < J; ++j) {
    const int d = K * j, s = d + m, t = d + m + 6;
    for (int c = 0; c < m; ++c)
      for (int r = 0; r < m; ++r) e.emplace_back(d + r, d + c);
    for (int c = 0; c < 6; ++c)
      for (int r = 0; r < m; ++r) e.emplace_back(d + r, s + c);
    if (ext)
      for (int c = 0; c < 3; ++c)
        for (int r = 0; r < m; ++r) e.emplace_back(d + r, t + c);
    for (int q = 0; q < 6; ++q) e.emplace_back(s + q, s + q);
    if (j + 1 < J) {
      for (int q = 0; q < 6; ++q) e.emplace_back(s + q, s + K + q);
      for (int c = 0; c < m; ++c)
        for (int q = 0; q < 6; ++q) e.emplace_back(s + q, d + K + c);
    }
    if (ext) {
      for (int q = 0; q < 3; ++q) e.emplace_back(t + q, t + q);
      if (j > 0) {
        for (int q = 0; q < 3; ++q) e.emplace_back(t + q, t - K + q);
        for (int c = 0; c < m; ++c)
          for (int q = 0; q < 3; ++q) e.emplace_back(t + q, d - K + c);
      }
    }
  }
  struct_pattern_ = bvp::SparsityPattern::from_triplets(K * J, K * J, e);
  struct_pos_.resize(e.size());
  for (std::size_t i = 0; i < e.size(); ++i) struct_pos_[i] = struct_pattern_.index_of(e[i].first, e[i].second);
  struct_values_.assign(static_cast<std::size_t>(struct_pattern_.nnz()), 0.0);
  struct_rhs_.resize(K * J);
  struct_J_ = J;
  struct_external_ = ext;
}

bool LumpedProblem::setup_newton_step(const Eigen::Ref<const Eigen::VectorXd>& x,
                                      const Eigen::Ref<const Eigen::VectorXd>& f) {
  if (!contacts_.empty()) return contact_setup_newton_step(x, f);
  if (!undamped_structured_jacobian(x, f)) return false;
  if (struct_J_ != active() || struct_external_ != jac_external_) build_structured_pattern();
  const int m = body_.per_subsegment, J = active();
  const bool ext = jac_external_;
  double* v = struct_values_.data();
  const int* pos = struct_pos_.data();
  std::size_t i = 0;
  auto put = [&](double value) { v[pos[i++]] = value; };
  for (int j = 0; j < J; ++j) {
    for (int c = 0; c < m; ++c)
      for (int r = 0; r < m; ++r)
        put(jac_diag_(r, m * j + c) + (r == c && damping_ > 0.0 ? damping_ * damping_scale_[m * j + c] : 0.0));
    for (int c = 0; c < 6; ++c)
      for (int r = 0; r < m; ++r) put(jac_E_(m * j + r, c));
    if (ext)
      for (int c = 0; c < 3; ++c)
        for (int r = 0; r < m; ++r) put(jac_D_(m * j + r, c));
    for (int q = 0; q < 6; ++q) put(1.0);
    if (j + 1 < J) {
      for (int q = 0; q < 6; ++q) put(-1.0);
      for (int c = 0; c < m; ++c)
        for (int q = 0; q < 6; ++q) put(-jac_dW_(q, m * (j + 1) + c));
    }
    if (ext) {
      for (int q = 0; q < 3; ++q) put(1.0);
      if (j > 0) {
        for (int q = 0; q < 3; ++q) put(-1.0);
        for (int c = 0; c < m; ++c)
          for (int q = 0; q < 3; ++q) put(-jac_Om_(q, m * (j - 1) + c));
      }
    }
  }
  return lu_.factorize(struct_pattern_, v) == bvp::SparseLu::Status::Success;
}

bool LumpedProblem::solve_newton_step(Eigen::Ref<Eigen::VectorXd> b) {
  if (!contacts_.empty()) return contact_solve_newton_step(b);
  const int m = body_.per_subsegment, K = m + 6 + (struct_external_ ? 3 : 0);
  struct_rhs_.setZero();
  for (int j = 0; j < active(); ++j) struct_rhs_.segment(K * j, m) = b.segment(m * j, m);
  if (!lu_.solve(struct_rhs_.data())) return false;
  for (int j = 0; j < active(); ++j) b.segment(m * j, m) = struct_rhs_.segment(K * j, m);
  return true;
}

}  // namespace tdcr::detail
