// bvp::continuation: natural-parameter continuation with adaptive steps.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "solve/bvp_options.hpp"
#include "tdcr/bvp/continuation.hpp"
#include "tdcr/core/error.hpp"

using tdcr::bvp::ContinuationOptions;
using tdcr::bvp::ContinuationResult;
using tdcr::bvp::ContinuationStatus;
using tdcr::bvp::NewtonOptions;
using tdcr::bvp::NewtonSolver;

namespace {

// A planar chain of n links of length h = 1/n (a discrete elastica) clamped at the base, with
// absolute link angles theta_i (from the y axis) and rotational springs k = 1 between
// consecutive links, loaded at the tip by a moment lambda M0 and a force lambda P along +x
// (fixed direction). Residual of joint i: spring moment k (theta_i - theta_{i-1}) minus the
// moment of the tip load about joint i. With P = 0 it is linear, theta_i = i lambda M0 / k.
// A large moment coils the chain beyond 2 pi; with P > 0 Newton from the straight chain can
// then stall, while continuation follows the loading path.
class Chain : public tdcr::bvp::ParameterizedSystem {
 public:
  Chain(int n, double moment, double force) : n_(n), M0_(moment), P_(force) {}
  int size() const override { return n_; }
  void set_parameter(double lambda) override {
    lambda_ = lambda;
    ++parameter_sets;
  }
  void accept_step(Eigen::VectorXd&) override { ++accepted; }
  bool residual(const Eigen::Ref<const Eigen::VectorXd>& th, Eigen::Ref<Eigen::VectorXd> f) override {
    // Tip load: moment lambda M0 and force lambda P along +x; link i spans joint i to i+1.
    const double h = 1.0 / n_;
    for (int i = n_ - 1; i >= 0; --i) {
      const double prev = i == 0 ? 0.0 : th[i - 1];
      // Moment about joint i (z): M0 + (r x F)_z with r = (x, y), F = (P, 0): -y P.
      double y = 0.0;
      for (int k = i; k < n_; ++k) y += h * std::cos(th[k]);
      f[i] = k_ * (th[i] - prev) - lambda_ * (M0_ - y * P_);
    }
    return f.allFinite();
  }
  int parameter_sets = 0;
  int accepted = 0;

 private:
  int n_;
  double M0_, P_;
  double k_ = 1.0;
  double lambda_ = 1.0;
};

// Bratu u'' + lambda e^u = 0 on (0, 1), u(0) = u(1) = 0, central differences scaled by h^2.
// The lower branch starts at u = 0 for lambda = 0 and ends in a fold at lambda* = 3.5138:
// no solution exists beyond it, so continuation towards lambda = 5 must stall just below.
class Bratu : public tdcr::bvp::ParameterizedSystem {
 public:
  explicit Bratu(int n) : n_(n), h_(1.0 / (n + 1)) {}
  int size() const override { return n_; }
  void set_parameter(double lambda) override { lambda_ = lambda; }
  bool residual(const Eigen::Ref<const Eigen::VectorXd>& u, Eigen::Ref<Eigen::VectorXd> f) override {
    for (int i = 0; i < n_; ++i) {
      const double left = i > 0 ? u[i - 1] : 0.0, right = i + 1 < n_ ? u[i + 1] : 0.0;
      f[i] = left - 2.0 * u[i] + right + h_ * h_ * lambda_ * std::exp(u[i]);
    }
    return f.allFinite();
  }

 private:
  int n_;
  double h_;
  double lambda_ = 0.0;
};

}  // namespace


namespace {
// max_i |F_i(x)| of a system at its current parameter.
double residual_max(tdcr::bvp::ResidualSystem& s, const Eigen::VectorXd& x) {
  Eigen::VectorXd f(s.size());
  if (!s.residual(x, f)) return INFINITY;
  return f.cwiseAbs().maxCoeff();
}
}  // namespace

// The chain under a pure tip moment is linear (theta_i = i lambda M0 / k): whatever the load,
// one Newton iteration per step; the step doubles after each success (0.25, +0.5, then the
// remaining 0.25 fits in the next step of 1): exactly 3 solves, answer exact.
TEST(BvpContinuation, StepsGrowAfterSuccessAndAnswerIsExact) {
  Chain c(10, 6.0, 0.0);
  NewtonSolver newton;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(10);
  const ContinuationResult r = tdcr::bvp::continuation(newton, c, x, NewtonOptions());
  ASSERT_TRUE(r.converged()) << r.message;
  EXPECT_EQ(r.status, ContinuationStatus::Reached);
  EXPECT_EQ(r.steps, 3);
  EXPECT_EQ(r.accepted_steps, 3);
  EXPECT_EQ(c.accepted, 3);  // accept_step once per converged step
  EXPECT_DOUBLE_EQ(r.parameter, 1.0);
  EXPECT_DOUBLE_EQ(r.fraction, 1.0);
  for (int i = 0; i < 10; ++i) EXPECT_NEAR(x[i], 6.0 * (i + 1), 1e-9);
}

