// Accuracy-driven RK4 (the default integrator "rk4" and SolverOptions::tip_tolerance,
// models/solve/rk4_refinement.cpp): VC and VCref refine the RK4 mesh until the Richardson estimate
// of the tip error is within the tolerance. Checked against CVODE at rtol 1e-12: the answer's tip is within the tolerance, the
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
  o.tip_tolerance = tolerance;
  return o;
}

// The accuracy-driven solve's first mesh, as a fixed mesh.
SolverOptions first_mesh() {
  SolverOptions o;
  o.integrator = IntegratorKind::FixedStepRK4;
  o.rk4_steps = SolverOptions::kFirstMeshRk4Steps;
  o.rk4_max_step = SolverOptions::kFirstMeshRk4MaxStep;
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
  const SolverOptions o = coarse(1e-18);  // below the round-off of a 0.1 m robot
  const Solution s = solve(*model, *ws, scene.input(), o);
  EXPECT_FALSE(s.converged());
  EXPECT_EQ(s.summary.termination, TerminationType::NoConvergence);
  EXPECT_GE(s.summary.rk4_refinements, 1);
  EXPECT_LE(s.summary.rk4_refinements, SolverOptions::kMaxRk4Halvings);
  EXPECT_NE(s.summary.message.find("tip_tolerance"), std::string::npos) << s.summary.message;
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
  const Solution c = solve(*model, *ws, scene.input(), first_mesh());
  const Solution s = solve(*model, *ws, scene.input(), coarse(1e-8));
  ASSERT_TRUE(c.converged() && s.converged());
  ASSERT_EQ(s.summary.rk4_refinements, 1);
  EXPECT_EQ(s.summary.jacobian_evaluations, c.summary.jacobian_evaluations);
  EXPECT_GT(s.summary.iterations, c.summary.iterations);  // the refined solve's work is counted
}

// Without external loads, with tendons that leave the base along the backbone, VC's cold guess
// (the tendons' pull at the clamped base) is the answer: the refinement checks it on the mesh of
// 4 steps per interval, with no Newton iteration and no Jacobian, and estimates that mesh's error
// by one coarser shot. The answer is still within the tolerance of the CVODE reference and the
// estimate is the error (the paper robot's two segments bent in different planes). A tolerance
// the check's mesh does not meet (1e-12 m) goes on refining from there. Not such cases, and
// solved by Newton as before: a tip force (the guess ignores the shape's lever) and the helical
// example (a tendon leaving the base at an angle pulls along a direction the strains tilt).
TEST(Rk4ToleranceVc, UnloadedColdGuessIsCheckedOnAFineMeshWithoutNewton) {
  Scene scene = paper::scene(10, 1, "vc");
  scene.actuation.values = {5.0, 0.0, 0.0, 2.5};
  auto model = make_model(ModelKind::VC, scene);
  auto ws = model->make_workspace();
  const ModelInput in = scene.input();
  const Solution ref = reference(*model, *ws, in);
  for (double tol : {1e-7, 1e-8}) {
    const Solution s = solve(*model, *ws, in, coarse(tol));
    ASSERT_TRUE(s.converged()) << s.summary.brief_report();
    EXPECT_EQ(s.summary.iterations, 0) << s.summary.brief_report();
    EXPECT_EQ(s.summary.jacobian_evaluations, 0);
    EXPECT_EQ(s.summary.rk4_halvings, 2);
    const double err = (s.tip().p - ref.tip().p).norm();
    EXPECT_LE(s.summary.tip_error_estimate, tol);
    EXPECT_LE(err, tol);
    EXPECT_LT(s.summary.tip_error_estimate, 2.0 * err);
    EXPECT_GT(s.summary.tip_error_estimate, 0.5 * err);
  }
  const Solution tight = solve(*model, *ws, in, coarse(1e-12));
  ASSERT_TRUE(tight.converged()) << tight.summary.brief_report();
  EXPECT_GT(tight.summary.rk4_halvings, 2);
  EXPECT_LE((tight.tip().p - ref.tip().p).norm(), 1e-12);

  Scene loaded = scene;
  loaded.loads.tip_force = Vec3(0.0, 0.05, 0.0);
  const Scene helical = load_scene(std::string(TDCR_SOURCE_DIR) + "/examples/helical_tendon.json");
  for (const Scene* other : std::vector<const Scene*>{&loaded, &helical}) {
    auto m = make_model(ModelKind::VC, *other);
    auto w = m->make_workspace();
    const Solution s = solve(*m, *w, other->input(), coarse(1e-8));
    ASSERT_TRUE(s.converged()) << s.summary.brief_report();
    EXPECT_GT(s.summary.iterations, 0);
    EXPECT_GT(s.summary.jacobian_evaluations, 0);
  }
}

