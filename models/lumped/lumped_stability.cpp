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
// With contact candidates (contact_stability, docs/contact.md "Stability with contact"): the same
// Jacobian with the contact forces held, restricted to the tangent space of the rigid contacts
// that carry force (the finite eigenvalues of the contact Jacobian's pencil), or with the
// compliant contacts' penalty stiffness added.
//
// direct_stability: a sufficient test first, the eigen test where it does not prove stability.
// The scaled Jacobian A from the structured factors (diagonal blocks G_j, E_j W_k above, D_j Om_k
// below: lumped_structured.cpp), balanced by a diagonal similarity T (Osborne sweeps on its
// block tridiagonal part: where A = Gm H, Gm a positive diagonal and H symmetric, T = Gm^-1/2
// makes it symmetric). Every eigenvalue's real part is at least the smallest eigenvalue of the
// symmetric part S of T A T^-1 (the field of values); S is block semiseparable, so a block
// Cholesky factorisation of S - sigma I carrying the generators' Schur complement (Haynsworth)
// decides in O(J) that S has no eigenvalue below sigma: stable, margin sigma (a certified lower
// bound of the smallest real part). The automatic rule's test of a cold direct answer under
// external loads. Its Jacobian is Newton's last where that is of the same equations and near
// the answer (a relative slack in the factorisation covers the change, kJacobianChange), else
// the answer's own: from Newton's last it adds 14 % (CCsub) and 22 % (PRB) to the median loaded
// solve of bench_loaded, where the answer's own added 42 and 44 % (docs/models.md, "Stability").
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/QR>

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
// The sufficient test from Newton's last Jacobian (taken at x_0, not at the answer x): a bound
// of the relative change of the balanced symmetric part per radian of |x - x_0|, |D^-1 dS D^-1|
// <= kJacobianChange |x - x_0| with D^2 = |diag S|. Measured against the Jacobian at the answer
// on the loaded cases of bench_loaded: at most 1.6 (CCsub) and 2.6 (PRB), median 0.4, over
// every solve of `bench_loaded --cases 60 --repeat 1 --steps 4` (365 answers each, T after 3
// sweeps, |x - x_0| up to 0.016 and 0.52 rad); at most 1.6 and 3.2 over the 60 cold default
// answers with T as the test takes it (after one sweep). The bound has a factor 3 of room.
constexpr double kJacobianChange = 10.0;
// Above this relative slack Newton's last Jacobian is not tried (on the 60 cold default PRB
// answers of bench_loaded a slack up to 0.39 proved, none from 0.58).
constexpr double kMaxReuseSlack = 0.5;
// The sufficient test's method, from the answer's Jacobian and from Newton's last.
const std::string kProvenMethod =
    "sufficient test of d(constitutive residuals)/d(scaled x_j); balanced symmetric part positive definite above the "
    "margin (block Cholesky): every eigenvalue's real part is at least the margin, a certified lower bound";
const std::string kProvenReusedMethod =
    kProvenMethod + " (from Newton's last Jacobian near the answer, its change covered by a relative slack)";

}  // namespace

