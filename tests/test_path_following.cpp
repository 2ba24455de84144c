// The answer to a loaded scene (docs/models.md): cold solves follow the loading path from rest,
// snap past folds and report the events.
#include <cstdio>
#include <string>

#include <gtest/gtest.h>

#include "tdcr/core/scene_io.hpp"
#include "tdcr/models/static_model.hpp"
#include "tdcr/models/vcref.hpp"
#include "fixed_mesh_settings.hpp"

using namespace tdcr;

namespace {

Scene scene_file(const std::string& name) { return load_scene(std::string(TDCR_TEST_DATA_DIR) + "/" + name); }

ModelInput scaled(const Scene& scene, double f) {
  ModelInput in = scene.input();
  for (double& v : in.actuation.values) v *= f;
  in.loads.tip_force *= f;
  in.loads.tip_moment *= f;
  in.loads.gravity *= f;
  return in;
}

// Natural-parameter path by warm-started direct solves from `from` to `to` in `steps` steps;
// returns the last converged Solution (empty disk_frames if the first step failed).
Solution natural_path(const StaticModel& m, ModelWorkspace& ws, const Scene& scene, const Solution& start, double from,
                      double to, int steps, bool& all_converged) {
  SolverOptions opt = scene.solver;
  opt.continuation = false;  // a plain warm solve per step: no path following
  Solution prev = start;
  all_converged = true;
  for (int k = 1; k <= steps; ++k) {
    const Solution s = solve(m, ws, scaled(scene, from + (to - from) * k / steps), opt, &prev);
    if (!s.converged()) {
      all_converged = false;
      break;
    }
    prev = s;
  }
  return prev;
}

}  // namespace

// The scene two_branches: VC, CCsub and PRB used to land near (-29, 46, 58) mm, VCref at (56, -40,
// -23) mm. The loading path (fine natural steps agree: docs/models.md) reaches VCref's.
TEST(PathFollowing, TwoBranchesSceneAllStaticModelsOnOneBranch) {
  const Scene scene = scene_file("two_branches.json");
  const double length = 0.1;
  Vec3 ref = Vec3::Zero();
  for (ModelKind kind : {ModelKind::VCref, ModelKind::VC, ModelKind::CCsub, ModelKind::PRB}) {
    auto m = make_model(kind, scene.robot, scene.effects);
    auto ws = m->make_workspace();
    const Solution s = solve(*m, *ws, scene.input(), scene.solver);
    ASSERT_TRUE(s.converged()) << m->name() << ": " << s.summary.message;
    if (kind == ModelKind::VCref) ref = s.tip().p;
    EXPECT_LT((s.tip().p - ref).norm(), 0.05 * length) << m->name() << " tip " << s.tip().p.transpose();
    EXPECT_GT(s.tip().p.x(), 0.04) << m->name();  // the branch of the loading path, not (-29, 46, 58) mm
  }
}

// The scene fold_on_path with CCsub: the loading path meets a fold near 60 % of the load and the
// robot snaps. A fine natural path confirms the events: warm-started solves reach just below
// the fold and fail (or jump) just past it; walking back from the answer at full load reaches
// just past the fold on the landing branch, and the two tips differ by the reported jump.
TEST(PathFollowing, SnapThroughMatchesAFineNaturalPath) {
  const Scene scene = scene_file("fold_on_path.json");
  auto m = make_model(ModelKind::CCsub, scene.robot, scene.effects);
  auto ws = m->make_workspace();
  const Solution s = solve(*m, *ws, scene.input(), scene.solver);
  ASSERT_TRUE(s.converged()) << s.summary.message;
  ASSERT_EQ(s.path_events.size(), 2u);
  EXPECT_EQ(s.path_events[0].type, PathEvent::Type::Fold);
  EXPECT_EQ(s.path_events[1].type, PathEvent::Type::Snap);
  EXPECT_NE(s.summary.message.find("snaps"), std::string::npos) << s.summary.message;
  const double fold = s.path_events[0].load_fraction;
  const double jump = s.path_events[1].tip_jump;
  EXPECT_GT(fold, 0.5);
  EXPECT_LT(fold, 0.7);
  EXPECT_GT(jump, 0.02);

  // Before the fold: fine natural path from rest (first step cold and tiny, so direct).
  SolverOptions opt = scene.solver;
  const Solution first = solve(*m, *ws, scaled(scene, 0.01), opt);
  ASSERT_TRUE(first.converged());
  bool ok = false;
  const double below = fold - 2e-4;
  const Solution before = natural_path(*m, *ws, scene, first, 0.01, below, 300, ok);
  ASSERT_TRUE(ok) << "the fine natural path stops before the reported fold";
  // Past the fold the lower branch is gone: a small warm step from just below it fails or jumps.
  SolverOptions plain = scene.solver;
  plain.continuation = false;
  const Solution past = solve(*m, *ws, scaled(scene, fold + 2e-4), plain, &before);
  EXPECT_TRUE(!past.converged() || (past.tip().p - before.tip().p).norm() > 0.5 * jump);

  // After the snap: walk back from the full-load answer to just past the fold.
  const Solution after = natural_path(*m, *ws, scene, s, 1.0, fold + 2e-4, 300, ok);
  ASSERT_TRUE(ok) << "the landing branch does not reach back to the fold";
  // The tip moves like sqrt(distance to the fold) there: 15 % covers the 2e-4 offsets.
  EXPECT_NEAR((after.tip().p - before.tip().p).norm(), jump, 0.15 * jump);
}