// The default: accuracy-driven RK4 to 1e-7 of the robot's length (1e-8 m here), Newton's
// tolerance tied to it; the fixed mesh and CVODE on request; the lumped models integrate nothing.
TEST(Rk4ToleranceVc, OnByDefaultAndIgnoredByFixedMeshCvodeAndLumpedModels) {
  const Scene scene = loaded_case();
  auto vc = make_model(ModelKind::VC, scene);
  auto ws = vc->make_workspace();
  const Solution ref = reference(*vc, *ws, scene.input());
  const Solution plain = solve(*vc, *ws, scene.input(), SolverOptions());
  ASSERT_TRUE(plain.converged()) << plain.summary.brief_report();
  EXPECT_GE(plain.summary.rk4_refinements, 1);
  EXPECT_LE(plain.summary.tip_error_estimate, 1e-8);
  EXPECT_LE((plain.tip().p - ref.tip().p).norm(), 1e-8);
  SolverOptions fixed;
  fixed.integrator = IntegratorKind::FixedStepRK4;
  const Solution f = solve(*vc, *ws, scene.input(), fixed);
  EXPECT_TRUE(f.converged());
  EXPECT_EQ(f.summary.rk4_refinements, 0);
  EXPECT_TRUE(std::isnan(f.summary.tip_error_estimate));
  SolverOptions cv;
  cv.integrator = IntegratorKind::Cvode;
  cv.tip_tolerance = 1e-8;
  const Solution c = solve(*vc, *ws, scene.input(), cv);
  EXPECT_TRUE(c.converged());
  EXPECT_EQ(c.summary.rk4_refinements, 0);
  auto ccsub = make_model(ModelKind::CCsub, scene);
  auto wl = ccsub->make_workspace();
  const Solution l = solve(*ccsub, *wl, scene.input(), coarse(1e-8));
  EXPECT_TRUE(l.converged());
  EXPECT_EQ(l.summary.rk4_refinements, 0);
}

// A warm-started solve solves on the coarsest mesh its warm start's estimate predicts within half
// the tolerance, and keeps that prediction as its estimate (age 1): its answer meets the
// tolerance all the same, and the prediction is no smaller than the true error.
TEST(Rk4ToleranceVc, WarmSolveSolvesOnThePredictedMesh) {
  Scene scene = loaded_case();
  auto vc = make_model(ModelKind::VC, scene);
  auto ws = vc->make_workspace();
  const Solution cold = solve(*vc, *ws, scene.input(), coarse(1e-10));
  ASSERT_TRUE(cold.converged()) << cold.summary.brief_report();
  ASSERT_GE(cold.summary.rk4_halvings, 2);
  EXPECT_EQ(cold.summary.tip_error_estimate_age, 0);
  scene.actuation.values[0] *= 1.001;
  const Solution warm = solve(*vc, *ws, scene.input(), coarse(1e-10), &cold);
  ASSERT_TRUE(warm.converged()) << warm.summary.brief_report();
  EXPECT_EQ(warm.summary.tip_error_estimate_age, 1);
  EXPECT_EQ(warm.summary.rk4_refinements, 0);
  EXPECT_LE(warm.summary.rk4_halvings, cold.summary.rk4_halvings);
  EXPECT_LE(warm.summary.tip_error_estimate, 0.5e-10);
  const Solution ref = reference(*vc, *ws, scene.input());
  const double error = (warm.tip().p - ref.tip().p).norm();
  EXPECT_LE(error, 1e-10);
  EXPECT_LE(error, 1.2 * warm.summary.tip_error_estimate);
}

// Along a trajectory (the bench_loaded trajectory's input, T1 from 0 to T_M and back with a
// 0.05 N transverse tip force, 60 steps, n = 10), in VC and VCref: every step's tip is within
// the default tolerance (1e-8 m) of CVODE at rtol 1e-12, whether its estimate was measured or
// predicted; the estimate is measured again at least every kMaxEstimateAge + 1 steps.
class Rk4TrajectoryEstimate : public ::testing::TestWithParam<ModelKind> {};