// A coiled elastica (tip moment 6 k, transverse tip force 3 k / length): Newton from the
// straight chain at full load fails (line search stalls in a local minimum of |F|); following
// the load from 0 reaches the full load, and the answer is an equilibrium at full load.
TEST(BvpContinuation, SucceedsWhereTheDirectSolveFails) {
  Chain c(10, 6.0, 3.0);
  NewtonSolver newton;
  c.set_parameter(1.0);
  Eigen::VectorXd x0 = Eigen::VectorXd::Zero(10);
  const auto direct = newton.solve(c, x0, NewtonOptions());
  ASSERT_FALSE(direct.converged()) << "precondition: the direct solve must fail";

  Eigen::VectorXd x = Eigen::VectorXd::Zero(10);
  const ContinuationResult r = tdcr::bvp::continuation(newton, c, x, NewtonOptions());
  ASSERT_TRUE(r.converged()) << r.message;
  EXPECT_DOUBLE_EQ(r.parameter, 1.0);
  EXPECT_TRUE(r.last.converged());
  EXPECT_GE(r.iterations, r.steps);
  EXPECT_EQ(c.accepted, r.accepted_steps);
  // Independent check at the full load, outside the solver.
  c.set_parameter(1.0);
  EXPECT_LT(residual_max(c, x), 1e-9);
  // Coiled: the tip link has turned by more than a full turn (the moment alone gives 6 rad).
  EXPECT_GT(x[9], 2.0 * M_PI);
}

// Bratu's lower branch ends in a fold at lambda* = 3.513830719 (no solution beyond it).
// Continuation towards 5 must stall below the fold, report where, and leave x a solution there.
TEST(BvpContinuation, StallsAtAFoldAndReportsTheParameterReached) {
  constexpr double kFold = 3.513830719;
  Bratu b(40);
  NewtonSolver newton;
  Eigen::VectorXd u = Eigen::VectorXd::Zero(40);
  ContinuationOptions opt;
  opt.target = 5.0;
  opt.max_steps = 200;
  const ContinuationResult r = tdcr::bvp::continuation(newton, b, u, NewtonOptions(), opt);
  EXPECT_FALSE(r.converged());
  EXPECT_EQ(r.status, ContinuationStatus::Stalled) << r.message;
  EXPECT_LT(r.parameter, kFold + 1e-3);  // discretisation moves the fold by O(h^2) ~ 1e-3
  EXPECT_GT(r.parameter, 3.3);           // it got close: within ~ min_step of the fold
  EXPECT_NEAR(r.fraction, r.parameter / 5.0, 1e-15);
  EXPECT_LT(r.steps, 200);
  EXPECT_FALSE(r.last.converged());
  EXPECT_NE(r.message.find("stalled"), std::string::npos);
  // x is the converged solution at the parameter reached (the system is left there).
  EXPECT_LT(residual_max(b, u), 1e-9);
  EXPECT_TRUE(u.allFinite());

  // Below the fold the same continuation reaches its target.
  Eigen::VectorXd v = Eigen::VectorXd::Zero(40);
  opt.target = 3.0;
  const ContinuationResult ok = tdcr::bvp::continuation(newton, b, v, NewtonOptions(), opt);
  EXPECT_TRUE(ok.converged()) << ok.message;
}

// At most max_steps Newton solves: constant steps of 1 % of the way (growth 1) and a bound of
// 5 solves stop at exactly 5 % of the way, reported as StepLimit.
TEST(BvpContinuation, HonoursTheStepBound) {
  Bratu b(20);
  NewtonSolver newton;
  Eigen::VectorXd u = Eigen::VectorXd::Zero(20);
  ContinuationOptions opt;
  opt.target = 3.0;
  opt.initial_step = 0.01;
  opt.growth = 1.0;
  opt.max_steps = 5;
  const ContinuationResult r = tdcr::bvp::continuation(newton, b, u, NewtonOptions(), opt);
  EXPECT_EQ(r.status, ContinuationStatus::StepLimit);
  EXPECT_FALSE(r.converged());
  EXPECT_EQ(r.steps, 5);
  EXPECT_EQ(r.accepted_steps, 5);
  EXPECT_NEAR(r.parameter, 0.15, 1e-12);
  EXPECT_NEAR(r.fraction, 0.05, 1e-12);
  EXPECT_NE(r.message.find("limit"), std::string::npos);
  EXPECT_LT(residual_max(b, u), 1e-9);
}

// Continuation runs backwards too (start > target).
TEST(BvpContinuation, RunsDownwards) {
  Chain c(5, 2.0, 0.0);
  NewtonSolver newton;
  Eigen::VectorXd x(5);
  for (int i = 0; i < 5; ++i) x[i] = 2.0 * (i + 1) / 5.0;  // exact at lambda = 1
  ContinuationOptions opt;
  opt.start = 1.0;
  opt.target = 0.0;
  const ContinuationResult r = tdcr::bvp::continuation(newton, c, x, NewtonOptions(), opt);
  ASSERT_TRUE(r.converged()) << r.message;
  EXPECT_EQ(r.parameter, 0.0);
  EXPECT_LT(x.cwiseAbs().maxCoeff(), 1e-12);
}

TEST(BvpContinuation, RejectsBadOptions) {
  Chain c(2, 1.0, 0.0);
  NewtonSolver newton;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(2);
  auto bad = [&](auto edit) {
    ContinuationOptions o;
    edit(o);
    EXPECT_THROW(tdcr::bvp::continuation(newton, c, x, NewtonOptions(), o), tdcr::InputError);
  };
  bad([](ContinuationOptions& o) { o.target = o.start; });
  bad([](ContinuationOptions& o) { o.initial_step = 0.0; });
  bad([](ContinuationOptions& o) { o.min_step = -1.0; });
  bad([](ContinuationOptions& o) { o.growth = 0.5; });
  bad([](ContinuationOptions& o) { o.shrink = 1.0; });
  bad([](ContinuationOptions& o) { o.max_steps = 0; });
  tdcr::SolverOptions so;
  so.max_continuation_steps = 7;
  EXPECT_EQ(tdcr::detail::continuation_options(so).max_steps, 7);
  EXPECT_EQ(tdcr::bvp::to_string(ContinuationStatus::StepLimit), "step_limit");
}
