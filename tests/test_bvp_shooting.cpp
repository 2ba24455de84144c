// Multiple shooting: structure, Jacobian cost and accuracy, solutions of BVPs with known answers.
#include <gtest/gtest.h>

#include <cmath>

#include "tdcr/bvp/integrator.hpp"
#include "tdcr/bvp/newton_solver.hpp"
#include "tdcr/bvp/shooting.hpp"

using tdcr::bvp::LinearSolverKind;
using tdcr::bvp::NewtonOptions;
using tdcr::bvp::NewtonSolver;
using tdcr::bvp::ShootingNodes;
using tdcr::bvp::ShootingSystem;

namespace {

// u' = v, v' = -lambda e^u (lambda = 0: u' = v, v' = -u, the linear oscillator).
class BratuOde : public tdcr::bvp::OdeSystem {
 public:
  explicit BratuOde(double lambda, bool linear) : lambda_(lambda), linear_(linear) {}
  int dimension() const override { return 2; }
  void rhs(double, const double* y, double* d) const override {
    d[0] = y[1];
    d[1] = linear_ ? -y[0] : -lambda_ * std::exp(y[0]);
  }

 private:
  double lambda_;
  bool linear_;
};

// u(0) = ua, u(1) = ub on N equal intervals; optional jumps in v at inner nodes that depend on
// the neighbouring nodes: v_i^+ = v_i^- - kappa (u_{i+1} - u_{i-1}), read from intervals i-1, i
// (coupling 0) or, with far = true, also u_{i+2} from interval i+1 (coupling 1).
class Problem : public tdcr::bvp::ShootingProblem {
 public:
  Problem(int n, double lambda, bool linear, double ua, double ub)
      : n_(n), ode_(lambda, linear), ua_(ua), ub_(ub) {}
  int state_dimension() const override { return 2; }
  int intervals() const override { return n_; }
  double node(int k) const override { return static_cast<double>(k) / n_; }
  const tdcr::bvp::OdeSystem& ode(int) const override { return ode_; }
  int coupling() const override { return far ? 1 : 0; }
  void boundary(const ShootingNodes& y, double* r) const override {
    r[0] = y.start(0)[0] - ua_;
    r[1] = y.end(n_ - 1)[0] - ub_;
  }
  void junction(int i, const ShootingNodes& y, double* r) const override {
    r[0] = y.start(i)[0] - y.end(i - 1)[0];
    double jump = kappa * (y.end(i)[0] - y.start(i - 1)[0]);
    if (far && i + 1 < n_) jump += kappa * y.end(i + 1)[0];
    r[1] = y.start(i)[1] - y.end(i - 1)[1] + jump;
  }
  double kappa = 0.0;
  bool far = false;

 private:
  int n_;
  BratuOde ode_;
  double ua_, ub_;
};

double bratu_exact(double x, double lambda) {
  double t = 1.0;
  for (int k = 0; k < 100; ++k) {
    const double g = t - std::sqrt(2.0 * lambda) * std::cosh(t / 4.0);
    const double dg = 1.0 - std::sqrt(2.0 * lambda) * std::sinh(t / 4.0) / 4.0;
    t -= g / dg;
  }
  return -2.0 * std::log(std::cosh((x - 0.5) * t / 2.0) / std::cosh(t / 4.0));
}

}  // namespace

TEST(BvpShooting, PatternIsBlockBandedAndJacobianCostsNTimesM) {
  const int n = 10;
  Problem p(n, 1.0, false, 0.0, 0.0);
  tdcr::bvp::Rk4Integrator rk(10);
  ShootingSystem sys(p, rk);
  EXPECT_EQ(sys.size(), 2 * n);
  // Every interval is read by exactly two residual blocks of 2 rows: nnz = N m (2 m).
  EXPECT_EQ(sys.sparsity()->nnz(), n * 2 * 2 * 2);
  int groups = 0;
  tdcr::bvp::column_groups(*sys.sparsity(), &groups);
  EXPECT_LE(groups, 3 * 2);  // independent of N

  Eigen::VectorXd x = Eigen::VectorXd::Constant(2 * n, 0.1), f(2 * n);
  ASSERT_TRUE(sys.residual(x, f));
  const long before = sys.interval_integrations();
  std::vector<double> values(sys.sparsity()->nnz());
  ASSERT_TRUE(sys.sparse_jacobian(x, f, values.data()));
  EXPECT_EQ(sys.interval_integrations() - before, n * 2);  // one interval per unknown
}

