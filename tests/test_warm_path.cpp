// A warm start follows the input path from the previous answer (docs/models.md, "The answer to
// a loaded scene"): where the loads change a lot, or the direct warm solve fails, the solver
// walks the input from the previous Solution's tensions and loads to the new ones.
#include <cstdio>
#include <string>

#include <gtest/gtest.h>

#include "tdcr/core/paper_robot.hpp"
#include "tdcr/core/scene_io.hpp"
#include "tdcr/models/static_model.hpp"
#include "fixed_mesh_settings.hpp"

using namespace tdcr;

namespace {

Scene scene_file(const std::string& name) { return load_scene(std::string(TDCR_TEST_DATA_DIR) + "/" + name); }

constexpr ModelKind kStatic[] = {ModelKind::VC, ModelKind::VCref, ModelKind::CCsub, ModelKind::PRB};

}  // namespace

// The scene two_branches (L^2 |F| / EI = 8.6): warm-started from the tendon-only answer, every
// static model walks the tip force in and lands where its cold solve (the loading path from
// rest) does: both paths load the same robot from the same tendon-bent shape.
TEST(WarmPath, LargeLoadChangeFollowsTheInputPathToTheColdAnswer) {
  const Scene scene = scene_file("two_branches.json");
  Scene unloaded = scene;
  unloaded.loads.tip_force.setZero();
  for (ModelKind kind : kStatic) {
    auto m = make_model(kind, scene.robot, scene.effects);
    SCOPED_TRACE(m->name());
    auto ws = m->make_workspace();
    const Solution cold = solve(*m, *ws, scene.input(), test::fixed_mesh_settings(scene.solver));
    ASSERT_TRUE(cold.converged()) << cold.summary.message;
    const Solution start = solve(*m, *ws, unloaded.input(), test::fixed_mesh_settings(unloaded.solver));
    ASSERT_TRUE(start.converged()) << start.summary.message;
    EXPECT_TRUE(start.loads.tip_force.isZero());
    const Solution warm = solve(*m, *ws, scene.input(), test::fixed_mesh_settings(scene.solver), &start);
    ASSERT_TRUE(warm.converged()) << warm.summary.message;
    EXPECT_NE(warm.summary.message.find("input path"), std::string::npos) << warm.summary.message;
    std::printf("%s: %.0f ms: %s\n", m->name().c_str(), 1e3 * warm.summary.solve_time_s, warm.summary.message.c_str());
    EXPECT_GT(warm.summary.continuation_steps, 1);
    EXPECT_EQ(warm.loads.tip_force, scene.loads.tip_force);
    EXPECT_LT((warm.tip().p - cold.tip().p).norm(), 1e-6) << warm.tip().p.transpose() << " vs "
                                                          << cold.tip().p.transpose();
  }
}

// A small change stays a direct warm solve: no input path, few iterations and Jacobians.
TEST(WarmPath, SmallChangeStaysADirectSolve) {
  const Scene scene = scene_file("two_branches.json");
  Scene nearby = scene;
  nearby.loads.tip_force *= 0.98;
  for (ModelKind kind : kStatic) {
    auto m = make_model(kind, scene.robot, scene.effects);
    SCOPED_TRACE(m->name());
    auto ws = m->make_workspace();
    const Solution start = solve(*m, *ws, scene.input(), test::fixed_mesh_settings(scene.solver));
    ASSERT_TRUE(start.converged()) << start.summary.message;
    const Solution warm = solve(*m, *ws, nearby.input(), test::fixed_mesh_settings(nearby.solver), &start);
    ASSERT_TRUE(warm.converged()) << warm.summary.message;
    EXPECT_EQ(warm.summary.message.find("input path"), std::string::npos) << warm.summary.message;
    EXPECT_EQ(warm.summary.continuation_steps, 0);
    // Few iterations (VC reuses the previous Jacobian on warm starts: modified Newton, cheaper
    // iterations, a few more of them).
    EXPECT_LE(warm.summary.iterations, 10);
    EXPECT_LE(warm.summary.jacobian_evaluations, 4);
  }
}

