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
// ((m + 6) J without external loads, where D = 0), factored by KLU in O(J). Each step is first
// solved by the block LU of J in its generators (qs_factor below, a few fixed-size products per
// subsegment, about a tenth of KLU's refactorisation and solves); that system on KLU is the
// fallback where the block LU, which does not pivot between blocks, loses accuracy. The iterates
// are those of the recursive form with its dense Jacobian (up to rounding), at a cost linear in
// the number of subsegments.
#include <cmath>
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

bool LumpedProblem::klu_setup_newton_step() {
  klu_factored_ = false;
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
  klu_factored_ = lu_.factorize(struct_pattern_, v) == bvp::SparseLu::Status::Success;
  return klu_factored_;
}

bool LumpedProblem::klu_solve_newton_step(Eigen::Ref<Eigen::VectorXd> b) {
  const int m = body_.per_subsegment, K = m + 6 + (struct_external_ ? 3 : 0);
  struct_rhs_.setZero();
  for (int j = 0; j < active(); ++j) struct_rhs_.segment(K * j, m) = b.segment(m * j, m);
  if (!lu_.solve(struct_rhs_.data())) return false;
  for (int j = 0; j < active(); ++j) b.segment(m * j, m) = struct_rhs_.segment(K * j, m);
  return true;
}

}  // namespace tdcr::detail

