// `--model auto`: the cheapest model expected to meet the requested accuracy, on scenes where the
// answer is known, and the promise checked against the reference model.
#include <gtest/gtest.h>

#include "tdcr/core/error.hpp"
#include "tdcr/core/metrics.hpp"
#include "tdcr/core/paper_robot.hpp"
#include "tdcr/models/model_selection.hpp"

using namespace tdcr;

TEST(ModelSelection, NoExternalLoadAndManyDisksIsCc) {
  // Without external load the fully constrained Cosserat rod is one arc per segment (Camarillo
  // et al. 2008), so CC from tensions is as accurate as VC; above 5 disks both are within 1 %.
  for (int n : {6, 10, 20, 50}) {
    const ModelChoice c = choose_model(paper::scene(n, 6, "auto"), 0.01);
    EXPECT_EQ(c.kind, ModelKind::CC) << n << " disks: " << c.reason;
  }
}

TEST(ModelSelection, FewDisksNeedTheReference) {
  // With 1 disk per segment the constant-curvature family is 25 % off (scenario 1).
  const ModelChoice c = choose_model(paper::scene(1, 6, "auto"), 0.01);
  EXPECT_NE(c.kind, ModelKind::CC);
  EXPECT_NE(c.kind, ModelKind::VC);
}

TEST(ModelSelection, TransverseTipForceOnSoftBackboneIsVcOrVcref) {
  Scene s;
  s.robot = paper::robot(10, 0.1);
  s.actuation.values = paper::configuration_tensions(2, paper::max_tension(s.robot));
  s.loads.tip_force = Vec3(0.5, 0, 0);
  s.model = "auto";
  const ModelChoice c = choose_model(s, 0.01);
  EXPECT_TRUE(c.kind == ModelKind::VC || c.kind == ModelKind::VCref) << c.reason;
  // A tighter request than VC's expected error gets the reference model.
  EXPECT_EQ(choose_model(s, 1e-4).kind, ModelKind::VCref);
}

// Displacements go to CC (kinematic) unless the scene needs statics: external loads, mixed
// input or elastic tendons go to the cheapest static model (VC).
TEST(ModelSelection, DisplacementsGoToCcUnlessStaticsAreNeeded) {
  Scene s = paper::scene(10, 1, "auto");
  s.actuation.kind = Actuation::Kind::Displacements;
  s.actuation.values = {0.001, -0.001, 0, 0};
  EXPECT_EQ(choose_model(s).kind, ModelKind::CC);
  Scene mixed = s;
  mixed.actuation.kinds = {Actuation::Kind::Displacements, Actuation::Kind::Displacements, Actuation::Kind::Tensions,
                           Actuation::Kind::Tensions};
  EXPECT_EQ(choose_model(mixed).kind, ModelKind::VC);
  Scene elastic = s;
  elastic.robot.segments[0].tendons[0].stiffness = 100.0;
  EXPECT_EQ(choose_model(elastic).kind, ModelKind::VC);
  s.loads.tip_force = Vec3(0, 0.1, 0);
  EXPECT_EQ(choose_model(s).kind, ModelKind::VC);
  EXPECT_THROW(choose_model(paper::scene(10, 1, "auto"), 0.0), InputError);
}

TEST(ModelSelection, ThePromiseHoldsAgainstVcref) {
  // The chosen model's actual error on the paper's configurations stays within the requested
  // accuracy, checked against VCref.
  for (int n : {3, 10}) {
    // One reference model and workspace per robot; the configurations are its inputs.
    const auto vcref = make_model(ModelKind::VCref, paper::robot(n));
    const auto ws = vcref->make_workspace();
    for (int c : {2, 6, 11, 16}) {
      const Scene s = paper::scene(n, c, "auto");
      const Solution sol = solve_auto(s, 0.01);
      ASSERT_TRUE(sol.converged()) << sol.summary.brief_report();
      EXPECT_FALSE(sol.model_selection.empty());
      const Solution ref = solve(*vcref, *ws, s.input(), s.solver);
      ASSERT_TRUE(ref.converged());
      const TipError e = tip_error(sol.tip(), ref.tip());
      EXPECT_LT(e.position / s.robot.total_length(), 0.01) << "n " << n << " config " << c << ": " << sol.model_selection;
    }
  }
}

TEST(ModelSelection, SolveAcceptsAuto) {
  const Solution sol = solve(paper::scene(10, 6, "auto"));
  ASSERT_TRUE(sol.converged());
  EXPECT_EQ(sol.model, "cc");
  EXPECT_FALSE(sol.model_selection.empty());
}
