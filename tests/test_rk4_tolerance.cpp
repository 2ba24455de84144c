// Accuracy-driven RK4 (SolverOptions::rk4_tip_tolerance, models/common/solve_driver.cpp): VC and
// VCref refine the RK4 mesh until the Richardson estimate of the tip error is within the
// tolerance. Checked against CVODE at rtol 1e-12: the answer's tip is within the tolerance, the
// estimate is a true estimate of the error (RK4's h^4 law), the refined solve reuses the coarse
// solve's Jacobian, an unreachable tolerance is a failure that says so, bad values are rejected.
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tdcr/core/error.hpp"
#include "tdcr/core/paper_robot.hpp"
#include "tdcr/core/scene_io.hpp"
#include "tdcr/models/static_model.hpp"

using namespace tdcr;

namespace {

// Case 0 of benchmarks/data/paper_code_cases_inputs.csv: paper robot, 3 disks per segment,
// three tendons near 1.3 T_M and a tip force of 0.14 N.
Scene loaded_case() {
  Scene s = paper::scene(3, 1, "vc");
  s.actuation.values = {7.17760113103, 7.08736447216, 7.20604318256, 0.579424008131};
  s.loads.tip_force = Vec3(0.011158316017, -0.134904391563, 0.0356561453437);
  return s;
}

SolverOptions coarse(double tolerance) {
  SolverOptions o;
  o.rk4_steps = 1;
  o.rk4_max_step = 8e-3;
  o.rk4_tip_tolerance = tolerance;
  return o;
}

Solution reference(const StaticModel& model, ModelWorkspace& ws, const ModelInput& in) {
  SolverOptions o;
  o.integrator = IntegratorKind::Cvode;
  o.cvode_rtol = 1e-12;
  o.cvode_atol = 1e-14;
  o.function_tolerance = 1e-13;
  Solution s = solve(model, ws, in, o);
  EXPECT_TRUE(s.converged()) << s.summary.brief_report();
  return s;
}

class Rk4Tolerance : public ::testing::TestWithParam<ModelKind> {};

TEST_P(Rk4Tolerance, TipWithinToleranceOfCvodeAndEstimateIsTheError) {
  const Scene scene = loaded_case();
  auto model = make_model(GetParam(), scene);
  auto ws = model->make_workspace();
  const ModelInput in = scene.input();
  const Solution ref = reference(*model, *ws, in);
  for (double tol : {1e-7, 1e-8, 1e-9}) {
    const Solution s = solve(*model, *ws, in, coarse(tol));
    ASSERT_TRUE(s.converged()) << tol << ": " << s.summary.brief_report();
    const double err = (s.tip().p - ref.tip().p).norm();
    EXPECT_GE(s.summary.rk4_refinements, 1);
    EXPECT_LE(s.summary.tip_error_estimate, tol);
    EXPECT_LE(err, tol) << "tolerance " << tol;
    // Richardson on RK4's h^4 law: the estimate is the error, not just a bound (measured within
    // 10 % on the 60 loaded cases of bench_loaded; here a factor 2 either way).
    if (err > 1e-12) {
      EXPECT_LT(s.summary.tip_error_estimate, 2.0 * err) << tol;
      EXPECT_GT(s.summary.tip_error_estimate, 0.5 * err) << tol;
    }
  }
}

TEST_P(Rk4Tolerance, TighterToleranceRefinesMore) {
  const Scene scene = loaded_case();
  auto model = make_model(GetParam(), scene);
  auto ws = model->make_workspace();
  const Solution loose = solve(*model, *ws, scene.input(), coarse(1e-6));
  const Solution tight = solve(*model, *ws, scene.input(), coarse(1e-10));
  ASSERT_TRUE(loose.converged() && tight.converged());
  EXPECT_GE(tight.summary.rk4_refinements, loose.summary.rk4_refinements);
  EXPECT_LT(tight.summary.tip_error_estimate, loose.summary.tip_error_estimate);
  // Both within their tolerance of the exact tip, so within the sum of each other.
  EXPECT_LE((tight.tip().p - loose.tip().p).norm(), 1e-6 + 1e-10);
}

TEST_P(Rk4Tolerance, UnreachableToleranceFailsAndSaysWhy) {
  const Scene scene = loaded_case();
  auto model = make_model(GetParam(), scene);
  auto ws = model->make_workspace();
  SolverOptions o = coarse(1e-18);  // below the round-off of a 0.1 m robot
  o.rk4_max_step = 0.02;            // few steps: 64 times as many stay cheap
  const Solution s = solve(*model, *ws, scene.input(), o);
  EXPECT_FALSE(s.converged());
  EXPECT_EQ(s.summary.termination, TerminationType::NoConvergence);
  EXPECT_GE(s.summary.rk4_refinements, 1);
  EXPECT_LE(s.summary.rk4_refinements, SolverOptions::kMaxRk4Halvings);
  EXPECT_NE(s.summary.message.find("rk4_tip_tolerance"), std::string::npos) << s.summary.message;
  EXPECT_NE(s.summary.message.find("64 times the first"), std::string::npos) << s.summary.message;
  EXPECT_TRUE(std::isfinite(s.summary.tip_error_estimate));
}

INSTANTIATE_TEST_SUITE_P(Models, Rk4Tolerance, ::testing::Values(ModelKind::VC, ModelKind::VCref),
                         [](const auto& info) { return to_string(info.param); });

// The refined solve starts from the coarse answer with the coarse solve's Jacobian: on this
// case the coarse solve takes one Jacobian (modified Newton) and the refined one none.
TEST(Rk4ToleranceVc, RefinedSolveReusesTheCoarseJacobian) {
  const Scene scene = loaded_case();
  auto model = make_model(ModelKind::VC, scene);
  auto ws = model->make_workspace();
  SolverOptions fixed = coarse(0.0);
  const Solution c = solve(*model, *ws, scene.input(), fixed);
  const Solution s = solve(*model, *ws, scene.input(), coarse(1e-8));
  ASSERT_TRUE(c.converged() && s.converged());
  ASSERT_EQ(s.summary.rk4_refinements, 1);
  EXPECT_EQ(s.summary.jacobian_evaluations, c.summary.jacobian_evaluations);
  EXPECT_GT(s.summary.iterations, c.summary.iterations);  // the refined solve's work is counted
}

TEST(Rk4ToleranceVc, OffByDefaultAndIgnoredByCvodeAndLumpedModels) {
  const Scene scene = loaded_case();
  auto vc = make_model(ModelKind::VC, scene);
  auto ws = vc->make_workspace();
  const Solution plain = solve(*vc, *ws, scene.input(), SolverOptions());
  EXPECT_EQ(plain.summary.rk4_refinements, 0);
  EXPECT_TRUE(std::isnan(plain.summary.tip_error_estimate));
  SolverOptions cv;
  cv.integrator = IntegratorKind::Cvode;
  cv.rk4_tip_tolerance = 1e-8;
  const Solution c = solve(*vc, *ws, scene.input(), cv);
  EXPECT_TRUE(c.converged());
  EXPECT_EQ(c.summary.rk4_refinements, 0);
  auto ccsub = make_model(ModelKind::CCsub, scene);
  auto wl = ccsub->make_workspace();
  const Solution l = solve(*ccsub, *wl, scene.input(), coarse(1e-8));
  EXPECT_TRUE(l.converged());
  EXPECT_EQ(l.summary.rk4_refinements, 0);
}

TEST(Rk4ToleranceVc, BadToleranceNamesTheField) {
  for (double bad : {-1e-8, std::nan(""), std::numeric_limits<double>::infinity()}) {
    SolverOptions o;
    o.rk4_tip_tolerance = bad;
    try {
      o.validate();
      ADD_FAILURE() << "accepted " << bad;
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), "solver.rk4_tip_tolerance");
    }
  }
}

TEST(Rk4ToleranceVc, SceneKeyAndJsonOutput) {
  const std::string text = R"({"model": "vc",
    "robot": {"segments": [{"length": 0.05, "disks": 3, "tendons": [{"x": 0, "y": 0.008}]}]},
    "actuation": {"tensions": [1.0]}, "loads": {"tip_force": [0, 0.1, 0]},
    "solver": {"rk4_steps": 1, "rk4_max_step": 0.008, "rk4_tip_tolerance": 1e-8}})";
  const Scene s = parse_scene(text);
  EXPECT_EQ(s.solver.rk4_tip_tolerance, 1e-8);
  const Solution sol = solve(s);
  ASSERT_TRUE(sol.converged()) << sol.summary.brief_report();
  EXPECT_LE(sol.summary.tip_error_estimate, 1e-8);
  const std::string json = solution_to_json(sol);
  EXPECT_NE(json.find("\"tip_error_estimate\""), std::string::npos);
  EXPECT_NE(json.find("\"rk4_refinements\""), std::string::npos);
}

}  // namespace