TEST_P(Rk4TrajectoryEstimate, EveryStepWithinTheToleranceAndEstimatesRefreshed) {
  const Robot robot = paper::robot(10);
  const double t_max = paper::max_tension(robot);
  constexpr int kSteps = 60;
  auto model = make_model(GetParam(), robot);
  auto ws = model->make_workspace();
  auto ref_ws = model->make_workspace();
  Solution prev;
  int measured = 0, predicted = 0, max_age = 0;
  for (int k = 0; k <= kSteps; ++k) {
    ModelInput in;
    in.actuation.values = {t_max * 0.5 * (1.0 - std::cos(2.0 * M_PI * k / kSteps)), 0.0, 0.0, 0.0};
    in.loads.tip_force = Vec3(0.05, 0.0, 0.0);
    const Solution s = solve(*model, *ws, in, SolverOptions(), k > 0 ? &prev : nullptr);
    ASSERT_TRUE(s.converged()) << "step " << k << ": " << s.summary.brief_report();
    ASSERT_TRUE(std::isfinite(s.summary.tip_error_estimate)) << "step " << k;
    EXPECT_LE(s.summary.tip_error_estimate, s.summary.tip_tolerance) << "step " << k;
    (s.summary.tip_error_estimate_age == 0 ? measured : predicted) += 1;
    max_age = std::max(max_age, s.summary.tip_error_estimate_age);
    if (k % 5 == 0) {
      const Solution ref = reference(*model, *ref_ws, in);
      EXPECT_LE((s.tip().p - ref.tip().p).norm(), s.summary.tip_tolerance)
          << "step " << k << " (estimate " << s.summary.tip_error_estimate << " m, age "
          << s.summary.tip_error_estimate_age << ")";
    }
    prev = s;
  }
  EXPECT_LE(max_age, SolverOptions::kMaxEstimateAge);
  EXPECT_GE(measured, kSteps / (SolverOptions::kMaxEstimateAge + 1));
  EXPECT_GT(predicted, 0);
}

INSTANTIATE_TEST_SUITE_P(Models, Rk4TrajectoryEstimate, ::testing::Values(ModelKind::VC, ModelKind::VCref),
                         [](const auto& info) { return to_string(info.param); });

// A warm start far from the new input (the tip moves more than 1 % of the length) measures its
// estimate instead of predicting it.
TEST(Rk4ToleranceVc, LargeMoveMeasuresTheEstimate) {
  Scene scene = loaded_case();
  auto vc = make_model(ModelKind::VC, scene);
  auto ws = vc->make_workspace();
  const Solution cold = solve(*vc, *ws, scene.input(), SolverOptions());
  ASSERT_TRUE(cold.converged()) << cold.summary.brief_report();
  scene.loads.tip_force *= 1.5;
  const Solution warm = solve(*vc, *ws, scene.input(), SolverOptions(), &cold);
  ASSERT_TRUE(warm.converged()) << warm.summary.brief_report();
  ASSERT_GT((warm.tip().p - cold.tip().p).norm(), SolverOptions::kMaxPredictedTipMove * scene.robot.total_length());
  EXPECT_EQ(warm.summary.tip_error_estimate_age, 0);
  EXPECT_GE(warm.summary.rk4_refinements, 1);
  const Solution ref = reference(*vc, *ws, scene.input());
  EXPECT_LE((warm.tip().p - ref.tip().p).norm(), warm.summary.tip_tolerance);
}

// One option moves both: the tip tolerance (0: 1e-7 of the length) and Newton's tolerance tied
// to it (0: a hundredth of the tip tolerance over the length), each kept where it is set.
TEST(TipTolerance, ResolvedTiesNewtonsToleranceToTheTipTolerance) {
  const SolverOptions d = SolverOptions().resolved(0.1);
  EXPECT_DOUBLE_EQ(d.tip_tolerance, 1e-8);
  EXPECT_DOUBLE_EQ(d.function_tolerance, 1e-9);
  SolverOptions o;
  o.tip_tolerance = 1e-10;
  EXPECT_DOUBLE_EQ(o.resolved(0.1).function_tolerance, 1e-11);
  EXPECT_DOUBLE_EQ(o.resolved(1.0).function_tolerance, 1e-12);
  o.function_tolerance = 1e-6;
  EXPECT_DOUBLE_EQ(o.resolved(0.1).function_tolerance, 1e-6);
  EXPECT_DOUBLE_EQ(o.resolved(0.1).tip_tolerance, 1e-10);
  // The bounds hold for any length.
  EXPECT_GE(SolverOptions().resolved(1e-6).tip_tolerance, SolverOptions::kMinTipTolerance);
  o = SolverOptions();
  o.tip_tolerance = 1e-18;
  EXPECT_GE(o.resolved(10.0).function_tolerance, SolverOptions::kMinFunctionTolerance);
}

