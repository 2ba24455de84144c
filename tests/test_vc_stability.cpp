// VC's conjugate-point test (models/vc/vc_stability.cpp) on robots bent by one strongly tensioned
// tendon: every such tendon-only equilibrium is stable (the tendon potential T l is convex in the
// bend of a fully constrained tendon, and CCsub and PRB find positive reduced stiffness). The cut
// wrench must include the pull of the tendons crossing the cut: with the backbone's wrench alone
// the test reported these robots unstable from curvature x offset 0.5 (tendon T3) on.
#include <gtest/gtest.h>

#include "tdcr/core/paper_robot.hpp"
#include "tdcr/models/static_model.hpp"

using namespace tdcr;

namespace {

// Paper robot with n disks, tendon `k` alone at the tension that bends the robot (tendons only,
// fully constrained) to curvature x offset c: kappa = T r / EI, c = kappa r.
Scene one_tendon(int n, int k, double c) {
  Scene s = paper::scene(n, 1, "vc");
  const double EI = s.robot.backbone.effective_stiffness().EI;
  const double r = 0.008;
  s.actuation.values.assign(4, 0.0);
  s.actuation.values[k] = c * EI / (r * r);
  s.solver.stability = StabilityCheck::Always;
  return s;
}

}  // namespace

TEST(VcStability, OneTendonBendsUpToNearTheLimitAreStable) {
  for (int k : {0, 2}) {
    for (double c : {0.3, 0.5, 0.7, 0.85}) {
      const Scene s = one_tendon(10, k, c);
      for (ModelKind kind : {ModelKind::VC, ModelKind::CCsub, ModelKind::PRB}) {
        auto m = make_model(kind, s.robot, s.effects);
        SCOPED_TRACE(m->name() + " T" + std::to_string(k + 1) + " c = " + std::to_string(c));
        auto ws = m->make_workspace();
        const Solution sol = solve(*m, *ws, s.input(), s.solver);
        ASSERT_TRUE(sol.converged()) << sol.summary.message;
        EXPECT_EQ(sol.stability.status, StabilityStatus::Stable)
            << "margin " << sol.stability.margin << " (" << sol.stability.method << ")";
      }
    }
  }
}