// Hysteresis, as the physical robot shows it: past the fold of example b the cold answer has
// snapped; walking the load back down by warm starts stays on the landing branch, while a cold
// solve at the lower load (the path from rest, which stops short of the fold) is on the other.
TEST(WarmPath, WarmStartsKeepTheBranchOfThePreviousAnswer) {
  const Scene scene = scene_file("fold_on_path.json");
  auto m = make_model(ModelKind::CCsub, scene.robot, scene.effects);
  auto ws = m->make_workspace();
  const Solution full = solve(*m, *ws, scene.input(), test::fixed_mesh_settings(scene.solver));
  ASSERT_TRUE(full.converged()) << full.summary.message;
  ASSERT_FALSE(full.path_events.empty());
  const double fold = full.path_events.front().load_fraction;
  // Down to a load below the fold, scaling tensions and loads together, in warm steps.
  // The landing branch folds back between 0.5 % and 1 % of the load below the first fold (its own
  // limit point, measured): 0.4 % below lies inside the hysteresis loop, where both exist.
  const double target = fold - 0.004;
  Solution prev = full;
  for (int k = 1; k <= 10; ++k) {
    const double f = 1.0 + (target - 1.0) * k / 10.0;
    ModelInput in = scene.input();
    for (double& v : in.actuation.values) v *= f;
    in.loads.tip_force *= f;
    const Solution s = solve(*m, *ws, in, test::fixed_mesh_settings(scene.solver), &prev);
    ASSERT_TRUE(s.converged()) << "step " << k << ": " << s.summary.message;
    prev = s;
  }
  ModelInput low = scene.input();
  for (double& v : low.actuation.values) v *= target;
  low.loads.tip_force *= target;
  const Solution cold_low = solve(*m, *ws, low, test::fixed_mesh_settings(scene.solver));
  ASSERT_TRUE(cold_low.converged()) << cold_low.summary.message;
  EXPECT_TRUE(cold_low.path_events.empty());
  EXPECT_GT((prev.tip().p - cold_low.tip().p).norm(), 0.01)
      << "warm " << prev.tip().p.transpose() << " cold " << cold_low.tip().p.transpose();
}

// A warm start into an actuation the tendon geometry cannot take (E x 0.1, n = 10, tendon 1
// pulled to 1.25 times the tension T* = EI / r^2 where its curvature x offset reaches 1): the
// direct warm solve and the input path both stop, and the loading path from rest names the
// tendon. Never converged; the message says how far the input path got.
TEST(WarmPath, WarmStartIntoAnInfeasibleActuationIsNamed) {
  Scene scene;
  scene.robot = paper::robot(10, 0.1);
  const double EI = scene.robot.backbone.effective_stiffness().EI;
  const double limit = EI / (0.008 * 0.008);
  scene.actuation.values = {0.5 * limit, 0.0, 0.0, 0.0};
  Scene past = scene;
  past.actuation.values[0] = 1.25 * limit;
  for (ModelKind kind : {ModelKind::VC, ModelKind::CCsub}) {
    auto m = make_model(kind, scene.robot, scene.effects);
    SCOPED_TRACE(m->name());
    auto ws = m->make_workspace();
    const Solution start = solve(*m, *ws, scene.input(), test::fixed_mesh_settings(scene.solver));
    ASSERT_TRUE(start.converged()) << start.summary.message;
    const Solution warm = solve(*m, *ws, past.input(), test::fixed_mesh_settings(past.solver), &start);
    EXPECT_FALSE(warm.converged());
    EXPECT_EQ(warm.summary.termination, TerminationType::Infeasible) << warm.summary.message;
    EXPECT_NE(warm.summary.message.find("T1"), std::string::npos) << warm.summary.message;
    EXPECT_NE(warm.summary.message.find("input path"), std::string::npos) << warm.summary.message;
    std::printf("%s: %.0f ms: %s\n", m->name().c_str(), 1e3 * warm.summary.solve_time_s, warm.summary.message.c_str());
  }
}