Stability LumpedProblem::stability(const Eigen::VectorXd& y, double load_factor) {
  if (loads_.loads.load_factor() != load_factor) set_parameter(load_factor);
  if (!contacts_.empty()) return contact_stability(y);
  Stability out;
  out.method = "eigenvalues of d(constitutive residuals)/d(scaled x_j), smallest real part";
  gather_x(y, x_);
  // Left on every return below: the path goes on from a tested landing.
  const StabilityChartScope chart(*this, x_);
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

// A candidate whose scaled force b = f / F_s exceeds this is an active contact: a constraint of
// the test (1e-6 F_s is 4e-7 N on the paper robot). One at or below it is not; it is weakly
// active if it touches (kTouching).
constexpr double kActiveForce = 1e-6;
// A candidate below kActiveForce whose scaled gap g / r_o is below this touches without force:
// weakly active.
constexpr double kTouching = 1e-6;
// Rank of the constraint rows and force columns: pivots below this fraction of the largest (of
// unit rows and columns: their forward differences are good to about 1e-8).
constexpr double kRankTolerance = 1e-6;
// The oblique projection Y^T Z of contact_stability's reduction: below this reciprocal
// condition number the reduction is not trusted.
constexpr double kProjectionRcond = 1e-10;

// The least stable finite eigenvalue sigma of the constrained pencil
//   A v + C mu = sigma v,  G v = 0,
// A (n x n) the Jacobian of the constitutive residuals in the scaled x at fixed contact forces,
// G (k x n) the active gaps' gradients, C (n x k) the residuals' response to the active forces.
// With v = Z w (Z a basis of null(G)) and Y a basis of null(C^T) (which removes the unknown
// forces mu): Y^T A Z w = sigma Y^T Z w. Where A = B H (B the laws' regular matrix, H the
// potential's Hessian) and C = -B G^T (the contact forces do the gaps' virtual work), these are
// the eigenvalues of the pencil (Z^T H Z, Z^T B^-1 Z): the Hessian on the tangent space in the
// metric B^-1, whose inertia is that of Z^T H Z; for symmetric A (B = I) Y = Z and the matrix is
// Z^T A Z, whose smallest eigenvalue is at least A's (Cauchy interlacing). Returns false with
// `why` where the ranks of G and C differ or Y^T Z is (nearly) singular.
bool constrained_margin(const Eigen::MatrixXd& A, Eigen::MatrixXd G, Eigen::MatrixXd C, double& margin,
                        std::string& mode, std::string& why, Eigen::MatrixXd* reduced = nullptr,
                        Eigen::MatrixXd* basis = nullptr) {
  const Eigen::Index n = A.rows();
  for (Eigen::Index i = 0; i < G.rows(); ++i) {
    const double g = G.row(i).norm(), c = C.col(i).norm();
    if (!(g > 0.0) || !(c > 0.0)) {
      why = "; a contact's gap gradient or force column is zero";
      return false;
    }
    G.row(i) /= g;
    C.col(i) /= c;
  }
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qg(G.transpose()), qc(C);
  qg.setThreshold(kRankTolerance);
  qc.setThreshold(kRankTolerance);
  const Eigen::Index rank = qg.rank();
  if (qc.rank() != rank) {
    why = "; the active gaps' gradients (rank " + std::to_string(rank) + ") and the forces' columns (rank " +
          std::to_string(qc.rank()) + ") disagree";
    return false;
  }
  if (rank == n) {
    why = "; the active contacts fix every unknown";
    return false;
  }
  const Eigen::MatrixXd Qg = qg.householderQ(), Qc = qc.householderQ();
  const Eigen::MatrixXd Z = Qg.rightCols(n - rank), Y = Qc.rightCols(n - rank);
  const Eigen::PartialPivLU<Eigen::MatrixXd> lu(Y.transpose() * Z);
  if (!(lu.rcond() > kProjectionRcond)) {
    why = "; the tangent space and the forces' complement are (nearly) singular to each other";
    return false;
  }
  const Eigen::MatrixXd R = lu.solve(Y.transpose() * A * Z);
  const Eigen::EigenSolver<Eigen::MatrixXd> eig(R, false);
  if (eig.info() != Eigen::Success || !R.allFinite()) {
    why = "; the eigenvalue solver failed";
    return false;
  }
  margin = least_stable_mode(eig.eigenvalues(), mode);
  if (reduced) *reduced = R;
  if (basis) *basis = Z;
  return true;
}

// An unstable verdict whose modes may lie in unknowns whose laws decide nothing there
// (LumpedProblem::ill_posed_unknown: `ill`, indices into the scaled x): the eigenvalues of K
// (the reduced matrix, its modes mapped to x by `basis`, or K itself with no basis) below
// -kUndecided whose mode (the eigenvector's largest entries) is not mostly in `ill` decide:
// unstable, margin the least of them; if every one is, undetermined.
void recheck_ill_posed(const Eigen::MatrixXd& K, const Eigen::MatrixXd* basis, const std::vector<int>& ill,
                       Stability& out) {
  const Eigen::EigenSolver<Eigen::MatrixXd> eig(K, true);
  if (eig.info() != Eigen::Success) return;
  double worst = INFINITY;
  int dominated = 0;
  for (Eigen::Index k = 0; k < K.rows(); ++k) {
    const double re = eig.eigenvalues()[k].real();
    if (!(re < -kUndecided)) continue;
    Eigen::VectorXd v = eig.eigenvectors().col(k).cwiseAbs();
    if (basis) v = (*basis * eig.eigenvectors().col(k)).cwiseAbs();
    double in = 0.0;
    for (int i : ill) in = std::max(in, v[i]);
    if (in >= 0.5 * v.maxCoeff()) {
      ++dominated;
      continue;
    }
    worst = std::min(worst, re);
  }
  if (dominated == 0) return;
  char buf[200];
  if (std::isfinite(worst)) {
    out.margin = worst;
    std::snprintf(buf, sizeof buf,
                  "; %d unstable modes in an ill-posed law (a PRB subsegment's bending plane at an inflection) set "
                  "aside: the least of the others %.6g",
                  dominated, worst);
  } else {
    out.status = StabilityStatus::Undetermined;
    out.margin = NAN;
    std::snprintf(buf, sizeof buf,
                  "; undetermined: every unstable mode (%d) lies in an ill-posed law (a PRB subsegment's bending "
                  "plane at an inflection)",
                  dominated);
  }
  out.method += buf;
}

// The rows of G (columns of C) of the candidates in `set`.
void select(const Eigen::MatrixXd& G, const Eigen::MatrixXd& C, const std::vector<int>& set, Eigen::MatrixXd& Gs,
            Eigen::MatrixXd& Cs) {
  Gs.resize(static_cast<Eigen::Index>(set.size()), G.cols());
  Cs.resize(C.rows(), static_cast<Eigen::Index>(set.size()));
  for (std::size_t k = 0; k < set.size(); ++k) {
    Gs.row(static_cast<Eigen::Index>(k)) = G.row(set[k]);
    Cs.col(static_cast<Eigen::Index>(k)) = C.col(set[k]);
  }
}

}  // namespace