TEST(BvpShooting, StructuredJacobianMatchesCentralDifferences) {
  for (bool far : {false, true}) {
    Problem p(6, 1.0, false, 0.0, 0.0);
    p.kappa = 0.3;
    p.far = far;
    tdcr::bvp::Rk4Integrator rk(10);
    ShootingSystem sys(p, rk);
    Eigen::VectorXd x(12);
    for (int i = 0; i < 12; ++i) x[i] = 0.1 * std::sin(1.0 + i);
    const auto check = tdcr::bvp::check_jacobian(sys, x);
    EXPECT_TRUE(check.evaluated);
    // Forward differences of a smooth map: ~1e-7 relative; a missing pattern entry gives 1.
    EXPECT_LT(check.max_relative_error, 1e-5)
        << "far=" << far << " worst (" << check.worst_row << ", " << check.worst_col << ")";
  }
}

TEST(BvpShooting, LinearBvpMatchesExactSolution) {
  // u'' = -u, u(0) = 0, u(1) = 1: u = sin(s) / sin(1).
  const int n = 8;
  Problem p(n, 0.0, true, 0.0, 1.0);
  tdcr::bvp::Rk4Integrator rk(20);
  ShootingSystem sys(p, rk);
  NewtonSolver solver;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(2 * n);
  const auto r = solver.solve(sys, x);
  ASSERT_TRUE(r.converged()) << r.message;
  EXPECT_LE(r.iterations, 2);  // linear problem: one Newton step (plus rounding)
  for (int k = 0; k < n; ++k) {
    const double s = p.node(k);
    EXPECT_NEAR(x[2 * k], std::sin(s) / std::sin(1.0), 1e-9);
    EXPECT_NEAR(x[2 * k + 1], std::cos(s) / std::sin(1.0), 1e-9);
  }
}

TEST(BvpShooting, BratuWithRk4KluAndDenseAndCvode) {
  const int n = 10;
  const double lambda = 1.0;
  Problem p(n, lambda, false, 0.0, 0.0);
  NewtonSolver solver;
  NewtonOptions o;

  tdcr::bvp::Rk4Integrator rk(20);
  ShootingSystem sys_rk(p, rk);
  Eigen::VectorXd x_klu = Eigen::VectorXd::Zero(2 * n);
  o.linear_solver = LinearSolverKind::SparseKLU;
  const auto rk_klu = solver.solve(sys_rk, x_klu, o);
  ASSERT_TRUE(rk_klu.converged()) << rk_klu.message;
  EXPECT_EQ(rk_klu.linear_solver, "klu");

  Eigen::VectorXd x_dense = Eigen::VectorXd::Zero(2 * n);
  o.linear_solver = LinearSolverKind::Dense;
  const auto rk_dense = solver.solve(sys_rk, x_dense, o);
  ASSERT_TRUE(rk_dense.converged()) << rk_dense.message;
  EXPECT_LE((x_klu - x_dense).cwiseAbs().maxCoeff(), 1e-10);
  for (int k = 0; k < n; ++k) EXPECT_NEAR(x_klu[2 * k], bratu_exact(p.node(k), lambda), 1e-9);

  // CVODE: FD increments follow its tolerance (relative_noise), Newton still converges.
  tdcr::bvp::CvodeIntegrator cv(1e-10, 1e-12);
  ShootingSystem sys_cv(p, cv);
  EXPECT_EQ(sys_cv.relative_noise(), 1e-10);
  Eigen::VectorXd x_cv = Eigen::VectorXd::Zero(2 * n);
  o.linear_solver = LinearSolverKind::Automatic;
  const auto rc = solver.solve(sys_cv, x_cv, o);
  ASSERT_TRUE(rc.converged()) << rc.message;
  for (int k = 0; k < n; ++k) EXPECT_NEAR(x_cv[2 * k], bratu_exact(p.node(k), lambda), 1e-8);

  // The trajectory of the solution is available for output.
  ASSERT_TRUE(sys_cv.evaluate(x_cv));
  EXPECT_NEAR(sys_cv.nodes().end(n - 1)[0], 0.0, 1e-9);
}

TEST(BvpShooting, IntegrationFailureIsRecoverable) {
  // Blow-up: with a huge initial slope, e^u overflows; the solver must not crash and report it.
  Problem p(4, 1.0, false, 0.0, 0.0);
  tdcr::bvp::Rk4Integrator rk(10);
  ShootingSystem sys(p, rk);
  NewtonSolver solver;
  Eigen::VectorXd x = Eigen::VectorXd::Constant(8, 1e3);
  const auto r = solver.solve(sys, x);
  EXPECT_FALSE(r.converged());
  EXPECT_EQ(r.termination, tdcr::TerminationType::IntegrationFailed) << r.message;
}

