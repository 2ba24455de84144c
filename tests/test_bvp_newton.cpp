// NewtonSolver (KINSOL): convergence, dense vs KLU, failures and their reporting, reuse.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <new>
#include <stdexcept>
#include <utility>
#include <vector>

#include "bvp_test_systems.hpp"
#include "allocation_counter.hpp"
#include "solve/bvp_options.hpp"
#include "tdcr/bvp/newton_solver.hpp"
#include "tdcr/core/error.hpp"

using tdcr::bvp::LinearSolverKind;
using tdcr::TerminationType;
using tdcr::bvp::NewtonOptions;
using tdcr::bvp::NewtonSolver;
using tdcr::bvp::SparsityPattern;



namespace {

// F = [10 (x1 - x0^2), 1 - x0]: the Rosenbrock function as a root-finding problem; unique
// root (1, 1). From (0, 0) full Newton steps reach it exactly in two iterations.
class Rosenbrock : public tdcr::bvp::ResidualSystem {
 public:
  int size() const override { return 2; }
  bool residual(const Eigen::Ref<const Eigen::VectorXd>& x,
                Eigen::Ref<Eigen::VectorXd> f) override {
    f[0] = 10.0 * (x[1] - x[0] * x[0]);
    f[1] = 1.0 - x[0];
    return true;
  }
};

// A 3x3 system with the root (1, 2, 3) and an analytic Jacobian.
class Dense3 : public tdcr::bvp::ResidualSystem {
 public:
  int size() const override { return 3; }
  bool residual(const Eigen::Ref<const Eigen::VectorXd>& x,
                Eigen::Ref<Eigen::VectorXd> f) override {
    f[0] = 3.0 * x[0] + x[1] * x[2] - 9.0;
    f[1] = x[0] * x[0] + 2.0 * x[1] - x[2] - 2.0;
    f[2] = std::exp(x[0] - 1.0) + x[1] + x[2] * x[2] - 12.0;
    return true;
  }
  bool has_jacobian() const override { return true; }
  bool jacobian(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>&,
                Eigen::Ref<Eigen::MatrixXd> J) override {
    J << 3.0, x[2], x[1],  //
        2.0 * x[0], 2.0, -1.0,  //
        std::exp(x[0] - 1.0), 1.0, 2.0 * x[2];
    return true;
  }
};



using bvp_test::Bratu;
using bvp_test::tridiagonal;

// Exact Bratu solution u(x) = -2 ln(cosh((x - 1/2) t / 2) / cosh(t / 4)), where t solves
// t = sqrt(2 lambda) cosh(t / 4) (lower branch).
double bratu_exact(double x, double lambda) {
  double t = 1.0;
  for (int k = 0; k < 100; ++k) {
    const double g = t - std::sqrt(2.0 * lambda) * std::cosh(t / 4.0);
    const double dg = 1.0 - std::sqrt(2.0 * lambda) * std::sinh(t / 4.0) / 4.0;
    t -= g / dg;
  }
  return -2.0 * std::log(std::cosh((x - 0.5) * t / 2.0) / std::cosh(t / 4.0));
}

// F(x) = x^2 + 1 has no real root: min |F| = 1 at x = 0.
class NoRoot : public tdcr::bvp::ResidualSystem {
 public:
  int size() const override { return 1; }
  bool residual(const Eigen::Ref<const Eigen::VectorXd>& x,
                Eigen::Ref<Eigen::VectorXd> f) override {
    f[0] = x[0] * x[0] + 1.0;
    return true;
  }
};

// F(x) = atan(x - 1) (root 1), but F cannot be evaluated for x > limit (or gives NaN there).
class Fragile : public tdcr::bvp::ResidualSystem {
 public:
  Fragile(double limit, bool nan) : limit_(limit), nan_(nan) {}
  int size() const override { return 1; }
  bool residual(const Eigen::Ref<const Eigen::VectorXd>& x,
                Eigen::Ref<Eigen::VectorXd> f) override {
    if (x[0] > limit_) {
      if (!nan_) return false;
      f[0] = std::numeric_limits<double>::quiet_NaN();
      return true;
    }
    f[0] = std::atan(x[0] - 1.0);
    return true;
  }