// A looser tip tolerance moves the lumped models' Newton tolerance too: their tip moves by less
// than either tolerance.
TEST(TipTolerance, MovesTheLumpedModelsNewtonTolerance) {
  const Scene scene = loaded_case();
  for (ModelKind kind : {ModelKind::CCsub, ModelKind::PRB}) {
    auto model = make_model(kind, scene);
    auto ws = model->make_workspace();
    SolverOptions tight;
    tight.function_tolerance = 1e-13;
    const Solution ref = solve(*model, *ws, scene.input(), tight);
    for (double tol : {1e-6, 1e-8, 1e-10}) {
      const Solution s = solve(*model, *ws, scene.input(), coarse(tol));
      ASSERT_TRUE(s.converged()) << to_string(kind) << " " << tol << ": " << s.summary.brief_report();
      EXPECT_LE((s.tip().p - ref.tip().p).norm(), tol) << to_string(kind) << " " << tol;
    }
  }
}

TEST(Rk4ToleranceVc, BadToleranceNamesTheField) {
  for (double bad : {-1e-8, std::nan(""), std::numeric_limits<double>::infinity(), 1e-19, 1.0}) {
    SolverOptions o;
    o.tip_tolerance = bad;
    try {
      o.validate();
      ADD_FAILURE() << "accepted " << bad;
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), "solver.tip_tolerance");
    }
  }
}

// The fixed mesh's settings belong to the fixed-mesh integrator: with another one they would be
// ignored, so they are refused (C++ options and scene keys alike), naming the field.
TEST(Rk4ToleranceVc, FixedMeshSettingsNeedTheFixedMeshIntegrator) {
  SolverOptions o;
  o.rk4_steps = 4;
  try {
    o.validate();
    ADD_FAILURE() << "rk4_steps accepted with the accuracy-driven integrator";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "solver.rk4_steps");
    EXPECT_NE(std::string(e.what()).find("rk4_fixed"), std::string::npos) << e.what();
  }
  o.integrator = IntegratorKind::FixedStepRK4;
  EXPECT_NO_THROW(o.validate());
  const std::string scene = R"({"model": "vc",
    "robot": {"segments": [{"length": 0.05, "disks": 3, "tendons": [{"x": 0, "y": 0.008}]}]},
    "actuation": {"tensions": [1.0]}, "solver": {"rk4_max_step": 0.002}})";
  try {
    parse_scene(scene);
    ADD_FAILURE() << "solver.rk4_max_step accepted with the default integrator";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "solver.rk4_max_step");
  }
}

TEST(Rk4ToleranceVc, SceneKeyAndJsonOutput) {
  const std::string text = R"({"model": "vc",
    "robot": {"segments": [{"length": 0.05, "disks": 3, "tendons": [{"x": 0, "y": 0.008}]}]},
    "actuation": {"tensions": [1.0]}, "loads": {"tip_force": [0, 0.1, 0]},
    "solver": {"tip_tolerance": 1e-9}})";
  const Scene s = parse_scene(text);
  EXPECT_EQ(s.solver.tip_tolerance, 1e-9);
  const Solution sol = solve(s);
  ASSERT_TRUE(sol.converged()) << sol.summary.brief_report();
  EXPECT_LE(sol.summary.tip_error_estimate, 1e-9);
  const std::string json = solution_to_json(sol);
  EXPECT_NE(json.find("\"tip_error_estimate\""), std::string::npos);
  EXPECT_NE(json.find("\"rk4_refinements\""), std::string::npos);
  EXPECT_NE(json.find("\"rk4_halvings\""), std::string::npos);
  EXPECT_NE(json.find("\"tip_error_estimate_age\""), std::string::npos);
}

}  // namespace