// ---- Local unknowns: a chart per node, a smaller boundary node, row-level structure, shifts.
namespace {

// A planar curve of prescribed curvature w: state (p, a, b) with (a, b) = (cos t, sin t) the
// unit tangent angle t: p' = a, a' = -w b, b' = w a. The flow keeps a^2 + b^2 and is invariant
// under shifts of p. Node k >= 1 has unknowns (p, phi) with t = tbar_k + phi (a chart of the
// circle); node 0 only phi (p(0) = 0 is known). Residuals: block 0, p(1) = target; block i, p
// and angle continuity, sin(t_i - t^-) = a^- b_i - b^- a_i, plus kappa (p_{i+1} - p_{i-1}) in the
// angle row (a load read from the neighbouring nodes; coupling 1). Exact: p(1) = (sin(t0 + w) -
// sin t0) / w for kappa = 0.
class CurveProblem : public tdcr::bvp::ShootingProblem {
 public:
  CurveProblem(int n, double w, double target) : n_(n), ode_(w), target_(target), tbar_(n, 0.0) {}
  int state_dimension() const override { return 3; }
  int intervals() const override { return n_; }
  double node(int k) const override { return static_cast<double>(k) / n_; }
  const tdcr::bvp::OdeSystem& ode(int) const override { return ode_; }
  int coupling() const override { return 1; }
  int unknown_dimension(int k) const override { return k == 0 ? 1 : 2; }
  void start_state(int k, const double* x, double* y) const override {
    const double t = tbar_[k] + (k == 0 ? x[0] : x[1]);
    y[0] = k == 0 ? 0.0 : x[0];
    y[1] = std::cos(t);
    y[2] = std::sin(t);
  }
  void rebase(int k, double* x) override {
    double& phi = k == 0 ? x[0] : x[1];
    tbar_[k] += phi;
    phi = 0.0;
  }
  bool shifts_end(int k, int j) const override { return k > 0 && j == 0; }
  std::pair<int, int> dependent_rows(int block, int k, int j) const override {
    if (block == 0) return k == n_ - 1 ? std::make_pair(0, 1) : std::make_pair(0, 0);
    if (k == block - 1) return j == 0 && k > 0 && kappa == 0.0 ? std::make_pair(0, 1) : std::make_pair(0, 2);
    if (k == block && j == 0) return std::make_pair(0, k == n_ - 1 && kappa != 0.0 ? 2 : 1);  // tip: end(N-1)
    if (k == block) return {1, 2};
    if (k == block + 1 && j == 0 && kappa != 0.0) return {1, 2};
    return {0, 0};
  }
  void boundary(const ShootingNodes& y, double* r) const override { r[0] = y.end(n_ - 1)[0] - target_; }
  void junction(int i, const ShootingNodes& y, double* r) const override {
    const double* e = y.end(i - 1);
    const double* s = y.start(i);
    const double next = i + 1 < n_ ? y.start(i + 1)[0] : y.end(n_ - 1)[0];
    r[0] = s[0] - e[0];
    r[1] = e[1] * s[2] - e[2] * s[1] + kappa * (next - y.start(i - 1)[0]);
  }
  double tbar(int k) const { return tbar_[k]; }
  void set_tbar(int k, double t) { tbar_[k] = t; }
  double kappa = 0.0;

 private:
  class Ode : public tdcr::bvp::OdeSystem {
   public:
    explicit Ode(double w) : w_(w) {}
    int dimension() const override { return 3; }
    void rhs(double, const double* y, double* d) const override {
      d[0] = y[1];
      d[1] = -w_ * y[2];
      d[2] = w_ * y[1];
    }

   private:
    double w_;
  };
  int n_;
  Ode ode_;
  double target_;
  std::vector<double> tbar_;
};

// Guess: the arc of curvature w from angle t0 (tbar_k = t0 + w s_k, phi = 0, p on the arc).
Eigen::VectorXd curve_guess(CurveProblem& p, int n, double w, double t0) {
  Eigen::VectorXd x = Eigen::VectorXd::Zero(1 + 2 * (n - 1));
  for (int k = 0; k < n; ++k) {
    const double s = p.node(k);
    p.set_tbar(k, t0 + w * s);
    if (k > 0) x[1 + 2 * (k - 1)] = (std::sin(t0 + w * s) - std::sin(t0)) / w;
  }
  return x;
}

}  // namespace

