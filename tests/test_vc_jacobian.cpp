// VC single shooting's exact Jacobian (models/vc/vc_jacobian.cpp: dual numbers through the RK4
// steps, disk point loads and kink fixed points) against central differences of the shooting
// residual, on loaded cases with and without kinks, with and without shear/extension and gravity.
// CVODE keeps forward differences (the exact Jacobian is the derivative of the discrete RK4 map).
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tdcr/bvp/residual_system.hpp"
#include "tdcr/core/paper_robot.hpp"
#include "tdcr/models/vc.hpp"
#include "vc/vc_shooting.hpp"

using namespace tdcr;

namespace {

struct Case {
  std::string name;
  Scene scene;
  VcOptions options;
};

Scene paper_loaded(std::vector<double> tensions_in_tm, const Vec3& tip_force) {
  Scene s = paper::scene(10, 1, "vc");
  const double tm = paper::max_tension(s.robot);
  for (double& t : tensions_in_tm) t *= tm;
  s.actuation.values = tensions_in_tm;
  s.loads.tip_force = tip_force;
  return s;
}

std::vector<Case> cases() {
  VcOptions exact;
  exact.exact_jacobian = true;
  std::vector<Case> c;
  c.push_back({"kinks", paper_loaded({0.3, 0.0, 0.5, 0.1}, Vec3(0.2, -0.3, 0.1)), exact});
  VcOptions no_kinks = exact;
  no_kinks.kink_forces = false;
  c.push_back({"no kinks", paper_loaded({0.3, 0.0, 0.5, 0.1}, Vec3(0.2, -0.3, 0.1)), no_kinks});
  Scene k = paper_loaded({0.0, 0.6, 0.2, 0.0}, Vec3(-0.1, 0.4, 0.0));
  k.effects.shear_extension = false;
  k.loads.tip_moment = Vec3(0.002, 0.0, -0.001);
  c.push_back({"kirchhoff, tip moment", k, exact});
  Scene g = paper_loaded({0.5, 0.0, 0.0, 0.3}, Vec3(0.0, 0.1, 0.0));
  g.loads.gravity = Vec3(0.0, -9.81, 0.0);
  for (Segment& seg : g.robot.segments) seg.disk_mass = 2e-4;
  c.push_back({"gravity, disk weights", g, exact});
  c.push_back({"tendons only", paper_loaded({1.0, 0.0, 0.0, 0.0}, Vec3::Zero()), exact});
  return c;
}

// The shooting system of a bound workspace, at the solution and off it.
struct Bound {
  VcModel model;
  std::unique_ptr<ModelWorkspace> ws;
  std::unique_ptr<detail::ModelProblem> problem;
  Bound(const Case& c) : model(c.scene.robot, c.scene.effects, c.options), ws(model.make_workspace()) {
    VcWorkspace::Impl& W = static_cast<VcWorkspace&>(*ws).impl();
    vc::bind_input(W, model, c.scene.input(), c.scene.solver);
    problem = vc::make_single_shooting(W);
    problem->system()->set_parameter(1.0);
  }
};

}  // namespace

// Exact Jacobian = central differences (about 1e-10 here) to 1e-8, at the solution and
// at points off it; its residual is the shot's, bit for bit up to rounding.
TEST(VcJacobian, MatchesCentralDifferences) {
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.name);
    const Solution sol = [&] {
      VcModel m(c.scene.robot, c.scene.effects, c.options);
      auto ws = m.make_workspace();
      return solve(m, *ws, c.scene.input(), c.scene.solver);
    }();
    ASSERT_TRUE(sol.converged()) << sol.summary.message;
    ASSERT_EQ(sol.unknowns.size(), 6);
    Bound b(c);
    bvp::ParameterizedSystem& sys = *b.problem->system();
    ASSERT_TRUE(sys.has_jacobian());
    Eigen::VectorXd scale(6);
    sys.unknown_scale(scale);
    for (double offset : {0.0, 0.05, -0.2}) {
      SCOPED_TRACE(offset);
      Eigen::VectorXd x = sol.unknowns;
      for (int i = 0; i < 6; ++i) x[i] += offset * (i % 2 ? -1.0 : 1.0) * (1.0 + 0.3 * i) / scale[i];
      const bvp::JacobianCheck check = bvp::check_jacobian(sys, x);
      ASSERT_TRUE(check.evaluated);
      // Compared in Newton's scaling (forces and moments, unknowns and residuals in the units
      // of the solver): the central differences' rounding, about 1e-9 of the largest scaled
      // entry, would dominate entries in mixed units.
      Eigen::VectorXd fs(6);
      sys.residual_scale(fs);
      const Eigen::MatrixXd Ja = fs.asDiagonal() * check.analytic * scale.cwiseInverse().asDiagonal();
      const Eigen::MatrixXd Jn = fs.asDiagonal() * check.numeric * scale.cwiseInverse().asDiagonal();
      const double error = (Ja - Jn).cwiseAbs().maxCoeff() / Ja.cwiseAbs().maxCoeff();
      EXPECT_LT(error, 1e-8) << "scaled analytic\n" << Ja << "\nscaled numeric\n" << Jn;
      // The dual shot's values are the residual.
      Eigen::VectorXd f(6);
      ASSERT_TRUE(sys.residual(x, f));
      VcWorkspace::Impl& W = static_cast<VcWorkspace&>(*b.ws).impl();
      vc::Vec6 r;
      vc::Mat6 J;
      ASSERT_TRUE(vc::shoot_jacobian(W, vc::Vec6(x), r, J));
      EXPECT_LE((r - f).norm(), 1e-12 * (1.0 + f.norm()));
    }
  }
}

