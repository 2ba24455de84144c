// Differential kinematics by the implicit function theorem (differential_kinematics.hpp).
#include "solve/differential_kinematics.hpp"

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

// dF/dx at x: the system's own Jacobian unless it is a forward difference, else central differences with the increment
// h_rel max(|x_j|, min(typical magnitude, 1)). Not the Newton solver's forward differences: their
// O(h) error reaches 5e-5 relative in PRB's tip compliance, whose bending-plane angle has a
// deliberately large increment (1.5e-4 rad, PrbProblem::x_scale).
bool system_jacobian(bvp::ResidualSystem& sys, const Eigen::VectorXd& x, const Eigen::VectorXd& f, double h_rel,
                     Eigen::MatrixXd& J) {
  if (sys.has_jacobian() && !sys.jacobian_is_forward_difference() && bvp::analytic_jacobian_dense(sys, x, f, J))
    return true;
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

// Values at v + a h and v + b h extrapolated linearly to v: the mean for central differences
// (a = 1, b = -1), 2 g(h) - g(2h) for one-sided ones (a = 1, b = 2).
template <class T>
T at_v(const T& at_a, const T& at_b, double a, double b) {
  return (b * at_a - a * at_b) / (b - a);
}

// For a perturbation that adds unknowns (CCsub and PRB leave unloaded distal subsegments out of
// their system): the answer in the larger system bound to `va` and `vb` (their warm guess from the
// Solution: exact, those subsegments are straight) and that system's F_x at v, extrapolated.
// `lu` is reused if it already holds the F_x of a system of this size (the lumped models' only
// larger system: every subsegment loaded).
bool lifted_linearisation(const Rebind& rebind, const ModelInput& va, const ModelInput& vb, double a, double b,
                          const ModelProblem* P, const Solution& solution, double h_rel, Eigen::VectorXd& x,
                          Eigen::PartialPivLU<Eigen::MatrixXd>& lu) {
  ModelProblem* Pa = bound(rebind, va, P);
  if (!Pa || !Pa->warm_guess(solution, x) || !Pa->differentiable(x)) return false;
  const int n = Pa->system()->size();
  if (x.size() != n) return false;
  if (lu.rows() == n) return true;
  Eigen::VectorXd f(n);
  Eigen::MatrixXd J_a(n, n), J_b(n, n);
  if (!Pa->system()->residual(x, f) || !system_jacobian(*Pa->system(), x, f, h_rel, J_a)) return false;
  ModelProblem* Pb = bound(rebind, vb, P);
  if (!Pb || Pb->system()->size() != n || !Pb->system()->residual(x, f) ||
      !system_jacobian(*Pb->system(), x, f, h_rel, J_b))
    return false;
  lu.compute(at_v<Eigen::MatrixXd>(J_a, J_b, a, b));
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
  if (solution.disk_frames.empty()) return;
  const Frame tip = solution.tip();

  bool ok = true;
  Eigen::PartialPivLU<Eigen::MatrixXd> lu, lu_lifted;
  Eigen::VectorXd f(n);  // F(x; v)
  if (sys) {
    Eigen::MatrixXd J(n, n);
    ok = n == x.size() && P->differentiable(x) && sys->residual(x, f) && system_jacobian(*sys, x, f, h_rel, J);
    if (ok) lu.compute(J);
  }
  Eigen::MatrixXd D(6, parameters);
  Eigen::VectorXd xj, f_a, f_b, scale;
  for (int j = 0; ok && j < parameters; ++j) {
    const double h = increment(input, j, h_rel, force_scale, moment_scale);
    // Central differences (v + h, v - h), but one-sided (v + h, v + 2h) at a zero tension: a
    // tendon cannot push, and the models drop tendons without tension.
    const bool one_sided = j < m && input.actuation.kind == Actuation::Kind::Tensions &&
                           input.actuation.values[static_cast<std::size_t>(j)] == 0.0;
    const double a = 1.0, b = one_sided ? 2.0 : -1.0;
    const ModelInput va = perturbed(input, j, a * h), vb = perturbed(input, j, b * h);
    xj = x;  // the answer in the unknowns of the perturbed systems
    Eigen::VectorXd x_a = x, x_b = x;
    if (sys) {
      ModelProblem* Pa = bound(rebind, va, P);
      const bool lifted = Pa && Pa->system()->size() != n;
      ok = Pa && (!lifted || lifted_linearisation(rebind, va, vb, a, b, P, solution, h_rel, xj, lu_lifted));
      // dx/dv_j = -F_x^{-1} dF/dv_j at the answer.
      const int nj = static_cast<int>(xj.size());
      f_a.resize(nj);
      f_b.resize(nj);
      scale.resize(nj);
      ok = ok && (Pa = bound(rebind, va, P)) && Pa->system()->size() == nj && Pa->system()->residual(xj, f_a);
      ModelProblem* Pb = ok ? bound(rebind, vb, P) : nullptr;
      ok = ok && Pb && Pb->system()->size() == nj && Pb->system()->residual(xj, f_b);
      if (!ok) break;
      // F(x; v) of the system the perturbations are bound to (lifted: extrapolated, exact as the
      // lumped residuals are linear in the loads, and it must solve the larger system at v).
      const Eigen::VectorXd f0 = lifted ? at_v<Eigen::VectorXd>(f_a, f_b, a, b) : f;
      if (lifted) {
        Pb->system()->residual_scale(scale);
        ok = f0.cwiseProduct(scale).cwiseAbs().maxCoeff() <= 10.0 * tolerance;
        if (!ok) break;
      }
      const Eigen::VectorXd F_v =
          one_sided ? Eigen::VectorXd((4.0 * f_a - f_b - 3.0 * f0) / (2.0 * h)) : Eigen::VectorXd((f_a - f_b) / (2.0 * h));
      const Eigen::VectorXd dx = -(lifted ? lu_lifted : lu).solve(F_v);
      x_a = xj + a * h * dx;
      x_b = xj + b * h * dx;
    }
    // The tip along the tangent (dx/dv_j, 1) of the solution manifold.
    Frame tip_a, tip_b;
    ModelProblem* Pa = bound(rebind, va, P);
    ok = Pa && Pa->tip_pose(x_a, tip_a);
    ModelProblem* Pb = ok ? bound(rebind, vb, P) : nullptr;
    ok = ok && Pb && Pb->tip_pose(x_b, tip_b);
    if (!ok) break;
    if (one_sided)  // (4 g(h) - g(2h) - 3 g(0)) / 2h
      D.col(j) = (4.0 * pose_difference(tip_a, tip) - pose_difference(tip_b, tip)) / (2.0 * h);
    else
      D.col(j) = pose_difference(tip_a, tip_b) / (2.0 * h);
  }
  bound(rebind, input, nullptr);
  if (!ok || !D.allFinite()) return;
  solution.tip_jacobian = D.leftCols(m);
  if (sys) solution.tip_compliance = D.rightCols(6);
}

}  // namespace tdcr::detail
