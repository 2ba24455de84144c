// Fixed-step RK4 and CVODE on ODEs with known solutions.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <new>

#include "allocation_counter.hpp"
#include "solve/bvp_options.hpp"
#include "tdcr/bvp/integrator.hpp"
#include "tdcr/core/error.hpp"

using tdcr::bvp::CvodeIntegrator;
using tdcr::bvp::Rk4Integrator;



namespace {

// q' = p, p' = -w^2 q: y = (cos w s, -w sin w s) from (1, 0).
class Oscillator : public tdcr::bvp::OdeSystem {
 public:
  explicit Oscillator(double w) : w_(w) {}
  int dimension() const override { return 2; }
  void rhs(double, const double* y, double* d) const override {
    d[0] = y[1];
    d[1] = -w_ * w_ * y[0];
  }
  double q(double s) const { return std::cos(w_ * s); }
  double p(double s) const { return -w_ * std::sin(w_ * s); }

 private:
  double w_;
};

// Non-autonomous: y' = cos(s) y, y = exp(sin s) from y(0) = 1. Catches a wrong stage s.
class NonAutonomous : public tdcr::bvp::OdeSystem {
 public:
  int dimension() const override { return 1; }
  void rhs(double s, const double* y, double* d) const override { d[0] = std::cos(s) * y[0]; }
};

// 3-D rotation about a fixed axis: y' = w x y, a norm-preserving linear system.
class Rotation : public tdcr::bvp::OdeSystem {
 public:
  int dimension() const override { return 3; }
  void rhs(double, const double* y, double* d) const override {
    const double w[3] = {0.3, -0.5, 0.8};
    d[0] = w[1] * y[2] - w[2] * y[1];
    d[1] = w[2] * y[0] - w[0] * y[2];
    d[2] = w[0] * y[1] - w[1] * y[0];
  }
};

class Blowup : public tdcr::bvp::OdeSystem {
 public:
  int dimension() const override { return 1; }
  void rhs(double s, const double*, double* d) const override {
    d[0] = s > 0.5 ? std::numeric_limits<double>::quiet_NaN() : 1.0;
  }
};

double rk4_oscillator_error(int steps) {
  Oscillator osc(3.0);
  Rk4Integrator rk(steps);
  double y[2] = {1.0, 0.0};
  EXPECT_TRUE(rk.integrate(osc, 0.0, 2.0, y));
  return std::hypot(y[0] - osc.q(2.0), y[1] - osc.p(2.0));
}

}  // namespace

TEST(BvpIntegrator, Rk4ErrorFallsAsHToTheFourth) {
  const double e1 = rk4_oscillator_error(40);
  const double e2 = rk4_oscillator_error(80);
  const double e3 = rk4_oscillator_error(160);
  EXPECT_GT(e1 / e2, 12.0);
  EXPECT_LT(e1 / e2, 20.0);
  EXPECT_GT(e2 / e3, 12.0);
  EXPECT_LT(e2 / e3, 20.0);
  EXPECT_LT(e3, 1e-6);
}

TEST(BvpIntegrator, Rk4NonAutonomousOrderAndCounts) {
  NonAutonomous sys;
  auto err = [&](int steps) {
    Rk4Integrator rk(steps);
    double y = 1.0;
    EXPECT_TRUE(rk.integrate(sys, 0.0, 3.0, &y));
    EXPECT_EQ(rk.rhs_evaluations(), 4 * steps);
    return std::abs(y - std::exp(std::sin(3.0)));
  };
  const double ratio = err(20) / err(40);
  EXPECT_GT(ratio, 12.0);
  EXPECT_LT(ratio, 20.0);
}

TEST(BvpIntegrator, Rk4MaxStepBoundsTheStepLength) {
  // 2 steps minimum, 0.1 longest: [0, 2] takes 20 steps and is as accurate as Rk4Integrator(20);
  // [0, 0.1] keeps the minimum of 2 steps.
  Oscillator osc(3.0);
  Rk4Integrator bounded(2, 0.1), fixed(20);
  double a[2] = {1.0, 0.0}, b[2] = {1.0, 0.0};
  ASSERT_TRUE(bounded.integrate(osc, 0.0, 2.0, a));
  ASSERT_TRUE(fixed.integrate(osc, 0.0, 2.0, b));
  EXPECT_EQ(bounded.rhs_evaluations(), 4 * 20);
  EXPECT_EQ(a[0], b[0]);
  EXPECT_EQ(a[1], b[1]);
  double c[2] = {1.0, 0.0};
  ASSERT_TRUE(bounded.integrate(osc, 0.0, 0.1, c));
  EXPECT_EQ(bounded.rhs_evaluations(), 4 * 22);
  EXPECT_THROW(Rk4Integrator(2, 0.0), tdcr::InputError);
}

TEST(BvpIntegrator, Rk4AllocatesNothingOnceWarm) {
  Rotation sys;
  Rk4Integrator rk(16);
  double y[3] = {1.0, 0.0, 0.0};
  ASSERT_TRUE(rk.integrate(sys, 0.0, 0.1, y));  // first call sizes the stage buffers
  const long before = g_allocations.load();
  for (int k = 0; k < 100; ++k) rk.integrate(sys, 0.1 * k, 0.1 * (k + 1), y);
  EXPECT_EQ(g_allocations.load() - before, 0);
}