// The stability of an equilibrium with contact (docs/contact.md, "Stability"). The matrices of
// the free-space test at the answer, by the same forward differences of the recursive residual
// in the same scaled x (the contact forces held: their points and normals move with the disks,
// so A carries the obstacles' curvature and the rims' turning), plus the active gaps' gradients
// (the same evaluations' gaps, scaled by r_o) and the residuals' response to the scaled forces:
//  - rigid contact: a contact with force is an active unilateral constraint, and the equilibrium
//    is stable if the stiffness is positive definite on the tangent space of the active gaps
//    (constrained_margin()). Contacts touching with no force (weakly active) are taken as
//    inactive first: a sufficient test (perturbations that would open them are allowed too). If
//    that does not find the answer stable, the test with them as equalities (a necessary one)
//    decides unstable; between the two the verdict is undetermined (the cone test they need is
//    not done).
//  - compliant contact: no constraint; a penetrated pair's force k max(0, -g) follows x, so its
//    stiffness adds C dB/dx = -C (k r_o / F_s) G to A (the contact Jacobian with the forces
//    eliminated), whose eigenvalues are then taken as in free space. As k grows the eigenvalues
//    of the constrained directions grow with it and the others tend to the rigid test's.
Stability LumpedProblem::contact_stability(const Eigen::VectorXd& y) {
  Stability out;
  const int nc = static_cast<int>(contacts_.size());
  gather_x(y, x_);
  const StabilityChartScope chart(*this, x_);  // left on every return below
  const int n = static_cast<int>(x_.size());
  // The contact system's unknowns in the chart: the x_j, then the candidates' scaled forces.
  Eigen::VectorXd z(n + nc);
  z.head(n) = x_;
  z.tail(nc) = y.tail(nc);
  Eigen::VectorXd s(n), r0(n + nc), r1(n + nc), g0(nc);
  for (int j = 0; j < active(); ++j) x_scale(s.data() + body_.per_subsegment * j);
  const std::string failed = "eigenvalues with contact; the residual could not be evaluated";
  if (!recursive_residual(z.data(), r0.data()) || !r0.allFinite()) {
    out.method = failed;
    return out;
  }
  for (int i = 0; i < nc; ++i) g0[i] = contacts_[static_cast<std::size_t>(i)].at.gap;
  Eigen::MatrixXd A(n, n), G(nc, n), C(n, nc);
  const double rel = std::sqrt(std::numeric_limits<double>::epsilon());
  Eigen::VectorXd zp = z;
  for (int c = 0; c < n + nc; ++c) {
    const double h = c < n ? rel * std::max(std::abs(z[c]), 1.0 / s[c]) : rel * std::max(std::abs(z[c]), 1.0);
    zp[c] = z[c] + h;
    if (!recursive_residual(zp.data(), r1.data()) || !r1.allFinite()) {
      out.method = failed;
      recursive_residual(z.data(), r0.data());
      return out;
    }
    if (c < n) {  // columns in the scaled unknown s_c x_c; gaps scaled by r_o
      A.col(c) = (r1.head(n) - r0.head(n)) / (h * s[c]);
      for (int i = 0; i < nc; ++i)
        G(i, c) = (contacts_[static_cast<std::size_t>(i)].at.gap - g0[i]) / (h * s[c] * contact_length_scale_);
    } else {
      C.col(c - n) = (r1.head(n) - r0.head(n)) / h;
    }
    zp[c] = z[c];
  }
  // The candidates as the answer has them (their points, normals and forces).
  recursive_residual(z.data(), r0.data());
  std::vector<int> ill;  // unknowns whose laws decide nothing here (ill_posed_unknown)
  for (int j = 0; j < active(); ++j) {
    const int m = body_.per_subsegment, i = ill_posed_unknown(x_.data() + m * j);
    if (i >= 0) ill.push_back(m * j + i);
  }
  std::string mode;
  char buf[240];
  // The same Jacobian without the contact constraints (forces held): what the contacts change.
  const Eigen::EigenSolver<Eigen::MatrixXd> free_eig(A, false);
  std::string free_mode;
  const double free_margin =
      free_eig.info() == Eigen::Success ? least_stable_mode(free_eig.eigenvalues(), free_mode) : NAN;
  std::snprintf(buf, sizeof buf, "; without the contacts' constraints (forces held) %.9g", free_margin);
  const std::string free_note = buf;
  const auto decide = [&](double margin) {
    out.margin = margin;
    if (margin > kUndecided)
      out.status = StabilityStatus::Stable;
    else if (margin < -kUndecided)
      out.status = StabilityStatus::Unstable;
  };
  if (contact_stiffness_ > 0.0) {
    // Compliant: the penetrated pairs' penalty stiffness.
    int penetrated = 0;
    Eigen::MatrixXd K = A;
    const double k = contact_stiffness_ * contact_length_scale_ / contact_force_scale_;
    for (int i = 0; i < nc; ++i) {
      if (!(g0[i] < 0.0)) continue;
      ++penetrated;
      K.noalias() -= k * C.col(i) * G.row(i);
    }
    const Eigen::EigenSolver<Eigen::MatrixXd> eig(K, false);
    std::snprintf(buf, sizeof buf,
                  "eigenvalues of d(constitutive residuals)/d(scaled x_j) with the stiffness of %d compliant "
                  "contacts, smallest real part",
                  penetrated);
    out.method = buf;
    if (eig.info() != Eigen::Success || !K.allFinite()) {
      out.method += "; the eigenvalue solver failed";
      return out;
    }
    decide(least_stable_mode(eig.eigenvalues(), mode));
    out.method += mode;
    if (out.status == StabilityStatus::Unstable && !ill.empty()) recheck_ill_posed(K, nullptr, ill, out);
    out.method += free_note;
    return out;
  }
  // Rigid: active (force), weakly active (touching, no force), the others open.
  std::vector<int> strong, both;
  for (int i = 0; i < nc; ++i) {
    const double b = z[n + i];
    if (b > kActiveForce) {
      strong.push_back(i);
      both.push_back(i);
    } else if (g0[i] / contact_length_scale_ < kTouching) {
      both.push_back(i);
    }
  }
  const int weak = static_cast<int>(both.size() - strong.size());
  std::snprintf(buf, sizeof buf,
                "eigenvalues of d(constitutive residuals)/d(scaled x_j) on the tangent space of %d active contacts "
                "(the finite eigenvalues of the contact Jacobian's pencil), smallest real part",
                static_cast<int>(strong.size()));
  out.method = buf;
  Eigen::MatrixXd Gs, Cs, R, Z;
  double margin = NAN;
  std::string why;
  if (strong.empty()) {
    margin = free_margin;
    mode = free_mode;
  } else {
    select(G, C, strong, Gs, Cs);
    if (!constrained_margin(A, Gs, Cs, margin, mode, why, &R, &Z)) {
      out.method += why;
      return out;
    }
  }
  out.method += mode;
  if (weak > 0) {
    std::snprintf(buf, sizeof buf, "; %d weakly active (touching, force < %.0e F_s) taken as open: a sufficient test",
                  weak, kActiveForce);
    out.method += buf;
  }
  if (margin > kUndecided || weak == 0) {
    decide(margin);
    if (out.status == StabilityStatus::Unstable && !ill.empty())
      recheck_ill_posed(strong.empty() ? A : R, strong.empty() ? nullptr : &Z, ill, out);
    out.method += free_note;
    return out;
  }
  // Not proven stable with the weakly active contacts open: with them closed (a necessary test).
  double closed = NAN;
  std::string closed_mode;
  select(G, C, both, Gs, Cs);
  if (!constrained_margin(A, Gs, Cs, closed, closed_mode, why)) {
    out.method += "; with them closed" + why;
    return out;
  }
  std::snprintf(buf, sizeof buf, "; with them closed %.6g", closed);
  out.method += buf;
  if (closed < -kUndecided) {
    out.status = StabilityStatus::Unstable;
    out.margin = closed;
  } else {
    out.method += ": undetermined between the two (the cone of the weakly active contacts is not tested)";
  }
  out.method += free_note;
  return out;
}