 private:
  double limit_;
  bool nan_;
};

// Dense3 whose analytic Jacobian cannot be evaluated.
class BadJacobian : public Dense3 {
 public:
  bool jacobian(const Eigen::Ref<const Eigen::VectorXd>&, const Eigen::Ref<const Eigen::VectorXd>&,
                Eigen::Ref<Eigen::MatrixXd>) override {
    return false;
  }
};

// F(x) = A x - b with an analytic sparse Jacobian; the pattern holds A's nonzeros, or every
// entry (explicit zeros included) if full.
class SparseLinear : public tdcr::bvp::ResidualSystem {
 public:
  SparseLinear(Eigen::MatrixXd a, Eigen::VectorXd rhs, bool full) : A(std::move(a)), b(std::move(rhs)) {
    set_pattern(full);
  }
  void set_pattern(bool full) {
    std::vector<std::pair<int, int>> e;
    for (int i = 0; i < A.rows(); ++i)
      for (int j = 0; j < A.cols(); ++j)
        if (full || A(i, j) != 0.0) e.emplace_back(i, j);
    p_ = SparsityPattern::from_triplets(A.rows(), A.cols(), e);
  }
  int size() const override { return static_cast<int>(A.rows()); }
  bool residual(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> f) override {
    f = A * x - b;
    return true;
  }
  const SparsityPattern* sparsity() const override { return &p_; }
  bool has_jacobian() const override { return true; }
  bool sparse_jacobian(const Eigen::Ref<const Eigen::VectorXd>&, const Eigen::Ref<const Eigen::VectorXd>&,
                       double* v) override {
    for (int j = 0; j < p_.cols; ++j)
      for (int k = p_.col_ptr[j]; k < p_.col_ptr[j + 1]; ++k) v[k] = A(p_.row_idx[k], j);
    return true;
  }

  Eigen::MatrixXd A;
  Eigen::VectorXd b;

 private:
  SparsityPattern p_;
};

class Throwing : public tdcr::bvp::ResidualSystem {
 public:
  int size() const override { return 2; }
  bool residual(const Eigen::Ref<const Eigen::VectorXd>&, Eigen::Ref<Eigen::VectorXd>) override {
    throw std::runtime_error("model bug");
  }
};

}  // namespace

TEST(BvpNewton, RosenbrockFromZeroInTwoFullNewtonSteps) {
  Rosenbrock sys;
  NewtonSolver solver;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(2);
  NewtonOptions o;
  o.line_search = false;
  const auto r = solver.solve(sys, x, o);
  ASSERT_TRUE(r.converged()) << r.message;
  EXPECT_EQ(r.flag, 0);
  EXPECT_EQ(r.iterations, 2);
  EXPECT_NEAR(x[0], 1.0, 1e-14);
  EXPECT_NEAR(x[1], 1.0, 1e-14);
  EXPECT_LE(r.residual_norm, 1e-10);
  EXPECT_EQ(r.linear_solver, "dense");
  EXPECT_NE(r.message.find("KIN_SUCCESS"), std::string::npos) << r.message;
}

// Rosenbrock computing its own Newton steps (ResidualSystem::has_newton_step) with the exact
// inverse Jacobian: the same two full steps, no Jacobian matrix formed.
class RosenbrockOwnStep : public Rosenbrock {
 public:
  bool has_newton_step() const override { return true; }
  bool setup_newton_step(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>&) override {
    J << -20.0 * x[0], 10.0, -1.0, 0.0;
    ++setups;
    return true;
  }
  bool solve_newton_step(Eigen::Ref<Eigen::VectorXd> b) override {
    b = J.inverse() * b;
    return true;
  }
  Eigen::Matrix2d J;
  int setups = 0;
};

TEST(BvpNewton, SystemNewtonStepsGiveTheSameIterations) {
  RosenbrockOwnStep sys;
  NewtonSolver solver;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(2);
  NewtonOptions o;
  o.line_search = false;
  const auto r = solver.solve(sys, x, o);
  ASSERT_TRUE(r.converged()) << r.message;
  EXPECT_EQ(r.iterations, 2);
  EXPECT_EQ(sys.setups, 2);
  EXPECT_EQ(r.fd_residual_evaluations, 0);
  EXPECT_EQ(r.linear_solver, "system");
  EXPECT_NEAR(x[0], 1.0, 1e-14);
  EXPECT_NEAR(x[1], 1.0, 1e-14);
}