// The scene fold_on_path: every static model's loading path lands on one stable branch near
// (-11, 27, -10) mm. VCref meets a fold near 57 % and snaps (its first landing 1e-4 past the
// fold does not converge: the snap lands further past it); it used to stop at the fold. Its
// stability margin falls towards zero at the fold.
TEST(PathFollowing, FoldOnPathSceneAllStaticModelsOnOneStableBranch) {
  const Scene scene = scene_file("fold_on_path.json");
  const double length = 0.1;
  SolverOptions options = scene.solver;
  options.stability = StabilityCheck::Always;
  // The fold located on the requested mesh (a coarse path's fold is 1.6e-4 of the load off here,
  // which the margins 0.05 % below it resolve; CoarseLoadingPathKeepsTheAnswer covers the default).
  options.coarse_loading_path = false;
  Vec3 ref = Vec3::Zero();
  for (ModelKind kind : {ModelKind::VCref, ModelKind::VC, ModelKind::CCsub, ModelKind::PRB}) {
    auto m = make_model(kind, scene.robot, scene.effects);
    auto ws = m->make_workspace();
    const Solution s = solve(*m, *ws, scene.input(), options);
    ASSERT_TRUE(s.converged()) << m->name() << ": " << s.summary.message;
    EXPECT_EQ(s.stability.status, StabilityStatus::Stable) << m->name() << ": " << s.stability.method;
    if (kind == ModelKind::VCref) {
      ref = s.tip().p;
      ASSERT_EQ(s.path_events.size(), 2u) << s.summary.message;
      EXPECT_EQ(s.path_events[0].type, PathEvent::Type::Fold);
      EXPECT_EQ(s.path_events[1].type, PathEvent::Type::Snap);
      EXPECT_GT(s.path_events[0].load_fraction, 0.5);
      EXPECT_LT(s.path_events[0].load_fraction, 0.65);
      EXPECT_GT(s.path_events[1].tip_jump, 0.02);
      // Below the fold the lower branch is stable and its margin falls towards zero at the fold:
      // 0.05 % below it, under 5 % of the margin of the answer and 3 times smaller than 0.3 %
      // below it.
      const double fold = s.path_events[0].load_fraction;
      const Solution a = solve(*m, *ws, scaled(scene, fold - 0.003), options);
      const Solution b = solve(*m, *ws, scaled(scene, fold - 0.0005), options);
      ASSERT_TRUE(a.converged() && b.converged());
      EXPECT_EQ(b.stability.status, StabilityStatus::Stable) << b.stability.margin;
      EXPECT_GT(a.stability.margin, 3.0 * b.stability.margin);
      EXPECT_LT(b.stability.margin, 0.05 * s.stability.margin) << s.stability.margin;
    }
    EXPECT_LT((s.tip().p - ref).norm(), 0.05 * length) << m->name() << " tip " << s.tip().p.transpose();
  }
}