TEST(BvpShootingLocal, LayoutPatternAndJacobianCost) {
  const int n = 6;
  CurveProblem p(n, 5.0, 0.1);
  tdcr::bvp::Rk4Integrator rk(10);
  ShootingSystem sys(p, rk);
  EXPECT_EQ(sys.size(), 1 + 2 * (n - 1));
  EXPECT_EQ(sys.offset(0), 0);
  EXPECT_EQ(sys.offset(1), 1);
  EXPECT_EQ(sys.offset(n), sys.size());
  // Columns: node 0 (phi): junction 1 (2 rows); node k (p): junction k (1), k+1 (1; block 0 for
  // k = N-1); node k (phi): junction k (1), k+1 (2; block 0: 1 for k = N-1).
  const int nnz = 2 + (n - 1) * 2 + (n - 2) * 3 + 2;
  EXPECT_EQ(sys.sparsity()->nnz(), nnz);
  Eigen::VectorXd x = curve_guess(p, n, 5.0, 0.3), f(sys.size());
  ASSERT_TRUE(sys.residual(x, f));
  const long before = sys.interval_integrations();
  std::vector<double> values(nnz);
  ASSERT_TRUE(sys.sparse_jacobian(x, f, values.data()));
  EXPECT_EQ(sys.interval_integrations() - before, n);  // shifts of p need no integration
  // A structure built once serves another system of an identical problem; not of another one.
  const auto structure = tdcr::bvp::ShootingStructure::of(p);
  CurveProblem q(n, 5.0, 0.1);
  ShootingSystem shared(q, rk, structure);
  EXPECT_EQ(*shared.sparsity(), *sys.sparsity());
  CurveProblem other(n + 1, 5.0, 0.1);
  EXPECT_THROW(ShootingSystem(other, rk, structure), std::invalid_argument);
}

TEST(BvpShootingLocal, JacobianMatchesCentralDifferences) {
  for (double kappa : {0.0, 0.4}) {
    const int n = 5;
    CurveProblem p(n, 5.0, 0.1);
    p.kappa = kappa;
    tdcr::bvp::Rk4Integrator rk(10);
    ShootingSystem sys(p, rk);
    Eigen::VectorXd x = curve_guess(p, n, 5.0, 0.3);
    for (int i = 0; i < x.size(); ++i) x[i] += 0.05 * std::sin(1.0 + i);
    const auto check = tdcr::bvp::check_jacobian(sys, x);
    ASSERT_TRUE(check.evaluated);
    EXPECT_LT(check.max_relative_error, 1e-5)
        << "kappa=" << kappa << " worst (" << check.worst_row << ", " << check.worst_col << ")";
  }
}

TEST(BvpShootingLocal, BendBeyondAFullTurnMatchesExactSolutionAndRebases) {
  // w = 8: the tangent turns by 8 rad (> 2 pi); the charts keep every unknown angle small.
  const int n = 8;
  const double w = 8.0, t0 = 0.7;
  const double target = (std::sin(t0 + w) - std::sin(t0)) / w;
  CurveProblem p(n, w, target);
  tdcr::bvp::Rk4Integrator rk(40);
  ShootingSystem sys(p, rk);
  Eigen::VectorXd x = curve_guess(p, n, w, t0 + 0.2);
  NewtonSolver solver;
  const auto r = solver.solve(sys, x);
  ASSERT_TRUE(r.converged()) << r.message;
  EXPECT_NEAR(p.tbar(0) + x[0], t0, 1e-7);
  for (int k = 1; k < n; ++k) {
    const double s = p.node(k);
    EXPECT_NEAR(x[1 + 2 * (k - 1)], (std::sin(t0 + w * s) - std::sin(t0)) / w, 1e-7) << k;
    EXPECT_NEAR(std::remainder(p.tbar(k) + x[2 + 2 * (k - 1)] - (t0 + w * s), 2 * M_PI), 0.0, 1e-7) << k;
  }
  // Rebasing folds the angles into the references: same start states, zero angle unknowns.
  Eigen::VectorXd f0(sys.size()), f1(sys.size());
  ASSERT_TRUE(sys.residual(x, f0));
  sys.rebase(x);
  EXPECT_EQ(x[0], 0.0);
  for (int k = 1; k < n; ++k) EXPECT_EQ(x[2 + 2 * (k - 1)], 0.0);
  ASSERT_TRUE(sys.residual(x, f1));
  EXPECT_LT((f1 - f0).cwiseAbs().maxCoeff(), 1e-12);
  // A system of a const problem cannot rebase.
  const CurveProblem& cp = p;
  ShootingSystem fixed(cp, rk);
  EXPECT_THROW(fixed.rebase(x), std::logic_error);
}