TEST(BvpNewton, RosenbrockFromZeroWithLineSearch) {
  Rosenbrock sys;
  NewtonSolver solver;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(2);
  const auto r = solver.solve(sys, x);
  ASSERT_TRUE(r.converged()) << r.message;
  EXPECT_NEAR(x[0], 1.0, 1e-12);
  EXPECT_NEAR(x[1], 1.0, 1e-12);
  EXPECT_GT(r.jacobian_evaluations, 0);
  EXPECT_EQ(r.fd_residual_evaluations, 2 * r.jacobian_evaluations);  // dense FD: n per Jacobian
}

TEST(BvpNewton, Dense3x3AnalyticJacobianFromZero) {
  Dense3 sys;
  NewtonSolver solver;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(3);
  const auto r = solver.solve(sys, x);
  ASSERT_TRUE(r.converged()) << r.message;
  EXPECT_EQ(r.fd_residual_evaluations, 0);
  Eigen::VectorXd f(3);
  sys.residual(x, f);
  EXPECT_LE(f.cwiseAbs().maxCoeff(), 1e-10);
  EXPECT_EQ(r.physical_residual, f.norm());
  EXPECT_EQ(r.residual_norm, f.cwiseAbs().maxCoeff());
}

TEST(BvpNewton, BratuKluAndDenseAgreeAndMatchTheory) {
  const int n = 500;
  const double lambda = 1.0;
  NewtonSolver solver;
  NewtonOptions o;

  Bratu analytic(n, lambda, true);
  Eigen::VectorXd u_klu = Eigen::VectorXd::Zero(n);
  o.linear_solver = LinearSolverKind::Automatic;  // n = 500 > 200 with a pattern: KLU
  const auto rk = solver.solve(analytic, u_klu, o);
  ASSERT_TRUE(rk.converged()) << rk.message;
  EXPECT_EQ(rk.linear_solver, "klu");

  Eigen::VectorXd u_dense = Eigen::VectorXd::Zero(n);
  o.linear_solver = LinearSolverKind::Dense;
  const auto rd = solver.solve(analytic, u_dense, o);
  ASSERT_TRUE(rd.converged()) << rd.message;
  EXPECT_EQ(rd.linear_solver, "dense");
  EXPECT_LE((u_klu - u_dense).cwiseAbs().maxCoeff(), 1e-10);

  // Grouped finite differences on KLU: 3 residual evaluations per Jacobian, whatever n.
  Bratu numeric(n, lambda, false);
  Eigen::VectorXd u_fd = Eigen::VectorXd::Zero(n);
  o.linear_solver = LinearSolverKind::SparseKLU;
  const auto rf = solver.solve(numeric, u_fd, o);
  ASSERT_TRUE(rf.converged()) << rf.message;
  EXPECT_EQ(rf.fd_residual_evaluations, 3 * rf.jacobian_evaluations);
  EXPECT_LE((u_klu - u_fd).cwiseAbs().maxCoeff(), 1e-10);

  // Second-order discretisation: |u_h - u| = O(h^2) (h^2 = 4e-6, |u''''| is small).
  double err = 0.0;
  for (int i = 0; i < n; ++i)
    err = std::max(err, std::abs(u_klu[i] - bratu_exact((i + 1) * analytic.h(), lambda)));
  EXPECT_LT(err, analytic.h() * analytic.h());
}

TEST(BvpNewton, NoRootReportsFailureWithFlagIterationsAndResidual) {
  NoRoot sys;
  NewtonSolver solver;
  Eigen::VectorXd x(1);
  x << 0.5;
  const auto r = solver.solve(sys, x);
  EXPECT_FALSE(r.converged());
  EXPECT_NE(r.termination, TerminationType::NotSolved);
  EXPECT_LT(r.flag, 0);
  EXPECT_GT(r.iterations, 0);
  EXPECT_GE(r.residual_norm, 1.0);  // |x^2 + 1| >= 1 everywhere
  EXPECT_EQ(r.message.rfind("KIN_", 0), 0u) << r.message;
  EXPECT_NE(r.message.find("iterations"), std::string::npos) << r.message;
}