// SolverOptions::coarse_loading_path (the default): VC and VCref follow the loading path on a
// coarse RK4 mesh and solve the answer on the requested one from its end. On the scene fold_on_path
// (a fold and a snap on the way) the answer is the one of the whole path on the requested mesh
// (within the Newton tolerance), the path events are the coarse path's (the fold within 5e-4 of
// the load of the fine path's), and the integrations on the requested mesh are those of one short
// Newton solve. A mesh no finer than the coarse one, or the option off, follows the path as
// before.
TEST(PathFollowing, CoarseLoadingPathKeepsTheAnswer) {
  Scene scene = scene_file("fold_on_path.json");
  scene.solver.integrator = IntegratorKind::FixedStepRK4;  // the coarse path serves the fixed mesh
  for (ModelKind kind : {ModelKind::VCref, ModelKind::VC}) {
    auto m = make_model(kind, scene.robot, scene.effects);
    auto ws = m->make_workspace();
    SolverOptions fine = scene.solver;
    fine.coarse_loading_path = false;
    const Solution whole = solve(*m, *ws, scene.input(), fine);
    const Solution coarse = solve(*m, *ws, scene.input(), scene.solver);
    ASSERT_TRUE(whole.converged() && coarse.converged()) << m->name() << ": " << coarse.summary.message;
    EXPECT_NE(coarse.summary.message.find("loading path on a coarse RK4 mesh"), std::string::npos)
        << coarse.summary.message;
    EXPECT_EQ(whole.summary.message.find("coarse"), std::string::npos) << whole.summary.message;
    EXPECT_LT((coarse.tip().p - whole.tip().p).norm(), 1e-9) << m->name();
    ASSERT_EQ(coarse.path_events.size(), whole.path_events.size()) << m->name();
    for (size_t k = 0; k < whole.path_events.size(); ++k) {
      EXPECT_EQ(coarse.path_events[k].type, whole.path_events[k].type) << m->name() << " event " << k;
      EXPECT_NEAR(coarse.path_events[k].load_fraction, whole.path_events[k].load_fraction, 5e-4)
          << m->name() << " event " << k;
    }
    EXPECT_GT(coarse.summary.continuation_steps, 0);
    EXPECT_NE(coarse.summary.message.find("(2 per disk interval at least, h <= 0.004 m)"), std::string::npos)
        << coarse.summary.message;
    // A requested mesh finer in one setting only: the path's mesh takes the coarser of each (one
    // step per interval here, never two), and the answer is that of the whole path on it.
    SolverOptions one_step = scene.solver;
    one_step.integrator = IntegratorKind::FixedStepRK4;
    one_step.rk4_steps = 1;
    one_step.rk4_max_step = 1e-3;
    const Solution mixed = solve(*m, *ws, scene.input(), one_step);
    one_step.coarse_loading_path = false;
    const Solution mixed_whole = solve(*m, *ws, scene.input(), one_step);
    ASSERT_TRUE(mixed.converged() && mixed_whole.converged()) << mixed.summary.message;
    EXPECT_NE(mixed.summary.message.find("(1 per disk interval at least, h <= 0.004 m)"), std::string::npos)
        << mixed.summary.message;
    EXPECT_LT((mixed.tip().p - mixed_whole.tip().p).norm(), 1e-9) << m->name();
    // On the coarse mesh itself nothing changes: the path is followed there, as with the option off.
    SolverOptions on_coarse = scene.solver;
    on_coarse.integrator = IntegratorKind::FixedStepRK4;
    on_coarse.rk4_steps = SolverOptions::kCoarsePathRk4Steps;
    on_coarse.rk4_max_step = SolverOptions::kCoarsePathRk4MaxStep;
    const Solution plain = solve(*m, *ws, scene.input(), on_coarse);
    ASSERT_TRUE(plain.converged()) << plain.summary.message;
    EXPECT_EQ(plain.summary.message.find("coarse RK4 mesh"), std::string::npos) << plain.summary.message;
    EXPECT_EQ(plain.summary.continuation_steps, coarse.summary.continuation_steps) << m->name();
  }
}

// Below the direct-solve load parameters (tendons only) the fast path stays: no path events,
// no continuation.
TEST(PathFollowing, TendonOnlySceneSolvesDirectly) {
  Scene scene = scene_file("two_branches.json");
  scene.loads.tip_force.setZero();
  auto m = make_model(ModelKind::CCsub, scene.robot, scene.effects);
  auto ws = m->make_workspace();
  const Solution s = solve(*m, *ws, scene.input(), scene.solver);
  ASSERT_TRUE(s.converged()) << s.summary.message;
  EXPECT_EQ(s.summary.continuation_steps, 0);
  EXPECT_TRUE(s.path_events.empty());
}