namespace tdcr::detail {

// The block LU factors of J = blockdiag(G_j) + (block upper part of E W) + (block lower part of
// D Om) (see the top of this file) keep that structure: with N_j = sum_{l <= j} Q_l P_l (3 x 6),
//
//   U: diagonal Delta_j = G_j - D_j N_{j-1} W_j, above it P_j W_k with P_j = E_j - D_j N_{j-1};
//   L: unit diagonal, below it D_j Q_k with Q_k = (Om_k - N_{k-1} W_k) Delta_k^{-1},
//
// so a factorisation and a solve take O(J) products of m x m, m x 6 and m x 3 blocks (Without
// external loads D = 0: Delta_j = G_j, P_j = E_j, back substitution alone.) No pivoting between
// blocks: the Delta_j are the Schur complements of the leading block minors, nonsingular where
// the Jacobian's symmetric part is definite (a stable answer and its neighbourhood); pivoting
// within each Delta_j. The residual check of each solve catches the rest.
template <int Rows>
bool LumpedProblem::qs_factor() {
  const int m = body_.per_subsegment, J = active();
  const bool ext = jac_external_;
  using MatM = Eigen::Matrix<double, Rows, Rows, 0, Rows == Eigen::Dynamic ? 8 : Rows, Rows == Eigen::Dynamic ? 8 : Rows>;
  qs_G_.resize(m, m * J);
  qs_inv_.resize(m, m * J);
  if (ext) {
    qs_P_.resize(m * J, 6);
    qs_Q_.resize(3, m * J);
  }
  Eigen::Matrix<double, 3, 6> N = Eigen::Matrix<double, 3, 6>::Zero();
  for (int j = 0; j < J; ++j) {
    auto G = qs_G_.template middleCols<Rows>(m * j, m);
    G = jac_diag_.template middleCols<Rows>(m * j, m);
    if (damping_ > 0.0) G.diagonal() += damping_ * damping_scale_.template segment<Rows>(m * j, m);
    const auto W = jac_dW_.template middleCols<Rows>(m * j, m);
    MatM Delta = G;
    Eigen::Matrix<double, 3, Rows, 0, 3, Rows == Eigen::Dynamic ? 8 : Rows> NW(3, m);
    if (ext) {
      NW.noalias() = N * W;
      Delta.noalias() -= jac_D_.template middleRows<Rows>(m * j, m) * NW;
    }
    // Delta_j^{-1} by Gauss-Jordan elimination with partial pivoting (m <= 8: Eigen's LU and its
    // inverse go through its general triangular solves, several times slower at this size). A
    // zero pivot: singular; the KLU system pivots across blocks.
    MatM inv_j = MatM::Identity(m, m);
    for (int c = 0; c < m; ++c) {
      int p = c;
      for (int r = c + 1; r < m; ++r)
        if (std::abs(Delta(r, c)) > std::abs(Delta(p, c))) p = r;
      if (!(std::abs(Delta(p, c)) > 0.0)) return false;
      if (p != c) {
        Delta.row(p).swap(Delta.row(c));
        inv_j.row(p).swap(inv_j.row(c));
      }
      const double d = 1.0 / Delta(c, c);
      Delta.row(c) *= d;
      inv_j.row(c) *= d;
      for (int r = 0; r < m; ++r) {
        if (r == c) continue;
        const double e = Delta(r, c);
        if (e == 0.0) continue;
        Delta.row(r) -= e * Delta.row(c);
        inv_j.row(r) -= e * inv_j.row(c);
      }
    }
    auto inv = qs_inv_.template middleCols<Rows>(m * j, m);
    inv = inv_j;
    if (!ext) continue;
    auto P = qs_P_.template middleRows<Rows>(m * j, m);
    P = jac_E_.template middleRows<Rows>(m * j, m);
    P.noalias() -= jac_D_.template middleRows<Rows>(m * j, m) * N;
    auto Q = qs_Q_.template middleCols<Rows>(m * j, m);
    Q.noalias() = (jac_Om_.template middleCols<Rows>(m * j, m) - NW) * inv;
    N.noalias() += Q * P;
  }
  return qs_inv_.allFinite() && (!ext || (qs_P_.allFinite() && qs_Q_.allFinite()));
}

template <int Rows>
void LumpedProblem::qs_solve(double* b) const {
  // L y = b (forward, v = sum_{k < j} Q_k y_k), then U x = y (backward, w = sum_{k > j} W_k x_k).
  const int m = body_.per_subsegment, J = active();
  using VecM = Eigen::Matrix<double, Rows, 1, 0, Rows == Eigen::Dynamic ? 8 : Rows, 1>;
  if (jac_external_) {
    Vec3 v = Vec3::Zero();
    for (int j = 0; j < J; ++j) {
      Eigen::Map<VecM> y(b + m * j, m);
      y.noalias() -= jac_D_.template middleRows<Rows>(m * j, m) * v;
      v.noalias() += qs_Q_.template middleCols<Rows>(m * j, m) * y;
    }
  }
  const Eigen::MatrixXd& P = jac_external_ ? qs_P_ : jac_E_;
  Eigen::Matrix<double, 6, 1> w = Eigen::Matrix<double, 6, 1>::Zero();
  for (int j = J - 1; j >= 0; --j) {
    Eigen::Map<VecM> x(b + m * j, m);
    VecM r = x;
    r.noalias() -= P.template middleRows<Rows>(m * j, m) * w;
    x.noalias() = qs_inv_.template middleCols<Rows>(m * j, m) * r;
    w.noalias() += jac_dW_.template middleCols<Rows>(m * j, m) * x;
  }
}

template <int Rows>
void LumpedProblem::qs_multiply(const double* x, double* y) const {
  // y = J x from the generators: s_j = sum_{k > j} W_k x_k, t_j = sum_{k < j} Om_k x_k.
  const int m = body_.per_subsegment, J = active();
  using VecM = Eigen::Matrix<double, Rows, 1, 0, Rows == Eigen::Dynamic ? 8 : Rows, 1>;
  Eigen::Matrix<double, 6, 1> s = Eigen::Matrix<double, 6, 1>::Zero();
  for (int j = J - 1; j >= 0; --j) {
    const Eigen::Map<const VecM> xj(x + m * j, m);
    Eigen::Map<VecM> yj(y + m * j, m);
    yj.noalias() = qs_G_.template middleCols<Rows>(m * j, m) * xj;
    yj.noalias() += jac_E_.template middleRows<Rows>(m * j, m) * s;
    s.noalias() += jac_dW_.template middleCols<Rows>(m * j, m) * xj;
  }
  if (!jac_external_) return;
  Vec3 t = Vec3::Zero();
  for (int j = 0; j < J; ++j) {
    const Eigen::Map<const VecM> xj(x + m * j, m);
    Eigen::Map<VecM>(y + m * j, m).noalias() += jac_D_.template middleRows<Rows>(m * j, m) * t;
    t.noalias() += jac_Om_.template middleCols<Rows>(m * j, m) * xj;
  }
}

bool LumpedProblem::setup_newton_step(const Eigen::Ref<const Eigen::VectorXd>& x,
                                      const Eigen::Ref<const Eigen::VectorXd>& f) {
  if (!contacts_.empty()) return contact_setup_newton_step(x, f);
  qs_factored_ = klu_factored_ = false;
  if (!undamped_structured_jacobian(x, f)) return false;
  switch (body_.per_subsegment) {
    case 3: qs_factored_ = qs_factor<3>(); break;
    case 5: qs_factored_ = qs_factor<5>(); break;
    default: qs_factored_ = qs_factor<Eigen::Dynamic>(); break;
  }
  qs_serial_ = jac_serial_;
  return qs_factored_ || klu_setup_newton_step();
}

bool LumpedProblem::solve_newton_step(Eigen::Ref<Eigen::VectorXd> b) {
  if (!contacts_.empty()) return contact_solve_newton_step(b);
  if (!qs_factored_) return klu_factored_ && klu_solve_newton_step(b);
  const int n = body_.per_subsegment * active();
  qs_b_ = b;  // allocates only when the size changes
  qs_r_.resize(n);
  const auto solve = [&](double* v) {
    switch (body_.per_subsegment) {
      case 3: qs_solve<3>(v); break;
      case 5: qs_solve<5>(v); break;
      default: qs_solve<Eigen::Dynamic>(v); break;
    }
  };
  const auto residual = [&]() {  // qs_r_ = b - J x, its largest entry
    switch (body_.per_subsegment) {
      case 3: qs_multiply<3>(b.data(), qs_r_.data()); break;
      case 5: qs_multiply<5>(b.data(), qs_r_.data()); break;
      default: qs_multiply<Eigen::Dynamic>(b.data(), qs_r_.data()); break;
    }
    qs_r_ = qs_b_ - qs_r_;
    return qs_r_.cwiseAbs().maxCoeff();
  };
  solve(b.data());
  // Accepted as a backward-stable solve would be, to a few digits of slack (the step is judged
  // by the residual anyway: KLU's kept refactorisations may lose three digits); one step of
  // refinement first, then the pivoting KLU system of the same factors.
  constexpr double kRelativeResidual = 1e-10;
  const double bound = kRelativeResidual * qs_b_.cwiseAbs().maxCoeff();
  double r = residual();
  if (r <= bound) return true;
  if (std::isfinite(r)) {
    solve(qs_r_.data());
    b += qs_r_;
    r = residual();
    if (r <= bound) return true;
  }
  // The values of the factors are still those of structured_jacobian() unless it ran since.
  if (qs_serial_ != jac_serial_) return false;
  qs_factored_ = false;
  if (!klu_setup_newton_step()) return false;
  b = qs_b_;
  return klu_solve_newton_step(b);
}

}  // namespace tdcr::detail