TEST(BvpNewton, MaxIterationsIsReportedAsSuch) {
  NoRoot sys;
  NewtonSolver solver;
  Eigen::VectorXd x(1);
  x << 0.5;
  NewtonOptions o;
  o.line_search = false;
  o.max_iterations = 7;
  const auto r = solver.solve(sys, x, o);
  EXPECT_EQ(r.termination, TerminationType::MaxIterations) << r.message;
  EXPECT_EQ(r.flag, -6);
  EXPECT_EQ(r.iterations, 7);
  EXPECT_EQ(r.message.rfind("KIN_MAXITER_REACHED: 7 iterations, |F|=", 0), 0u) << r.message;
  EXPECT_GE(r.residual_norm, 1.0);
}

// f(x) = x^2: Newton halves x, so the residual falls by 4 per iteration (1/4^k from x = 1). With
// the Jacobian frozen below 1e-3 and a budget of 5 iterations, exact Newton reaches 1e-3 with its
// last iteration (4^-5 = 9.8e-4): that is convergence to the freezing threshold only, and the
// solve must say it ran out of iterations, not that it converged (a capped cold attempt of CCsub
// was returned as converged at 5e-4 and its caller never tried the loading path).
class DoubleRoot : public tdcr::bvp::ResidualSystem {
 public:
  int size() const override { return 1; }
  bool residual(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> f) override {
    f[0] = x[0] * x[0];
    return true;
  }
};

TEST(BvpNewton, BudgetEndingAtTheFreezingThresholdIsNotConvergence) {
  DoubleRoot sys;
  NewtonSolver solver;
  Eigen::VectorXd x(1);
  x << 1.0;
  NewtonOptions o;
  o.line_search = false;
  o.function_tolerance = 1e-10;
  o.freeze_jacobian_below = 1e-3;
  o.max_iterations = 5;
  const auto r = solver.solve(sys, x, o);
  EXPECT_EQ(r.termination, TerminationType::MaxIterations) << r.message;
  EXPECT_EQ(r.iterations, 5);
  EXPECT_GT(r.residual_norm, o.function_tolerance);
  EXPECT_LE(r.residual_norm, 1e-3);
  // With room for the frozen iterations it converges.
  x << 1.0;
  o.max_iterations = 60;
  const auto ok = solver.solve(sys, x, o);
  EXPECT_EQ(ok.termination, TerminationType::Converged) << ok.message;
  EXPECT_LE(ok.residual_norm, o.function_tolerance);
}

TEST(BvpNewton, ResidualFailureAtInitialGuess) {
  Fragile sys(0.0, false);
  NewtonSolver solver;
  Eigen::VectorXd x(1);
  x << 2.0;
  const auto r = solver.solve(sys, x);
  EXPECT_EQ(r.termination, TerminationType::IntegrationFailed) << r.message;
  EXPECT_NE(r.message.find("KIN_FIRST_SYSFUNC_ERR"), std::string::npos) << r.message;
  EXPECT_TRUE(std::isinf(r.residual_norm));
}

TEST(BvpNewton, NaNResidualAtInitialGuess) {
  Fragile sys(0.0, true);
  NewtonSolver solver;
  Eigen::VectorXd x(1);
  x << 2.0;
  const auto r = solver.solve(sys, x);
  EXPECT_EQ(r.termination, TerminationType::NonFiniteResidual) << r.message;
  EXPECT_NE(r.message.find("KIN_FIRST_SYSFUNC_ERR"), std::string::npos) << r.message;
}

TEST(BvpNewton, RecoverableFailureDuringIterationShortensTheStep) {
  // From x = -1 the full Newton step on atan(x - 1) lands at x = 6.5, beyond the limit 3 where
  // F cannot be evaluated; KINSOL must treat that as recoverable and still reach the root.
  for (bool nan : {false, true}) {
    Fragile sys(3.0, nan);
    NewtonSolver solver;
    Eigen::VectorXd x(1);
    x << -1.0;
    const auto r = solver.solve(sys, x);
    EXPECT_TRUE(r.converged()) << "nan=" << nan << ": " << r.message;
    EXPECT_NEAR(x[0], 1.0, 1e-10);
  }
}

TEST(BvpNewton, ExceptionInResidualPropagatesAndSolverStaysUsable) {
  Throwing bad;
  NewtonSolver solver;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(2);
  EXPECT_THROW(solver.solve(bad, x), std::runtime_error);
  Rosenbrock good;
  x.setZero();
  EXPECT_TRUE(solver.solve(good, x).converged());
}