// A cold direct solve is only the fast path to the loading path's answer: an attempt that has
// not converged within 30 Newton iterations hands over to the next guess or to the path. VCref's
// arcs guess on this antagonistic scene stalls (its line search failed after 86 iterations
// before the limit); the straight guess lands, on the answer of a fine natural loading path.
TEST(PathFollowing, StalledColdDirectSolveHandsOverEarly) {
  Scene scene = scene_file("antagonistic_tip_force.json");
  // From the arcs alone (no fixed-point passes: with them the first attempt converges).
  VcrefOptions arcs;
  arcs.guess_passes = 0;
  auto m = std::make_unique<VcrefModel>(scene.robot, scene.effects, arcs);
  auto ws = m->make_workspace();
  scene.solver = test::fixed_mesh_settings(scene.solver);  // the attempts' iteration counts are the fixed mesh's
  const Solution s = solve(*m, *ws, scene.input(), scene.solver);
  ASSERT_TRUE(s.converged()) << s.summary.message;
  EXPECT_NE(s.summary.message.find("first attempt: KIN_MAXITER_REACHED: 30 iterations"), std::string::npos)
      << s.summary.message;
  EXPECT_LE(s.summary.iterations, 45);
  // The loading path by warm-started direct solves from 5 % of the load.
  auto wp = m->make_workspace();
  SolverOptions o = scene.solver;
  o.continuation = false;
  const Solution start = solve(*m, *wp, scaled(scene, 0.05), o);
  ASSERT_TRUE(start.converged()) << start.summary.message;
  bool all = false;
  const Solution path = natural_path(*m, *wp, scene, start, 0.05, 1.0, 40, all);
  ASSERT_TRUE(all);
  EXPECT_LT((path.tip().p - s.tip().p).norm(), 1e-7) << path.tip().p.transpose() << " vs " << s.tip().p.transpose();
  // Without continuation there is no limit: the arcs guess fails in its line search first.
  auto w2 = m->make_workspace();
  const Solution d = solve(*m, *w2, scene.input(), o);
  ASSERT_TRUE(d.converged()) << d.summary.message;
  EXPECT_NE(d.summary.message.find("first attempt: KIN_LINESEARCH_NONCONV"), std::string::npos) << d.summary.message;
  // From the default guess (the arcs and fixed-point passes) the first attempt lands, there.
  auto md = make_model(ModelKind::VCref, scene.robot, scene.effects);
  auto wd = md->make_workspace();
  const Solution f = solve(*md, *wd, scene.input(), scene.solver);
  ASSERT_TRUE(f.converged()) << f.summary.message;
  EXPECT_EQ(f.summary.message.find("first attempt"), std::string::npos) << f.summary.message;
  EXPECT_LE(f.summary.iterations, 5);
  EXPECT_LT((path.tip().p - f.tip().p).norm(), 1e-7);
}

// A soft robot under a transverse tip force (tests/data/soft_transverse_tip_force.json, load
// parameter 15.8): the loading path's length in scaled arclength grows with the number of
// unknowns (VCref: 378) and PRB's bending-plane angles turn along it. Measured path steps: VCref
// 15 (31 with the options' step bound alone), PRB 15 (64 while the corrector had inverted
// unknown scales), CCsub 11; each lands on the answer of a 40-step natural path within 1e-7 m.
TEST(PathFollowing, SoftTransversePathTakesFewSteps) {
  const Scene scene = scene_file("soft_transverse_tip_force.json");
  for (ModelKind k : {ModelKind::VCref, ModelKind::PRB, ModelKind::CCsub}) {
    SCOPED_TRACE(to_string(k));
    auto m = make_model(k, scene.robot, scene.effects);
    auto ws = m->make_workspace();
    const Solution s = solve(*m, *ws, scene.input(), scene.solver);
    ASSERT_TRUE(s.converged()) << s.summary.message;
    EXPECT_GT(s.summary.continuation_steps, 0);
    EXPECT_LE(s.summary.continuation_steps, 20) << s.summary.message;
    auto wp = m->make_workspace();
    SolverOptions o = scene.solver;
    o.continuation = false;
    const Solution start = solve(*m, *wp, scaled(scene, 0.025), o);
    ASSERT_TRUE(start.converged()) << start.summary.message;
    bool all = false;
    const Solution path = natural_path(*m, *wp, scene, start, 0.025, 1.0, 40, all);
    ASSERT_TRUE(all);
    EXPECT_LT((path.tip().p - s.tip().p).norm(), 1e-7) << path.tip().p.transpose() << " vs " << s.tip().p.transpose();
  }
}