TEST(BvpIntegrator, Rk4BackwardReturnsToStart) {
  Rotation sys;
  Rk4Integrator rk(50);
  double y[3] = {1.0, 2.0, -0.5};
  ASSERT_TRUE(rk.integrate(sys, 0.0, 1.0, y));
  const double norm = std::sqrt(y[0] * y[0] + y[1] * y[1] + y[2] * y[2]);
  EXPECT_NEAR(norm, std::sqrt(5.25), 1e-9);  // rotation preserves the norm
  ASSERT_TRUE(rk.integrate(sys, 1.0, 0.0, y));
  EXPECT_NEAR(y[0], 1.0, 1e-9);
  EXPECT_NEAR(y[1], 2.0, 1e-9);
  EXPECT_NEAR(y[2], -0.5, 1e-9);
}

TEST(BvpIntegrator, Rk4ReportsNonFiniteState) {
  Blowup sys;
  Rk4Integrator rk(10);
  double y = 0.0;
  EXPECT_FALSE(rk.integrate(sys, 0.0, 1.0, &y));
  EXPECT_FALSE(rk.last_error().empty());
  EXPECT_THROW(Rk4Integrator(0), tdcr::InputError);
}

TEST(BvpIntegrator, CvodeWithinTolerance) {
  Oscillator osc(3.0);
  CvodeIntegrator cv(1e-10, 1e-12);
  double y[2] = {1.0, 0.0};
  ASSERT_TRUE(cv.integrate(osc, 0.0, 2.0, y)) << cv.last_error();
  // Local error control at rtol 1e-10 keeps the global error within a small multiple of it
  // over a few periods (|y| ~ 3).
  EXPECT_LT(std::hypot(y[0] - osc.q(2.0), y[1] - osc.p(2.0)), 1e-8);
  EXPECT_GT(cv.rhs_evaluations(), 0);
  EXPECT_GT(cv.steps_taken(), 0);
  EXPECT_EQ(cv.name(), "cvode");
}

TEST(BvpIntegrator, CvodeReusedAcrossCallsAndDirections) {
  NonAutonomous sys;
  CvodeIntegrator cv(1e-10, 1e-12);
  // Chained intervals (as in multiple shooting): ReInit at every call.
  double y = 1.0;
  for (int k = 0; k < 6; ++k) ASSERT_TRUE(cv.integrate(sys, 0.5 * k, 0.5 * (k + 1), &y));
  EXPECT_NEAR(y, std::exp(std::sin(3.0)), 1e-8);
  // Backwards to the start.
  ASSERT_TRUE(cv.integrate(sys, 3.0, 0.0, &y));
  EXPECT_NEAR(y, 1.0, 1e-8);
  // Same call twice gives the same answer (no state leaks between calls).
  double a = 1.0, b = 1.0;
  ASSERT_TRUE(cv.integrate(sys, 0.0, 1.0, &a));
  ASSERT_TRUE(cv.integrate(sys, 0.0, 1.0, &b));
  EXPECT_EQ(a, b);
  // A different dimension rebuilds transparently.
  Rotation rot;
  double r[3] = {1.0, 2.0, -0.5};
  ASSERT_TRUE(cv.integrate(rot, 0.0, 1.0, r));
  EXPECT_NEAR(r[0] * r[0] + r[1] * r[1] + r[2] * r[2], 5.25, 1e-7);
  // Empty interval: nothing to do.
  double z = 4.0;
  EXPECT_TRUE(cv.integrate(sys, 1.0, 1.0, &z));
  EXPECT_EQ(z, 4.0);
}

TEST(BvpIntegrator, CvodeFailureIsReportedNotPrinted) {
  Blowup sys;
  CvodeIntegrator cv(1e-8, 1e-10, 500);
  double y = 0.0;
  EXPECT_FALSE(cv.integrate(sys, 0.0, 1.0, &y));
  EXPECT_EQ(cv.last_error().rfind("CV_", 0), 0u) << cv.last_error();
  // Still usable afterwards.
  Oscillator osc(1.0);
  double q[2] = {1.0, 0.0};
  EXPECT_TRUE(cv.integrate(osc, 0.0, 1.0, q)) << cv.last_error();
  EXPECT_NEAR(q[0], std::cos(1.0), 1e-6);
}

TEST(BvpIntegrator, MakeIntegratorFollowsOptions) {
  tdcr::SolverOptions o;
  o.integrator = tdcr::IntegratorKind::FixedStepRK4;
  o.rk4_steps = 12;
  auto a = tdcr::bvp::make_integrator(tdcr::detail::integrator_options(o));
  EXPECT_EQ(a->name(), "rk4");
  EXPECT_EQ(dynamic_cast<Rk4Integrator&>(*a).steps(), 12);
  o.integrator = tdcr::IntegratorKind::Cvode;
  auto b = tdcr::bvp::make_integrator(tdcr::detail::integrator_options(o));
  EXPECT_EQ(b->name(), "cvode");
  Oscillator osc(2.0);
  double y[2] = {1.0, 0.0};
  ASSERT_TRUE(b->integrate(osc, 0.0, 1.0, y));
  EXPECT_NEAR(y[0], osc.q(1.0), 1e-6);
}
