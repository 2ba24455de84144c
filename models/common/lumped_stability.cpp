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
#include <limits>

#include <Eigen/Eigenvalues>

#include "common/least_stable_mode.hpp"
#include "common/lumped_problem.hpp"

namespace tdcr::detail {

namespace {

constexpr double kUndecided = 1e-6;

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

}  // namespace tdcr::detail
