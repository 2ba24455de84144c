// Tests of the VCref model (multiple shooting, Cosserat rod per subsegment, discrete disk forces).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tdcr/core/error.hpp"
#include "tdcr/core/lie.hpp"
#include "tdcr/core/metrics.hpp"
#include "tdcr/core/paper_robot.hpp"
#include "tdcr/models/tendon_physics.hpp"
#include "tdcr/models/vcref.hpp"

namespace tdcr {
namespace {

Solution run(const Scene& scene, const Solution* warm = nullptr) {
  VcrefModel model(scene);
  auto ws = model.make_workspace();
  return model.solve(*ws, warm);
}

double angle_deg(const Mat3& A, const Mat3& B) { return lie::rotation_angle(A, B) * 180.0 / M_PI; }

// 1. Zero tension: the straight robot, exactly (the straight guess is the solution), for one
// disk per segment and for 500 disks per segment.
TEST(Vcref, ZeroTensionIsStraight) {
  for (int n : {1, 500}) {
    Scene s = paper::scene(n, 1);
    const Solution sol = run(s);
    ASSERT_TRUE(sol.converged()) << n << ": " << sol.summary.message;
    ASSERT_EQ(static_cast<int>(sol.disk_frames.size()), 2 * n + 1);
    EXPECT_EQ(sol.summary.unknowns, 6 + 12 * (2 * n - 1));
    for (std::size_t j = 0; j < sol.disk_frames.size(); ++j) {
      EXPECT_NEAR((sol.disk_frames[j].p - Vec3(0, 0, 0.1 * j / (2.0 * n))).norm(), 0.0, 1e-14);
      EXPECT_NEAR(angle_deg(sol.disk_frames[j].R, Mat3::Identity()), 0.0, 1e-12);
    }
    for (double d : sol.tendon_displacements) EXPECT_NEAR(d, 0.0, 1e-15);
    EXPECT_EQ(sol.summary.linear_solver, n == 1 ? "dense" : "klu");
  }
}

// 2. Pure tip moment, no tension: every subsegment is a circular arc of curvature M / EI,
// exactly (the Cosserat rod with n = 0 has constant m and u), so every disk frame equals
// exp_se3(u s, e_z s). Shear/extension does not enter (n = 0). RK4 integrates the arc with an
// error O(h^4); 16 steps per 25 mm interval at 90 deg of bending give well below 1e-9 m.
TEST(Vcref, PureTipMomentIsCircularArc) {
  Scene s = paper::scene(2, 1);
  const double EI = s.robot.backbone.effective_stiffness().EI;
  const double kappa = (M_PI / 2) / 0.1;  // 90 deg over the robot
  s.loads.tip_moment = Vec3(EI * kappa, 0.0, 0.0);
  s.solver.rk4_steps = 16;
  const Solution sol = run(s);
  ASSERT_TRUE(sol.converged()) << sol.summary.message;
  const Vec3 u(kappa, 0.0, 0.0);
  for (std::size_t j = 0; j < sol.disk_frames.size(); ++j) {
    const double sj = 0.025 * j;
    const Frame ref = lie::exp_se3(u * sj, Vec3::UnitZ() * sj);
    EXPECT_LT((sol.disk_frames[j].p - ref.p).norm(), 1e-9) << j;
    EXPECT_LT(lie::rotation_angle(sol.disk_frames[j].R, ref.R), 1e-8) << j;
  }
  // Bending about +x moves the tip towards -y.
  EXPECT_LT(sol.tip().p.y(), -0.05);
  // Internal moment equals the tip moment everywhere; internal force vanishes.
  for (const BackboneSample& b : sol.backbone) {
    EXPECT_NEAR((b.m - s.loads.tip_moment).norm(), 0.0, 1e-12);
    EXPECT_NEAR(b.n.norm(), 0.0, 1e-12);
  }
}

}  // namespace
}  // namespace tdcr
