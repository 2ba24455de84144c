// Contact tests every model with contact takes the same way (CCsub, PRB, VC, VCref, on the scenes
// of contact_scenes.hpp): untouched obstacles, symmetric supports, no penetration, compliant
// contact tending to rigid, a warm trajectory along a wall. The models' own tests are in
// tests/test_contact_lumped.cpp and tests/test_contact_shooting.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "contact_scenes.hpp"

using namespace tdcr;
using namespace contact_test;

namespace {
class ContactEveryModel : public ::testing::TestWithParam<std::string> {};
}  // namespace

// Obstacles the free-space answer does not reach leave it as it is (1e-12 m): a far wall, a
// sphere beside the robot, a wide lumen around it.
TEST_P(ContactEveryModel, UntouchedObstaclesGiveTheFreeSpaceAnswer) {
  Scene s = robot_scene(GetParam(), 10);
  s.actuation.values = {0.5, 0, 0.3, 0};
  s.loads.tip_force = Vec3(0.01, 0.0, 0.0);
  const Solution free = run(s);
  ASSERT_TRUE(free.converged()) << free.summary.message;
  s.environment.obstacles = untouched_obstacles();
  const Solution touched = run(s);
  ASSERT_TRUE(touched.converged()) << touched.summary.message;
  EXPECT_TRUE(touched.contacts.empty());
  ASSERT_EQ(touched.disk_frames.size(), free.disk_frames.size());
  for (std::size_t j = 0; j < free.disk_frames.size(); ++j)
    EXPECT_LE((touched.disk_frames[j].p - free.disk_frames[j].p).norm(), 1e-12) << "disk " << j;
}

// Two supports mirror-symmetric about the x-z plane (1 mm spheres at +-45 deg about the x axis,
// touching the backbone at s = 0.05 m) under a tip force along x: equal forces, mirrored.
TEST_P(ContactEveryModel, SymmetricSupportsCarryEqualForces) {
  Scene s = robot_scene(GetParam(), 10);
  s.loads.tip_force = Vec3(0.004, 0, 0);
  const double d = s.robot.backbone.outer_radius + 0.001;
  s.environment.obstacles = {sphere(Vec3(d * std::sqrt(0.5), d * std::sqrt(0.5), 0.05), 0.001),
                             sphere(Vec3(d * std::sqrt(0.5), -d * std::sqrt(0.5), 0.05), 0.001)};
  const Solution sol = run(s);
  ASSERT_TRUE(sol.converged()) << sol.summary.message;
  ASSERT_EQ(sol.contacts.size(), 2u);
  const Contact& a = sol.contacts[0].obstacle == 0 ? sol.contacts[0] : sol.contacts[1];
  const Contact& b = sol.contacts[0].obstacle == 0 ? sol.contacts[1] : sol.contacts[0];
  EXPECT_NEAR(a.force, b.force, 1e-10 * a.force);
  EXPECT_NEAR(a.normal.x(), b.normal.x(), 1e-10);
  EXPECT_NEAR(a.normal.y(), -b.normal.y(), 1e-10);
  EXPECT_NEAR(sol.tip().p.y(), 0.0, 1e-13);
  // Together they hold what one support straight ahead would (beam theory: 2.5 P along x).
  EXPECT_NEAR((a.force * a.normal + b.force * b.normal).x(), -2.5 * 0.004, 0.05 * 2.5 * 0.004);
}

// A robot bent by its tendons against a wall, disks with a 10 mm rim: no part penetrates
// (1e-9 m), every force is non-negative and every reported contact closed (gap ~ 0).
TEST_P(ContactEveryModel, NoPenetrationAgainstAWall) {
  Scene s = robot_scene(GetParam(), 10);
  s.actuation.values = {1.5, 0, 0.8, 0};
  for (Segment& g : s.robot.segments) g.disk_radius = 0.01;
  s.environment.obstacles = {plane(Vec3(0, 0.025, 0), Vec3(0, -1, 0))};
  const Solution sol = run(s);
  ASSERT_TRUE(sol.converged()) << sol.summary.message;
  ASSERT_FALSE(sol.contacts.empty());
  EXPECT_GE(smallest_gap(s, sol), -1e-9);
  for (const Contact& c : sol.contacts) {
    EXPECT_GE(c.force, 0.0);
    EXPECT_NEAR(c.gap, 0.0, 1e-9);
    EXPECT_TRUE(c.disk);  // the rims stand out 9.6 mm beyond the backbone
  }
  std::printf("%s: %zu contacts, smallest gap %.3g m, %s\n", GetParam().c_str(), sol.contacts.size(),
              smallest_gap(s, sol), sol.summary.brief_report().c_str());
}

