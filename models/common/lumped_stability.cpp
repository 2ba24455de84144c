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
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "common/least_stable_mode.hpp"
#include "common/lumped_problem.hpp"

namespace tdcr::detail {

namespace {

constexpr double kUndecided = 1e-6;
// The sufficient test proves stability only above this bound of the smallest real part (ten
// times the undecided band: its Jacobian's differences are not the eigen test's).
constexpr double kProof = 10.0 * kUndecided;

}  // namespace

Stability LumpedProblem::stability(const Eigen::VectorXd& y, double load_factor) {
  Stability out;
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

bool LumpedProblem::proven_stable(double& margin, std::string& how) {
  const int m = body_.per_subsegment, n = static_cast<int>(x_.size()), J = active();
  stab_r_.resize(n);
  if (!recursive_residual(x_.data(), stab_r_.data()) || !stab_r_.allFinite()) return false;
  if (!structured_jacobian(x_, stab_r_)) return false;
  // The dense Jacobian from the structured factors (as jacobian(), undamped), columns in the
  // scaled unknowns s_c x_c as the eigen test's.
  Eigen::MatrixXd& A = stab_A_;
  A.resize(n, n);
  A.setZero();
  jac_prod_.resize(n, n);
  jac_prod_.noalias() = jac_E_ * jac_dW_;
  for (int k = 2; k <= J; ++k) A.block(0, m * (k - 1), m * (k - 1), m) = jac_prod_.block(0, m * (k - 1), m * (k - 1), m);
  if (jac_external_) {
    jac_prod_.noalias() = jac_D_ * jac_Om_;
    for (int k = 1; k < J; ++k)
      A.block(m * k, m * (k - 1), m * (J - k), m) = jac_prod_.block(m * k, m * (k - 1), m * (J - k), m);
  }
  for (int k = 1; k <= J; ++k) A.block(m * (k - 1), m * (k - 1), m, m) = jac_diag_.middleCols(m * (k - 1), m);
  stab_s_.resize(n);
  for (int j = 0; j < J; ++j) x_scale(stab_s_.data() + m * j);
  for (int c = 0; c < n; ++c) A.col(c) /= stab_s_[c];
  if (!A.allFinite()) return false;
  // Balanced (Osborne): a diagonal similarity T A T^-1 with equal off-diagonal row and column
  // norms. Where A = G H with G a positive diagonal and H symmetric (the laws' B diagonal, in the
  // scaled unknowns), the symmetric G^1/2 H G^1/2 is balanced and balancing is unique up to a
  // factor: it finds that T; near it, T A T^-1 is near symmetric.
  Eigen::VectorXd& t = stab_t_;
  t.setOnes(n);
  for (int sweep = 0; sweep < 20; ++sweep) {
    bool done = true;
    for (int i = 0; i < n; ++i) {
      const double d = A(i, i) * A(i, i);
      const double c = std::sqrt(std::max(0.0, A.col(i).squaredNorm() - d));
      const double r = std::sqrt(std::max(0.0, A.row(i).squaredNorm() - d));
      if (!(c > 0.0) || !(r > 0.0)) continue;
      const double f = std::sqrt(c / r);
      if (!std::isfinite(f) || std::abs(t[i] * f) > 1e8 || std::abs(t[i] * f) < 1e-8) continue;
      if (std::abs(f - 1.0) > 0.05) done = false;
      A.row(i) *= f;
      A.col(i) /= f;
      t[i] *= f;
    }
    if (done) break;
  }
  // Its symmetric part S: every eigenvalue of A has a real part of at least S's smallest
  // eigenvalue (x* A x / x* x lies in the field of values).
  A = 0.5 * (A + A.transpose()).eval();
  stab_v_ = A.diagonal();
  A.diagonal().array() -= kProof;
  {
    Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> llt(A);
    if (llt.info() != Eigen::Success) return false;
    // An estimate of S's smallest eigenvalue (inverse iteration with the factor), then the
    // margin certified as a lower bound by one more factorisation of S - margin I.
    Eigen::VectorXd& v = stab_r_;
    v.setOnes(n);
    v /= v.norm();
    double mu = std::numeric_limits<double>::infinity();
    for (int it = 0; it < 6; ++it) {
      llt.solveInPlace(v);
      const double norm = v.norm();
      if (!(norm > 0.0) || !std::isfinite(norm)) break;
      v /= norm;
      mu = 1.0 / norm;  // -> the smallest eigenvalue of S - kProof I
    }
    margin = std::min(mu + kProof, stab_v_.minCoeff());
  }
  // Certify: S - margin I positive definite (S rebuilt from its strict upper triangle, which the
  // in-place factorisations leave alone, and its diagonal).
  for (double f : {0.98, 0.9, 0.5}) {
    const double sigma = f * margin;
    if (!(sigma > kProof)) break;
    stab_A_.triangularView<Eigen::StrictlyLower>() = stab_A_.transpose();
    stab_A_.diagonal() = stab_v_.array() - sigma;
    const Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> check(stab_A_);
    if (check.info() == Eigen::Success) {
      margin = sigma;
      how = "; balanced symmetric part positive definite (Cholesky): every eigenvalue's real part is at least the "
            "margin, a lower bound of that part's smallest eigenvalue certified by its factorisation";
      return true;
    }
  }
  margin = kProof;
  how = "; balanced symmetric part positive definite (Cholesky): every eigenvalue's real part is at least the "
        "margin, a lower bound of that part's smallest eigenvalue certified by its factorisation";
  return true;
}

Stability LumpedProblem::direct_stability(const Eigen::VectorXd& y, double load_factor) {
  if (banded_ || body_.statics.friction() || damping_ > 0.0) return stability(y, load_factor);
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
  static const bool debug = std::getenv("TDCR_STAB_DEBUG") != nullptr;
  if (debug) {
    const Stability exact = stability(y, load_factor);
    std::fprintf(stderr, "STABDBG n=%d proven=%d bound=%.6g exact=%.6g status=%s\n", static_cast<int>(x_.size()),
                 proven ? 1 : 0, margin, exact.margin, to_string(exact.status).c_str());
  }
  if (!proven) return stability(y, load_factor);
  Stability out;
  out.status = StabilityStatus::Stable;
  out.margin = margin;
  out.method = "sufficient test of d(constitutive residuals)/d(scaled x_j)" + how;
  return out;
}

}  // namespace tdcr::detail
