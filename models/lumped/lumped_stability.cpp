// Stability of a CCsub or PRB equilibrium (LumpedProblem::stability): the reduced stiffness in
// the model's generalized coordinates x_j.
//
// The recursive residuals r(x) are the constitutive laws of the subsegments: spring moment minus
// the moment of everything distal (Eq. 43 for CCsub, Eq. 48-54 for PRB), scaled by l / EI. With
// conservative loads (tensions: potential sum T_k l_k over the tendon chords; dead tip force and
// weights) they are r = B(x) Q(x), Q the gradient of the total potential and B a regular matrix
// that is a positive diagonal at rest (each law is written along its own coordinate; PRB puts
// its bending plane along the distal moment, so its bending angles are positive). B's entry of
// PRB's bending-plane law has the sign of the subsegment's bend: a subsegment bent against its
// plane (a solve can end there past an inflection of the bend, where the in-plane moment turns)
// would give B H a negative eigenvalue for a stable equilibrium, so the test rewrites such a
// subsegment as the same shape with its plane turned by pi (enter_stability_chart). At an
// equilibrium dr/dx = B H, H the Hessian of the total potential: along the loading path from
// rest, an eigenvalue of dr/dx crosses zero exactly where H becomes singular. The test takes
// the eigenvalues of the Jacobian in the scaled unknowns (dimensionless) and
//   margin = the smallest real part,
// stable if > 1e-6, unstable if < -1e-6, else undetermined (forward-difference noise).
// Not covered (documented in docs/models.md): with Eq. 58 (disk normal forces removed, the
// paper's default) the disk forces are not conservative, and a dead tip moment is not
// conservative in 3-D; the real parts then are the quasi-static divergence criterion (flutter,
// complex eigenvalues crossing the imaginary axis, is not a static question).
//
// direct_stability: a sufficient test first, the eigen test where it does not prove stability.
// The scaled Jacobian A from the structured factors (diagonal blocks G_j, E_j W_k above, D_j Om_k
// below: lumped_structured.cpp), balanced by a diagonal similarity T (Osborne sweeps on its
// block tridiagonal part: where A = Gm H, Gm a positive diagonal and H symmetric, T = Gm^-1/2
// makes it symmetric). Every eigenvalue's real part is at least the smallest eigenvalue of the
// symmetric part S of T A T^-1 (the field of values); S is block semiseparable, so a block
// Cholesky factorisation of S - sigma I carrying the generators' Schur complement (Haynsworth)
// decides in O(J) that S has no eigenvalue below sigma: stable, margin sigma (a certified lower
// bound of the smallest real part). Not called by the automatic rule: with its structured
// Jacobian at the answer it adds 42 % (CCsub) and 44 % (PRB) to the median loaded solve of
// bench_loaded (docs/models.md, "Stability").
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "physics/least_stable_mode.hpp"
#include "lumped/lumped_problem.hpp"