namespace {

// The sufficient test's core for M unknowns per subsegment and R generator columns (6: the
// distal wrench; 9 with external loads: and the distal rotation), fixed sizes (lumped_problem.hpp,
// proven_stable). Inputs: the structured Jacobian's factors (diag m x n, E n x 6, dW 6 x n, and
// with external loads D n x 3, Om 3 x n), the unknowns' scales s; buffers G, up, lo (m x n),
// Pt, Q (R x n), t (n). Returns whether S - sigma I - slack |diag S| is positive definite for
// sigma half S's smallest diagonal entry, or else kProof, and that sigma (slack: the relative
// change allowed for where the factors are Newton's last, not the answer's; else 0).
template <int M, int R>
bool balanced_symmetric_part_above(const Eigen::MatrixXd& diag, const Eigen::MatrixXd& E, const Eigen::MatrixXd& dW,
                                   const Eigen::MatrixXd& D, const Eigen::MatrixXd& Om, const Eigen::VectorXd& s,
                                   int J, Eigen::MatrixXd& G, Eigen::MatrixXd& up, Eigen::MatrixXd& lo,
                                   Eigen::MatrixXd& Pt, Eigen::MatrixXd& Q, Eigen::VectorXd& t, double slack,
                                   double& margin) {
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
  // Finite (a sum is, unless an entry is not or they are near overflow: then not tried either).
  if (!std::isfinite(G.sum() + up.sum() + lo.sum())) return false;
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
    const double inv = 1.0 / f;
    t[i] *= f;
    g(j).row(a) *= f;
    g(j).col(a) *= inv;
    if (j + 1 < J) {
      u(j).row(a) *= f;
      l(j).col(a) *= inv;
    }
    if (j > 0) {
      l(j - 1).row(a) *= f;
      u(j - 1).col(a) *= inv;
    }
  };
  auto ok = [&](int i, double f) { return std::isfinite(f) && t[i] * f < 1e8 && t[i] * f > 1e-8; };
  // One Osborne sweep; true if no factor moved by more than 1 %.
  const auto sweep = [&]() {
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
    return done;
  };
  // S = sym(T A T^-1) has the diagonal blocks sym(T_j G_j T_j^-1) and, for j < k, the blocks
  // S_jk = P_j Q_k with P_j = [T_j E_j, (Om_j C_j)^T], Q_k = [W_k C_k; (T_k D_k)^T] / 2 (C = the
  // column factors 1 / (s t)): a block semiseparable matrix, factorised in O(J).
  Pt.resize(R, n);
  Q.resize(R, n);
  const auto generators = [&]() {
    for (int i = 0; i < n; ++i) {
      const double c = 1.0 / (s[i] * t[i]);
      Pt.col(i).template head<6>() = t[i] * E.row(i).transpose();
      Q.col(i).template head<6>() = 0.5 * c * dW.col(i);
      if constexpr (ext) {
        Pt.col(i).template tail<3>() = c * Om.col(i);
        Q.col(i).template tail<3>() = 0.5 * t[i] * D.row(i).transpose();
      }
    }
  };
  // (S's diagonal is A's: a diagonal similarity keeps it.)
  double smallest = std::numeric_limits<double>::infinity();
  for (int j = 0; j < J; ++j) smallest = std::min(smallest, g(j).diagonal().minCoeff());
  // Whether S - sigma I is positive definite: the block Cholesky factorisation from the base,
  // with the generators' Schur complement Z carried along (Haynsworth).
  const auto above = [&](double sigma) {
    MatR Z = MatR::Zero();
    MatRM Y, U;
    MatM Pi;
    Eigen::Matrix<double, M, R> V;
    for (int j = 0; j < J; ++j) {
      const Eigen::Map<const MatRM> Qj(Q.data() + R * M * j);
      // Fixed-size products by coefficients (Eigen would take these sizes to its blocked GEMM).
      Y.noalias() = Z.lazyProduct(Qj);
      Pi = 0.5 * (g(j) + g(j).transpose());
      Pi.diagonal().array() -= sigma + slack * g(j).diagonal().array().abs();
      Pi.noalias() -= Qj.transpose().lazyProduct(Y);
      // Pi = L L^T in place (lower triangle), false where a pivot is not positive.
      for (int c = 0; c < M; ++c) {
        double p = Pi(c, c);
        for (int k = 0; k < c; ++k) p -= Pi(c, k) * Pi(c, k);
        if (!(p > 0.0)) return false;
        p = std::sqrt(p);
        Pi(c, c) = p;
        for (int r = c + 1; r < M; ++r) {
          double v = Pi(r, c);
          for (int k = 0; k < c; ++k) v -= Pi(r, k) * Pi(c, k);
          Pi(r, c) = v / p;
        }
      }
      if (j + 1 == J) break;
      U = Eigen::Map<const MatRM>(Pt.data() + R * M * j) - Y;  // (P_j - Q_j^T Z)^T
      // Z += U Pi^-1 U^T = V^T V with V = L^-1 U^T (forward substitution).
      double inv[M];
      for (int r = 0; r < M; ++r) inv[r] = 1.0 / Pi(r, r);
      for (int c = 0; c < R; ++c)
        for (int r = 0; r < M; ++r) {
          double v = U(c, r);
          for (int k = 0; k < r; ++k) v -= Pi(r, k) * V(k, c);
          V(r, c) = v * inv[r];
        }
      Z.noalias() += V.transpose().lazyProduct(V);
    }
    return true;
  };
  // S's smallest eigenvalue lies below its smallest diagonal entry: half that entry, else kProof.
  const auto proven = [&]() {
    generators();
    for (double sigma : {0.5 * smallest, kProof}) {
      if (!(sigma >= kProof) || !above(sigma)) continue;
      margin = sigma;
      return true;
    }
    return false;
  };
  // Tried after the first sweep (enough for most answers: a sweep costs about as much as the
  // factorisation), else after the others.
  bool done = sweep();
  if (proven()) return true;
  if (done) return false;  // the others would not move it
  for (int k = 1; k < kBalanceSweeps && !done; ++k) done = sweep();
  return proven();
}

}  // namespace