TEST(BvpNewton, ReusedSolverWarmStartIsCheapAndDoesNotRebuild) {
  const int n = 300;
  Bratu sys(n, 1.0, true);
  NewtonSolver solver;
  Eigen::VectorXd u = Eigen::VectorXd::Zero(n);
  const auto r1 = solver.solve(sys, u);
  ASSERT_TRUE(r1.converged()) << r1.message;
  EXPECT_EQ(solver.rebuilds(), 1);
  const Eigen::VectorXd u1 = u;

  // Same structure, slightly different parameter, warm start: same workspace, fewer iterations.
  sys.lambda = 1.05;
  const auto r2 = solver.solve(sys, u);
  ASSERT_TRUE(r2.converged()) << r2.message;
  EXPECT_EQ(solver.rebuilds(), 1);
  EXPECT_LT(r2.iterations, r1.iterations);
  EXPECT_GT(u.maxCoeff(), u1.maxCoeff());  // more load, larger deflection

  // Solving the first problem again from scratch reproduces the first answer exactly.
  sys.lambda = 1.0;
  u.setZero();
  const auto r3 = solver.solve(sys, u);
  ASSERT_TRUE(r3.converged());
  EXPECT_EQ(r3.iterations, r1.iterations);
  EXPECT_LE((u - u1).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_EQ(solver.rebuilds(), 1);

  // A different size forces a rebuild.
  Rosenbrock small;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(2);
  EXPECT_TRUE(solver.solve(small, x).converged());
  EXPECT_EQ(solver.rebuilds(), 2);
}

TEST(BvpNewton, OptionsFromSolverOptionsAndValidation) {
  tdcr::SolverOptions so;
  so.function_tolerance = 1e-8;
  so.step_tolerance = 1e-12;
  so.max_iterations = 17;
  so.linear_solver = tdcr::LinearSolverKind::SparseKLU;
  const auto o = tdcr::detail::newton_options(so);
  EXPECT_EQ(o.function_tolerance, 1e-8);
  EXPECT_EQ(o.step_tolerance, 1e-12);
  EXPECT_EQ(o.max_iterations, 17);
  EXPECT_EQ(o.linear_solver, LinearSolverKind::SparseKLU);
  EXPECT_NO_THROW(o.validate());

  NewtonOptions bad;
  bad.function_tolerance = 0.0;
  EXPECT_THROW(bad.validate(), tdcr::InputError);
  bad = NewtonOptions();
  bad.max_iterations = 0;
  EXPECT_THROW(bad.validate(), tdcr::InputError);
  Rosenbrock sys;
  NewtonSolver solver;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(2);
  EXPECT_THROW(solver.solve(sys, x, bad), tdcr::InputError);
  Eigen::VectorXd wrong = Eigen::VectorXd::Zero(3);
  EXPECT_THROW(solver.solve(sys, wrong), std::invalid_argument);
}

TEST(BvpNewton, StepToleranceStopIsNotConvergence) {
  // A huge step tolerance stops KINSOL after the first step with KIN_STEP_LT_STPTOL while the
  // residual is still large: that must not be reported as converged.
  Bratu sys(50, 3.0, true);
  NewtonSolver solver;
  Eigen::VectorXd u = Eigen::VectorXd::Zero(50);
  NewtonOptions o;
  o.step_tolerance = 1e3;
  const auto r = solver.solve(sys, u, o);
  EXPECT_EQ(r.flag, 2);
  EXPECT_EQ(r.termination, TerminationType::NoConvergence) << r.message;
  EXPECT_GT(r.residual_norm, o.function_tolerance);
  EXPECT_EQ(r.message.rfind("KIN_STEP_LT_STPTOL", 0), 0u) << r.message;
}

TEST(BvpNewton, JacobianFailureIsReported) {
  BadJacobian sys;
  NewtonSolver solver;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(3);
  const auto r = solver.solve(sys, x);
  EXPECT_FALSE(r.converged());
  EXPECT_EQ(r.termination, TerminationType::IntegrationFailed) << r.message;
  EXPECT_NE(r.message.find("Jacobian"), std::string::npos) << r.message;
}

TEST(BvpNewton, AllocationsDoNotGrowWithIterations) {
  const int n = 300;
  Bratu sys(n, 1.0, false);  // grouped FD Jacobian on KLU
  NewtonSolver solver;
  NewtonOptions o;
  o.linear_solver = LinearSolverKind::SparseKLU;
  Eigen::VectorXd u = Eigen::VectorXd::Zero(n);
  ASSERT_TRUE(solver.solve(sys, u, o).converged());  // warm-up: builds the workspace
  const Eigen::VectorXd solution = u;

  u.setZero();
  long before = g_allocations.load();
  const auto many = solver.solve(sys, u, o);
  const long allocations_many = g_allocations.load() - before;

  u = solution * 1.001;
  before = g_allocations.load();
  const auto few = solver.solve(sys, u, o);
  const long allocations_few = g_allocations.load() - before;

  ASSERT_TRUE(many.converged() && few.converged());
  ASSERT_GT(many.iterations, few.iterations);
  EXPECT_EQ(allocations_many, allocations_few);
  EXPECT_LE(allocations_many, 8);  // the report's strings only
}

TEST(BvpNewton, RepeatedKluSolvesKeepTheSymbolicAnalysisAndMatchFreshSolvers) {
  // A trajectory: one solver, one pattern, warm starts. Only the first Jacobian is analysed
  // and factorised with pivoting; every later one is refactorised in that pivot order.
  const int n = 300;
  Bratu sys(n, 1.0, true);
  NewtonSolver solver;
  NewtonOptions o;
  o.linear_solver = LinearSolverKind::SparseKLU;
  Eigen::VectorXd u = Eigen::VectorXd::Zero(n);
  int jacobians = 0;
  for (int step = 0; step < 6; ++step) {
    sys.lambda = 1.0 + 0.05 * step;
    const Eigen::VectorXd guess = u;
    const auto r = solver.solve(sys, u, o);
    ASSERT_TRUE(r.converged()) << r.message;
    jacobians += r.jacobian_evaluations;

    NewtonSolver fresh;
    Eigen::VectorXd v = guess;
    const auto rf = fresh.solve(sys, v, o);
    ASSERT_TRUE(rf.converged()) << rf.message;
    EXPECT_EQ(rf.iterations, r.iterations);
    EXPECT_LE((u - v).cwiseAbs().maxCoeff(), 1e-12) << "step " << step;
    EXPECT_EQ(fresh.sparse_lu_statistics().symbolic_analyses, 1);
  }
  const auto st = solver.sparse_lu_statistics();
  EXPECT_EQ(st.symbolic_analyses, 1);
  EXPECT_EQ(st.factorizations, 1);
  EXPECT_EQ(st.refactorizations, jacobians - 1);
  EXPECT_EQ(st.rejected_refactorizations, 0);
  EXPECT_EQ(solver.rebuilds(), 1);

  // KLU forced on a system without a pattern (dense pattern): analysed once as well.
  NewtonSolver dense_klu;
  Rosenbrock rb;
  for (int k = 0; k < 3; ++k) {
    Eigen::VectorXd x = Eigen::VectorXd::Zero(2);
    ASSERT_TRUE(dense_klu.solve(rb, x, o).converged());
  }
  EXPECT_EQ(dense_klu.sparse_lu_statistics().symbolic_analyses, 1);
  EXPECT_EQ(dense_klu.rebuilds(), 1);
  EXPECT_EQ(NewtonSolver().sparse_lu_statistics().symbolic_analyses, 0);
}

TEST(BvpNewton, KluRefactorWithABadPivotOrderFallsBackToPivoting) {
  // [eps 1; 1 eps] makes KLU pivot off the diagonal (whichever column comes first). Reusing that
  // order on [1 d; d 1] divides by d: d = 1e-10 grows the pivots by 1e10 (rejected), d = 0 is a
  // zero pivot (refactorisation fails). Both must be refactorised with pivoting and solve.
  const Eigen::Vector2d b(1.0, 2.0);
  Eigen::Matrix2d a1;
  a1 << 1e-8, 1.0, 1.0, 1e-8;
  SparseLinear sys(a1, b, true);
  NewtonSolver solver;
  NewtonOptions o;
  o.linear_solver = LinearSolverKind::SparseKLU;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(2);
  ASSERT_TRUE(solver.solve(sys, x, o).converged());
  EXPECT_LE((a1 * x - b).cwiseAbs().maxCoeff(), 1e-12);

  for (double d : {1e-10, 0.0}) {
    // Re-establish the off-diagonal order (itself a rejected refactorisation after d = 1e-10:
    // the diagonal order divides by 1e-8 there).
    sys.A << 1e-8, 1.0, 1.0, 1e-8;
    x.setZero();
    ASSERT_TRUE(solver.solve(sys, x, o).converged());
    const auto before = solver.sparse_lu_statistics();
    sys.A << 1.0, d, d, 1.0;
    x.setZero();
    const auto r = solver.solve(sys, x, o);
    ASSERT_TRUE(r.converged()) << "d = " << d << ": " << r.message;
    EXPECT_LE((x - sys.A.partialPivLu().solve(b)).cwiseAbs().maxCoeff(), 1e-14) << "d = " << d;
    const auto after = solver.sparse_lu_statistics();
    EXPECT_EQ(after.rejected_refactorizations, before.rejected_refactorizations + 1) << "d = " << d;
    EXPECT_EQ(after.factorizations, before.factorizations + 1) << "d = " << d;
  }
  EXPECT_EQ(solver.sparse_lu_statistics().symbolic_analyses, 1);
}

TEST(BvpNewton, KluAnalysesEachOfItsLastTwoPatternsOnce) {
  Eigen::Matrix3d a;
  a << 4.0, 1.0, 0.0,  //
      1.0, 5.0, 2.0,   //
      0.0, 2.0, 6.0;
  const Eigen::Vector3d b(1.0, -2.0, 3.0);
  const Eigen::Vector3d exact = a.lu().solve(b);
  SparseLinear sys(a, b, false);
  NewtonSolver solver;
  NewtonOptions o;
  o.linear_solver = LinearSolverKind::SparseKLU;
  int analyses = 0;
  // Two patterns alternating (as a loading path's corrector and its natural solve): each is
  // analysed once, on first use (SparseLu keeps kPatternSlots = 2 analyses).
  for (bool full : {false, false, true, true, false, true}) {
    sys.set_pattern(full);
    if (analyses == 0 || (full && analyses == 1)) ++analyses;
    Eigen::VectorXd x = Eigen::VectorXd::Zero(3);
    const auto r = solver.solve(sys, x, o);
    ASSERT_TRUE(r.converged()) << r.message;
    EXPECT_LE((x - exact).cwiseAbs().maxCoeff(), 1e-14);
    EXPECT_EQ(solver.sparse_lu_statistics().symbolic_analyses, analyses) << "full = " << full;
  }
  EXPECT_EQ(analyses, 2);
  EXPECT_EQ(solver.rebuilds(), 1);  // a new pattern re-sizes the matrix, nothing else
}

// Systems of two sizes alternating (a loading path's bordered corrector, n + 1 unknowns, and its
// natural solve, n): the SUNDIALS objects are rebuilt at every size change, the KLU analyses are
// not (they belong to the workspace, not to the SUNDIALS linear solver).
TEST(BvpNewton, RebuildsForAnotherSizeKeepTheKluAnalyses) {
  Eigen::MatrixXd a3(3, 3), a4 = Eigen::MatrixXd::Zero(4, 4);
  a3 << 4.0, 1.0, 0.0,  //
      1.0, 5.0, 2.0,    //
      0.0, 2.0, 6.0;
  a4.topLeftCorner(3, 3) = a3;
  a4(3, 3) = 2.0;
  a4(0, 3) = a4(3, 0) = 1.0;
  SparseLinear small(a3, Eigen::Vector3d(1.0, -2.0, 3.0), false);
  SparseLinear large(a4, Eigen::Vector4d(1.0, -2.0, 3.0, 0.5), false);
  NewtonSolver solver;
  NewtonOptions o;
  o.linear_solver = LinearSolverKind::SparseKLU;
  for (int round = 0; round < 3; ++round)
    for (SparseLinear* sys : {&small, &large}) {
      Eigen::VectorXd x = Eigen::VectorXd::Zero(sys->size());
      const auto r = solver.solve(*sys, x, o);
      ASSERT_TRUE(r.converged()) << r.message;
      EXPECT_LE((x - sys->A.lu().solve(sys->b)).cwiseAbs().maxCoeff(), 1e-14);
    }
  EXPECT_EQ(solver.rebuilds(), 6);
  EXPECT_EQ(solver.sparse_lu_statistics().symbolic_analyses, 2);
  EXPECT_EQ(solver.sparse_lu_statistics().factorizations, 2);
  EXPECT_EQ(solver.sparse_lu_statistics().refactorizations, 4);
}

// A well-conditioned nonlinear system with the root r = (1, 0.5, -0.3): f_i(x) = g_i(x) - g_i(r),
// g_i = x_i^3 + x_i + 0.5 sin(x_{i+1}) (cyclic); Jacobian 1 + 3 x_i^2 on the diagonal.
class Cubic3 : public tdcr::bvp::ResidualSystem {
 public:
  int size() const override { return 3; }
  static double g(const Eigen::Ref<const Eigen::VectorXd>& x, int i) {
    return x[i] * x[i] * x[i] + x[i] + 0.5 * std::sin(x[(i + 1) % 3]);
  }
  bool residual(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> f) override {
    const Eigen::Vector3d r = root();
    for (int i = 0; i < 3; ++i) f[i] = g(x, i) - g(r, i);
    return true;
  }
  static Eigen::Vector3d root() { return Eigen::Vector3d(1.0, 0.5, -0.3); }
};

// NewtonOptions::freeze_jacobian_below: exact Newton down to the threshold, then modified Newton
// from the last Jacobian. From a far start: the same root, fewer Jacobians, a residual below the
// full tolerance.
TEST(BvpNewton, FrozenJacobianBelowAThresholdSavesJacobiansAndReachesTheSameRoot) {
  Cubic3 sys;
  NewtonSolver exact_solver, frozen_solver;
  const Eigen::VectorXd start = Eigen::Vector3d(3.0, -2.0, 2.5);
  Eigen::VectorXd xe = start, xf = start;
  NewtonOptions o;
  const auto exact = exact_solver.solve(sys, xe, o);
  o.freeze_jacobian_below = 1e-3;
  const auto frozen = frozen_solver.solve(sys, xf, o);
  ASSERT_TRUE(exact.converged() && frozen.converged()) << exact.message << " / " << frozen.message;
  EXPECT_LT(frozen.jacobian_evaluations, exact.jacobian_evaluations);
  EXPECT_GT(frozen.iterations, exact.iterations);  // cheap iterations instead of Jacobians
  EXPECT_EQ(frozen.message.find("exact Newton after"), std::string::npos) << frozen.message;
  EXPECT_LE(frozen.residual_norm, 1e-10);
  EXPECT_LE((xe - Cubic3::root()).norm(), 1e-10);
  EXPECT_LE((xf - Cubic3::root()).norm(), 1e-10);
  // Freezing at a threshold the first residual already meets: KINSOL's own initial-guess test
  // (0.01 x tolerance) still decides, so a start 1e-9 off is iterated to the root, not kept.
  Eigen::VectorXd near = Cubic3::root() + Eigen::Vector3d(0.0, 0.0, 1e-9);
  const auto r = frozen_solver.solve(sys, near, o);
  ASSERT_TRUE(r.converged()) << r.message;
  EXPECT_LE((near - Cubic3::root()).norm(), 1e-12);
  // Validation: 0 (off) or above the tolerance.
  NewtonOptions bad;
  bad.freeze_jacobian_below = 1e-12;  // below function_tolerance
  EXPECT_THROW(bad.validate(), tdcr::InputError);
  bad.freeze_jacobian_below = -1.0;
  EXPECT_THROW(bad.validate(), tdcr::InputError);
  bad.freeze_jacobian_below = std::nan("");
  EXPECT_THROW(bad.validate(), tdcr::InputError);
}

// A frozen Jacobian that contracts too slowly (Dense3 has a nearly singular root: exact Newton
// itself needs 20 iterations from zero) hands the solve back to exact Newton, which converges.
TEST(BvpNewton, FrozenJacobianThatStallsFallsBackToExactNewton) {
  Dense3 sys;
  NewtonSolver solver;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(3);
  NewtonOptions o;
  o.freeze_jacobian_below = 1e-2;
  const auto r = solver.solve(sys, x, o);
  ASSERT_TRUE(r.converged()) << r.message;
  EXPECT_NE(r.message.find("exact Newton after"), std::string::npos) << r.message;
  Eigen::VectorXd f(3);
  sys.residual(x, f);
  EXPECT_LE(f.cwiseAbs().maxCoeff(), 1e-10);
}