namespace tdcr::detail {

namespace {

constexpr double kUndecided = 1e-6;
// The sufficient test proves stability only above this bound of the smallest real part (ten
// times the undecided band: its Jacobian's differences are not the eigen test's).
constexpr double kProof = 10.0 * kUndecided;
// Osborne sweeps of the sufficient test's balancing.
constexpr int kBalanceSweeps = 3;

}  // namespace

Stability LumpedProblem::stability(const Eigen::VectorXd& y, double load_factor) {
  Stability out;
  if (!contacts_.empty()) {  // the test knows no contact constraints (docs/contact.md)
    out.method = "not determined with contact";
    return out;
  }
  out.method = "eigenvalues of d(constitutive residuals)/d(scaled x_j), smallest real part";
  if (loads_.loads.load_factor() != load_factor) set_parameter(load_factor);
  gather_x(y, x_);
  enter_stability_chart(x_);
  // Every return below leaves the chart (the path goes on from a tested landing).
  struct Leave {
    LumpedProblem& p;
    ~Leave() { p.leave_stability_chart(); }
  } leave{*this};
  const int n = static_cast<int>(x_.size());
  if (n == 0) {
    // Nothing loaded: the straight robot held by its elastic stiffness alone.
    out.status = StabilityStatus::Stable;
    out.method = "unloaded: the straight robot";
    return out;
  }
  Eigen::VectorXd s(n), r0(n), r1(n);
  for (int j = 0; j < active(); ++j) x_scale(s.data() + body_.per_subsegment * j);
  if (!recursive_residual(x_.data(), r0.data()) || !r0.allFinite()) {
    out.method += "; the residual could not be evaluated";
    return out;
  }
  Eigen::MatrixXd J(n, n);
  const double rel = std::sqrt(std::numeric_limits<double>::epsilon());
  Eigen::VectorXd xp = x_;
  for (int c = 0; c < n; ++c) {
    const double h = rel * std::max(std::abs(x_[c]), 1.0 / s[c]);
    xp[c] = x_[c] + h;
    if (!recursive_residual(xp.data(), r1.data()) || !r1.allFinite()) {
      out.method += "; the residual could not be evaluated";
      return out;
    }
    // Column in the scaled unknown s_c x_c.
    J.col(c) = (r1 - r0) / (h * s[c]);
    xp[c] = x_[c];
  }
  const Eigen::EigenSolver<Eigen::MatrixXd> eig(J, false);
  if (eig.info() != Eigen::Success) {
    out.method += "; the eigenvalue solver failed";
    return out;
  }
  std::string mode;
  out.margin = least_stable_mode(eig.eigenvalues(), mode);
  out.method += mode;
  if (out.margin > kUndecided)
    out.status = StabilityStatus::Stable;
  else if (out.margin < -kUndecided)
    out.status = StabilityStatus::Unstable;
  return out;
}

namespace {

// The sufficient test's core for M unknowns per subsegment and R generator columns (6: the
// distal wrench; 9 with external loads: and the distal rotation), fixed sizes (lumped_problem.hpp,
// proven_stable). Inputs: the structured Jacobian's factors (diag m x n, E n x 6, dW 6 x n, and
// with external loads D n x 3, Om 3 x n), the unknowns' scales s; buffers G, up, lo (m x n),
// Pt, Q (R x n), t (n). Returns whether S - sigma I is positive definite for sigma half S's
// smallest diagonal entry, or else kProof, and that sigma.
template <int M, int R>
bool balanced_symmetric_part_above(const Eigen::MatrixXd& diag, const Eigen::MatrixXd& E, const Eigen::MatrixXd& dW,
                                   const Eigen::MatrixXd& D, const Eigen::MatrixXd& Om, const Eigen::VectorXd& s,
                                   int J, Eigen::MatrixXd& G, Eigen::MatrixXd& up, Eigen::MatrixXd& lo,
                                   Eigen::MatrixXd& Pt, Eigen::MatrixXd& Q, Eigen::VectorXd& t, double& margin) {
  using MatM = Eigen::Matrix<double, M, M>;
  using MatR = Eigen::Matrix<double, R, R>;
  using MatRM = Eigen::Matrix<double, R, M>;
  using Strided = Eigen::OuterStride<>;
  constexpr bool ext = R == 9;
  const int n = M * J;
  G.resize(M, n);
  up.setZero(M, n);
  lo.setZero(M, n);
  auto g = [&](int j) { return Eigen::Map<MatM>(G.data() + M * M * j); };
  auto u = [&](int j) { return Eigen::Map<MatM>(up.data() + M * M * j); };
  auto l = [&](int j) { return Eigen::Map<MatM>(lo.data() + M * M * j); };
  auto e = [&](int j) {
    return Eigen::Map<const Eigen::Matrix<double, M, 6>, 0, Strided>(E.data() + M * j, Strided(E.rows()));
  };
  auto w = [&](int j) { return Eigen::Map<const Eigen::Matrix<double, 6, M>>(dW.data() + 6 * M * j); };
  auto d = [&](int j) {
    return Eigen::Map<const Eigen::Matrix<double, M, 3>, 0, Strided>(D.data() + M * j, Strided(D.rows()));
  };
  auto om = [&](int j) { return Eigen::Map<const Eigen::Matrix<double, 3, M>>(Om.data() + 3 * M * j); };
  // The block tridiagonal part of the scaled Jacobian A = J diag(1/s): diagonal blocks G_j,
  // A_j,j+1 = E_j W_j+1 and A_j+1,j = D_j+1 Om_j.
  for (int j = 0; j < J; ++j) {
    const auto sj = s.segment<M>(M * j).cwiseInverse().asDiagonal();
    g(j).noalias() = Eigen::Map<const MatM>(diag.data() + M * M * j) * sj;
    if (j + 1 < J) {
      u(j).noalias() = e(j) * w(j + 1) * s.segment<M>(M * (j + 1)).cwiseInverse().asDiagonal();
      if constexpr (ext) l(j).noalias() = d(j + 1) * om(j) * sj;
    }
  }
  if (!G.allFinite() || !up.allFinite() || !lo.allFinite()) return false;
  // Balanced: a diagonal similarity T A T^-1 with equal off-diagonal row and column norms
  // (Osborne). Where A = Gm H with Gm a positive diagonal and H symmetric (the laws' B diagonal,
  // in the scaled unknowns), T = Gm^-1/2 makes A and its block tridiagonal part symmetric, and
  // balancing (unique up to a factor) finds it. A few sweeps (kBalanceSweeps) take it close
  // enough: on the loaded cases of bench_loaded (n = 3 to 20) every answer is then proven
  // stable (more sweeps converge on the block tridiagonal part, which at n = 20 balanced the
  // whole matrix worse: 6 of 90 PRB answers not proven with 30).
  t.setOnes(n);
  auto scale = [&](int i, double f) {  // row i times f, column i over f
    const int j = i / M, a = i % M;
    t[i] *= f;
    g(j).row(a) *= f;
    g(j).col(a) /= f;
    if (j + 1 < J) {
      u(j).row(a) *= f;
      l(j).col(a) /= f;
    }
    if (j > 0) {
      l(j - 1).row(a) *= f;
      u(j - 1).col(a) /= f;
    }
  };
  auto ok = [&](int i, double f) { return std::isfinite(f) && t[i] * f < 1e8 && t[i] * f > 1e-8; };
  for (int sweep = 0; sweep < kBalanceSweeps; ++sweep) {
    bool done = true;
    for (int i = 0; i < n; ++i) {
      const int j = i / M, a = i % M;
      const double dd = g(j)(a, a) * g(j)(a, a);
      double row = g(j).row(a).squaredNorm() - dd, col = g(j).col(a).squaredNorm() - dd;
      if (j + 1 < J) {
        row += u(j).row(a).squaredNorm();
        col += l(j).col(a).squaredNorm();
      }
      if (j > 0) {
        row += l(j - 1).row(a).squaredNorm();
        col += u(j - 1).col(a).squaredNorm();
      }
      if (!(row > 0.0) || !(col > 0.0)) continue;
      const double f = std::sqrt(std::sqrt(col / row));
      if (!ok(i, f)) continue;
      if (std::abs(f - 1.0) > 0.01) done = false;
      scale(i, f);
    }
    if (done) break;
  }
  // S = sym(T A T^-1) has the diagonal blocks sym(T_j G_j T_j^-1) and, for j < k, the blocks
  // S_jk = P_j Q_k with P_j = [T_j E_j, (Om_j C_j)^T], Q_k = [W_k C_k; (T_k D_k)^T] / 2 (C = the
  // column factors 1 / (s t)): a block semiseparable matrix, factorised in O(J).
  Pt.resize(R, n);
  Q.resize(R, n);
  for (int i = 0; i < n; ++i) {
    const double c = 1.0 / (s[i] * t[i]);
    Pt.col(i).template head<6>() = t[i] * E.row(i).transpose();
    Q.col(i).template head<6>() = 0.5 * c * dW.col(i);
    if constexpr (ext) {
      Pt.col(i).template tail<3>() = c * Om.col(i);
      Q.col(i).template tail<3>() = 0.5 * t[i] * D.row(i).transpose();
    }
  }
  double smallest = std::numeric_limits<double>::infinity();
  for (int j = 0; j < J; ++j) smallest = std::min(smallest, g(j).diagonal().minCoeff());
  // Whether S - sigma I is positive definite: the block Cholesky factorisation from the base,
  // with the generators' Schur complement Z carried along (Haynsworth).
  const auto above = [&](double sigma) {
    MatR Z = MatR::Zero();
    MatRM Y, U;
    MatM Pi;
    for (int j = 0; j < J; ++j) {
      const Eigen::Map<const MatRM> Qj(Q.data() + R * M * j);
      Y.noalias() = Z * Qj;
      Pi = 0.5 * (g(j) + g(j).transpose());
      Pi.diagonal().array() -= sigma;
      Pi.noalias() -= Qj.transpose() * Y;
      const Eigen::LLT<MatM> llt(Pi);
      if (llt.info() != Eigen::Success) return false;
      if (j + 1 == J) break;
      U = Eigen::Map<const MatRM>(Pt.data() + R * M * j) - Y;  // (P_j - Q_j^T Z)^T
      Z.noalias() += U * llt.solve(U.transpose());
    }
    return true;
  };
  // S's smallest eigenvalue lies below its smallest diagonal entry: half that entry, else kProof.
  for (double sigma : {0.5 * smallest, kProof}) {
    if (!(sigma >= kProof) || !above(sigma)) continue;
    margin = sigma;
    return true;
  }
  return false;
}

}  // namespace

bool LumpedProblem::proven_stable(double& margin, std::string& how) {
  const int m = body_.per_subsegment, n = static_cast<int>(x_.size()), J = active();
  stab_r_.resize(n);
  if (!recursive_residual(x_.data(), stab_r_.data()) || !stab_r_.allFinite()) return false;
  if (!structured_jacobian(x_, stab_r_)) return false;
  stab_s_.resize(n);
  for (int j = 0; j < J; ++j) x_scale(stab_s_.data() + m * j);
  const bool ext = jac_external_;
  bool proven = false;
#define TDCR_BALANCED(M, R)                                                                                      \
  proven = balanced_symmetric_part_above<M, R>(jac_diag_, jac_E_, jac_dW_, jac_D_, jac_Om_, stab_s_, J, stab_G_, \
                                               stab_up_, stab_lo_, stab_P_, stab_Q_, stab_t_, margin)
  if (m == 3 && ext) TDCR_BALANCED(3, 9);
  else if (m == 3) TDCR_BALANCED(3, 6);
  else if (m == 5 && ext) TDCR_BALANCED(5, 9);
  else if (m == 5) TDCR_BALANCED(5, 6);
  else return false;  // no other lumped model
#undef TDCR_BALANCED
  if (proven)
    how = "; balanced symmetric part positive definite above the margin (block Cholesky): every eigenvalue's real "
          "part is at least the margin, a certified lower bound";
  return proven;
}

Stability LumpedProblem::direct_stability(const Eigen::VectorXd& y, double load_factor) {
  if (banded_ || body_.statics.friction() || damping_ > 0.0 || !contacts_.empty()) return stability(y, load_factor);
  if (loads_.loads.load_factor() != load_factor) set_parameter(load_factor);
  double margin = NAN;
  std::string how;
  bool proven = false;
  {
    gather_x(y, x_);
    if (x_.size() == 0) return stability(y, load_factor);
    enter_stability_chart(x_);
    struct Leave {
      LumpedProblem& p;
      ~Leave() { p.leave_stability_chart(); }
    } leave{*this};
    proven = proven_stable(margin, how);
  }
  if (!proven) return stability(y, load_factor);
  Stability out;
  out.status = StabilityStatus::Stable;
  out.margin = margin;
  out.method = "sufficient test of d(constitutive residuals)/d(scaled x_j)" + how;
  return out;
}

}  // namespace tdcr::detail