bool LumpedProblem::proven_stable(double& margin, bool& reused, bool reuse) {
  reused = false;
  const int m = body_.per_subsegment, n = static_cast<int>(x_.size()), J = active();
  stab_s_.resize(n);
  for (int j = 0; j < J; ++j) x_scale(stab_s_.data() + m * j);
  const auto balanced = [&](double slack) {
    const bool ext = jac_external_;
#define TDCR_BALANCED(M, R)                                                                                 \
  balanced_symmetric_part_above<M, R>(jac_diag_, jac_E_, jac_dW_, jac_D_, jac_Om_, stab_s_, J, stab_G_, stab_up_, \
                                      stab_lo_, stab_P_, stab_Q_, stab_t_, slack, margin)
    if (m == 3) return ext ? TDCR_BALANCED(3, 9) : TDCR_BALANCED(3, 6);
    if (m == 5) return ext ? TDCR_BALANCED(5, 9) : TDCR_BALANCED(5, 6);
    return false;  // no other lumped model
#undef TDCR_BALANCED
  };
  if (m != 3 && m != 5) return false;
  if (reuse) {
    // Newton's last Jacobian, taken at jac_at_: its balanced symmetric part S_0 differs from the
    // answer's S by dS, and S - sigma I is positive definite where S_0 - sigma I - delta D^2 is
    // (D^2 = |diag S_0|) and |D^-1 dS D^-1| <= delta. delta: kJacobianChange per radian of the
    // unknowns' change |x - jac_at_| (2-norm; the x_j are angles in both models).
    const double change = (x_ - jac_at_).norm();
    const double delta = kJacobianChange * change;
    if (delta <= kMaxReuseSlack && balanced(delta)) {
      reused = true;
      return true;
    }
  }
  // The answer's Jacobian (residual(): the structured differences then start from its evaluation).
  stab_r_.resize(n);
  if (!residual(x_, stab_r_)) return false;
  if (!structured_jacobian(x_, stab_r_)) return false;
  return balanced(0.0);
}

Stability LumpedProblem::direct_stability(const Eigen::VectorXd& y, double load_factor) {
  if (banded_ || body_.statics.friction() || damping_ > 0.0 || !contacts_.empty()) return stability(y, load_factor);
  if (loads_.loads.load_factor() != load_factor) set_parameter(load_factor);
  double margin = NAN;
  bool proven = false, reused = false;
  {
    gather_x(y, x_);
    if (x_.size() == 0) return stability(y, load_factor);
    // Newton's last Jacobian is of these equations if nothing changed them since (the chart
    // below does where it turns a subsegment's plane: then the unknowns change too).
    bool reuse = jac_equations_ == equations_serial_ && jac_lambda_ == load_factor && jac_at_.size() == x_.size();
    if (reuse) stab_y_ = x_;
    const StabilityChartScope chart(*this, x_);  // left on every return below
    reuse = reuse && stab_y_ == x_;
    proven = proven_stable(margin, reused, reuse);
  }
  if (!proven) return stability(y, load_factor);
  Stability out;
  out.status = StabilityStatus::Stable;
  out.margin = margin;
  out.method = reused ? kProvenReusedMethod : kProvenMethod;
  return out;
}

}  // namespace tdcr::detail