// With CVODE the residual is only piecewise smooth in the unknowns: no exact Jacobian, the
// solver differentiates it (and the loaded case still converges).
TEST(VcJacobian, CvodeKeepsFiniteDifferences) {
  Case c = cases().front();
  c.scene.solver.integrator = IntegratorKind::Cvode;
  Bound b(c);
  EXPECT_FALSE(b.problem->system()->has_jacobian());
  VcModel m(c.scene.robot, c.scene.effects);
  auto ws = m.make_workspace();
  const Solution cv = solve(m, *ws, c.scene.input(), c.scene.solver);
  ASSERT_TRUE(cv.converged()) << cv.summary.message;
  Case r = cases().front();
  const Solution rk = solve(m, *ws, r.scene.input(), r.scene.solver);
  ASSERT_TRUE(rk.converged()) << rk.summary.message;
  EXPECT_LT((cv.tip().p - rk.tip().p).norm(), 1e-6);
}

// Snap landings damp VC in multiple shooting (single shooting cannot): set_damping adds to the
// force and moment rows of each inner disk's junction the viscous wrench -rate (F_s / L) (p - p_ref)
// and -rate F_s L R_ref w, w the rotation from the reference (its skew part), and nothing
// elsewhere; rate 0 removes it.
TEST(VcMultipleShooting, DampingAddsTheViscousWrenchAtInnerDisksOnly) {
  const Scene s = paper_loaded({0.3, 0.0, 0.5, 0.1}, Vec3(0.2, -0.3, 0.1));
  VcOptions o;
  o.formulation = VcFormulation::MultipleShooting;
  const VcModel model(s.robot, s.effects, o);
  auto ws = model.make_workspace();
  const Solution sol = solve(model, *ws, s.input(), s.solver);
  ASSERT_TRUE(sol.converged()) << sol.summary.message;
  ASSERT_TRUE(static_cast<VcWorkspace&>(*ws).impl().multiple);  // bound to s's input by the solve
  detail::ModelProblem& P = *static_cast<VcWorkspace&>(*ws).impl().multiple;
  bvp::ParameterizedSystem& sys = *P.system();
  sys.set_parameter(1.0);
  const int n = sys.size();
  constexpr int kDim = 18;
  ASSERT_EQ(n % kDim, 0);
  const Eigen::VectorXd x_ref = sol.unknowns;
  ASSERT_EQ(x_ref.size(), n);
  // Node 3 moved by dp, node 5 turned by a small angle about its own z axis.
  const Vec3 dp(1e-4, -2e-4, 5e-5);
  const double angle = 1e-3;
  Eigen::VectorXd x = x_ref;
  x.segment<3>(3 * kDim) += dp;
  Eigen::Map<Mat3> R5(x.data() + 5 * kDim + 3);
  const Mat3 R5_ref = R5;
  R5 = R5_ref * Eigen::AngleAxisd(angle, Vec3::UnitZ()).toRotationMatrix();
  Eigen::VectorXd f0(n), f(n), scale(n);
  ASSERT_TRUE(sys.residual(x, f0));
  sys.residual_scale(scale);
  const double rate = 2.0, Fs = 1.0 / scale[3 * kDim + 12], L = s.robot.total_length();
  ASSERT_TRUE(sys.set_damping(x_ref, rate));
  ASSERT_TRUE(sys.residual(x, f));
  Eigen::VectorXd expected = Eigen::VectorXd::Zero(n);
  expected.segment<3>(3 * kDim + 12) = -rate * (Fs / L) * dp;
  expected.segment<3>(5 * kDim + 15) = -rate * (Fs * L) * (R5_ref * Vec3(0.0, 0.0, std::sin(angle)));
  EXPECT_LT((f - f0 - expected).norm(), 1e-9 * expected.norm()) << (f - f0 - expected).transpose();
  ASSERT_TRUE(sys.set_damping(x_ref, 0.0));
  ASSERT_TRUE(sys.residual(x, f));
  EXPECT_EQ((f - f0).norm(), 0.0);
}
