// Differential kinematics by the implicit function theorem (differential_kinematics.hpp).
#include "common/differential_kinematics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/LU>

#include "tdcr/core/lie.hpp"

namespace tdcr::detail {

namespace {

// Input parameter j: actuation value j < m, then tip force x, y, z and tip moment x, y, z.
ModelInput perturbed(const ModelInput& input, int j, double dv) {
  ModelInput out = input;
  const int m = static_cast<int>(input.actuation.values.size());
  if (j < m)
    out.actuation.values[static_cast<std::size_t>(j)] += dv;
  else if (j < m + 3)
    out.loads.tip_force[j - m] += dv;
  else
    out.loads.tip_moment[j - m - 3] += dv;
  return out;
}

// Central-difference increment of parameter j: h_rel times its magnitude or its scale
// (tensions and forces: the force scale; displacements: 1 mm; moments: the moment scale).
double increment(const ModelInput& input, int j, double h_rel, double force_scale, double moment_scale) {
  const int m = static_cast<int>(input.actuation.values.size());
  if (j >= m) return h_rel * (j < m + 3 ? force_scale : moment_scale);
  const double v = std::abs(input.actuation.values[static_cast<std::size_t>(j)]);
  const bool tensions = input.actuation.kind == Actuation::Kind::Tensions;
  return h_rel * std::max(v, tensions ? force_scale : 1e-3);
}

// Pose difference a - b: position difference and the rotation vector of R_a R_b^T (base frame).
Eigen::Matrix<double, 6, 1> pose_difference(const Frame& a, const Frame& b) {
  Eigen::Matrix<double, 6, 1> d;
  d << a.p - b.p, lie::log_so3(a.R * b.R.transpose());
  return d;
}

// dF/dx at x: the system's analytic Jacobian, else central differences with the increment
// h_rel max(|x_j|, min(typical magnitude, 1)). Not the Newton solver's forward differences: their
// O(h) error reaches 5e-5 relative in PRB's tip compliance, whose bending-plane angle has a
// deliberately large increment (1.5e-4 rad, PrbProblem::x_scale).
bool system_jacobian(bvp::ResidualSystem& sys, const Eigen::VectorXd& x, const Eigen::VectorXd& f, double h_rel,
                     Eigen::MatrixXd& J) {
  if (sys.has_jacobian() && bvp::analytic_jacobian_dense(sys, x, f, J)) return true;
  const int n = sys.size();
  Eigen::VectorXd uscale(n), xp = x, fp(n), fm(n);
  sys.unknown_scale(uscale);
  for (int c = 0; c < n; ++c) {
    const double h = h_rel * std::max(std::abs(x[c]), std::min(1.0 / uscale[c], 1.0));
    xp[c] = x[c] + h;
    if (!sys.residual(xp, fp)) return false;
    xp[c] = x[c] - h;
    if (!sys.residual(xp, fm)) return false;
    xp[c] = x[c];
    J.col(c) = (fp - fm) / (2.0 * h);
  }
  return J.allFinite();
}

// The problem bound to `input` at load factor 1; null if it is not `expected` (a model that
// changes formulation with the input, VC near its multiple-shooting threshold).
ModelProblem* bound(const Rebind& rebind, const ModelInput& input, const ModelProblem* expected) {
  ModelProblem& P = rebind(input);
  if (expected && &P != expected) return nullptr;
  if (P.system()) P.system()->set_parameter(1.0);
  return &P;
}

// For a perturbation that adds unknowns (CCsub and PRB leave unloaded distal subsegments out of
// their system): the answer in the larger system bound to `plus` and `minus` (their warm guess
// from the Solution: exact, those subsegments are straight) and that system's F_x at v as the
// mean of F_x at v + h and v - h (O(h^2)).
// `lu` is reused if it already holds the F_x of a system of this size (the lumped models' only
// larger system: every subsegment loaded).
bool lifted_linearisation(const Rebind& rebind, const ModelInput& plus, const ModelInput& minus,
                          const ModelProblem* P, const Solution& solution, double h_rel, Eigen::VectorXd& x,
                          Eigen::PartialPivLU<Eigen::MatrixXd>& lu) {
  ModelProblem* Pp = bound(rebind, plus, P);
  if (!Pp || !Pp->warm_guess(solution, x) || !Pp->differentiable(x)) return false;
  const int n = Pp->system()->size();
  if (x.size() != n) return false;
  if (lu.rows() == n) return true;
  Eigen::VectorXd f(n);
  Eigen::MatrixXd J_plus(n, n), J_minus(n, n);
  if (!Pp->system()->residual(x, f) || !system_jacobian(*Pp->system(), x, f, h_rel, J_plus)) return false;
  ModelProblem* Pm = bound(rebind, minus, P);
  if (!Pm || Pm->system()->size() != n || !Pm->system()->residual(x, f) ||
      !system_jacobian(*Pm->system(), x, f, h_rel, J_minus))
    return false;
  lu.compute(0.5 * (J_plus + J_minus));
  return true;
}

}  // namespace

void differential_kinematics(const Rebind& rebind, const ModelInput& input, double force_scale,
                             double moment_scale, double tolerance, const Eigen::VectorXd& x, Solution& solution) {
  ModelProblem* P = bound(rebind, input, nullptr);
  bvp::ParameterizedSystem* sys = P->system();
  const int m = static_cast<int>(input.actuation.values.size());
  const int parameters = m + (sys ? 6 : 0);  // a closed-form model (CC) has no statics of loads
  const double eps = std::numeric_limits<double>::epsilon();
  const double h_rel = std::cbrt(std::max(eps, sys ? sys->relative_noise() : eps));
  const int n = sys ? sys->size() : 0;

  bool ok = true;
  Eigen::PartialPivLU<Eigen::MatrixXd> lu, lu_lifted;
  if (sys) {
    Eigen::VectorXd f(n);
    Eigen::MatrixXd J(n, n);
    ok = n == x.size() && P->differentiable(x) && sys->residual(x, f) && system_jacobian(*sys, x, f, h_rel, J);
    if (ok) lu.compute(J);
  }
  Eigen::MatrixXd D(6, parameters);
  Eigen::VectorXd xj, f_plus, f_minus, scale;
  for (int j = 0; ok && j < parameters; ++j) {
    const double h = increment(input, j, h_rel, force_scale, moment_scale);
    const ModelInput plus = perturbed(input, j, h), minus = perturbed(input, j, -h);
    xj = x;  // the answer in the unknowns of the perturbed systems
    Eigen::VectorXd x_plus = x, x_minus = x;
    if (sys) {
      ModelProblem* Pp = bound(rebind, plus, P);
      const bool lifted = Pp && Pp->system()->size() != n;
      ok = Pp && (!lifted || lifted_linearisation(rebind, plus, minus, P, solution, h_rel, xj, lu_lifted));
      // dx/dv_j = -F_x^{-1} dF/dv_j, the latter by central differences at the answer.
      const int nj = static_cast<int>(xj.size());
      f_plus.resize(nj);
      f_minus.resize(nj);
      scale.resize(nj);
      ok = ok && (Pp = bound(rebind, plus, P)) && Pp->system()->size() == nj && Pp->system()->residual(xj, f_plus);
      ModelProblem* Pm = ok ? bound(rebind, minus, P) : nullptr;
      ok = ok && Pm && Pm->system()->size() == nj && Pm->system()->residual(xj, f_minus);
      if (!ok) break;
      if (lifted) {  // the lifted answer must solve the larger system at v
        Pm->system()->residual_scale(scale);
        ok = (0.5 * (f_plus + f_minus)).cwiseProduct(scale).cwiseAbs().maxCoeff() <= 10.0 * tolerance;
        if (!ok) break;
      }
      const Eigen::VectorXd dx = -(lifted ? lu_lifted : lu).solve((f_plus - f_minus) / (2.0 * h));
      x_plus = xj + h * dx;
      x_minus = xj - h * dx;
    }
    // The tip along the tangent (dx/dv_j, 1) of the solution manifold, both sides.
    Frame tip_plus, tip_minus;
    ModelProblem* Pp = bound(rebind, plus, P);
    ok = Pp && Pp->tip_pose(x_plus, tip_plus);
    ModelProblem* Pm = ok ? bound(rebind, minus, P) : nullptr;
    ok = ok && Pm && Pm->tip_pose(x_minus, tip_minus);
    if (ok) D.col(j) = pose_difference(tip_plus, tip_minus) / (2.0 * h);
  }
  bound(rebind, input, nullptr);
  if (!ok || !D.allFinite()) return;
  solution.tip_jacobian = D.leftCols(m);
  if (sys) solution.tip_compliance = D.rightCols(6);
}

}  // namespace tdcr::detail