// Compliant contact tends to rigid contact as its stiffness grows: the reaction of the propped
// cantilever approaches the rigid one about in proportion to 1 / k.
TEST_P(ContactEveryModel, CompliantTendsToRigid) {
  Scene s = robot_scene(GetParam(), 10);
  s.loads.tip_force = Vec3(0.002, 0, 0);
  const double r = s.robot.backbone.outer_radius;
  s.environment.obstacles = {sphere(Vec3(r + 0.001, 0, 0.05), 0.001)};
  const Solution rigid = run(s);
  ASSERT_TRUE(rigid.converged()) << rigid.summary.message;
  ASSERT_EQ(rigid.contacts.size(), 1u);
  double last = INFINITY;
  for (double k : {1e2, 1e3, 1e4, 1e5, 1e6}) {
    s.environment.contact.stiffness = k;
    const Solution sol = run(s);
    ASSERT_TRUE(sol.converged()) << sol.summary.message;
    ASSERT_EQ(sol.contacts.size(), 1u);
    const double error = std::abs(sol.contacts[0].force - rigid.contacts[0].force);
    // The force law to the solver's tolerance (scaled residual 1e-10 of the force scale EI / L^2).
    EXPECT_NEAR(sol.contacts[0].force, -k * sol.contacts[0].gap, 1e-9);
    if (k > 1e3) {
      EXPECT_LT(error, 0.2 * last) << "k = " << k;
    }
    last = error;
  }
  EXPECT_LT(last, 1e-3 * rigid.contacts[0].force);
}

// A trajectory sliding along a wall, warm-started from step to step: each step converges, does
// not penetrate, and carries its contacts on.
TEST_P(ContactEveryModel, WarmTrajectoryAlongAWall) {
  Scene s = robot_scene(GetParam(), 10);
  for (Segment& g : s.robot.segments) g.disk_radius = 0.01;
  s.environment.obstacles = {plane(Vec3(0, 0.025, 0), Vec3(0, -1, 0))};
  Solution last;
  for (int step = 0; step <= 20; ++step) {
    s.actuation.values = {1.0 + 0.05 * step, 0, 0.8, 0.02 * step};
    const Solution sol = run(s, last.converged() ? &last : nullptr);
    ASSERT_TRUE(sol.converged()) << "step " << step << ": " << sol.summary.message;
    EXPECT_GE(smallest_gap(s, sol), -1e-9) << "step " << step;
    last = sol;
  }
  EXPECT_FALSE(last.contacts.empty());
}

// A 3 mm ball beside the path of the tip (the robot bent by tendon 1: its tip reaches the ball at
// 0.55 N, 20 deg below the horizontal through the tip), the tension raised to 2 N: the robot
// loaded from rest stays behind the ball, so the warm path and every cold solve end there. At 1.35
// to 1.65 N the free answer lies past the ball, shallowly in it or clear of it: the cold solve once
// came back to the far side of the ball (CCsub, VC, VCref: contact Newton from the free answer) or
// took the free answer (PRB: its sweep from rest interpolated its unknowns, which turn the bending
// plane on the way, and missed the ball); the completion now sweeps the disks' poses and loads
// from rest where the way there passes an obstacle's middle.
TEST_P(ContactEveryModel, ColdSolvesBehindABallAreTheLoadingPathsAnswer) {
  Scene s = robot_scene(GetParam(), 10);
  s.actuation.values = {0.5, 0, 0, 0};
  const Solution reach = run(s);
  ASSERT_TRUE(reach.converged()) << reach.summary.message;
  const double rho = 0.003, r = s.robot.backbone.outer_radius, a = 20.0 * M_PI / 180.0;
  const Vec3 centre = reach.tip().p + (rho + r + 1e-4) * Vec3(0, std::cos(a), -std::sin(a));
  s.environment.obstacles = {sphere(centre, rho)};
  Solution warm = reach;
  for (int i = 1; i <= 30; ++i) {
    const double T = 0.5 + 0.05 * i;
    s.actuation.values = {T, 0, 0, 0};
    warm = run(s, &warm);
    ASSERT_TRUE(warm.converged()) << "T = " << T << ": " << warm.summary.message;
    EXPECT_LT(warm.tip().p.y(), centre.y()) << "T = " << T;  // behind the ball
    if (i % 3 != 0) continue;  // cold at 0.65, 0.8, ..., 2 N
    const Solution cold = run(s);
    ASSERT_TRUE(cold.converged()) << "T = " << T << ": " << cold.summary.message;
    EXPECT_LE((cold.tip().p - warm.tip().p).norm(), 1e-6)
        << "T = " << T << ": cold tip y " << cold.tip().p.y() << ", warm " << warm.tip().p.y() << "; "
        << cold.summary.message;
    EXPECT_EQ(cold.contacts.size(), 1u) << "T = " << T;
  }
  std::printf("%s: tip behind the ball at 2 N, y = %.6g m (ball centre %.6g m)\n", GetParam().c_str(),
              warm.tip().p.y(), centre.y());
}

INSTANTIATE_TEST_SUITE_P(Models, ContactEveryModel, ::testing::Values("ccsub", "prb", "vc", "vcref"));
