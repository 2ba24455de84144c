// Robot description, tendon routing, the paper robot, metrics and API validation.
#include <cmath>

#include <gtest/gtest.h>

#include "tdcr/core/error.hpp"
#include "tdcr/core/lie.hpp"
#include "tdcr/core/metrics.hpp"
#include "tdcr/core/paper_robot.hpp"

using namespace tdcr;

TEST(PaperRobot, Table3Stiffness) {
  const Robot r = paper::robot(10);
  const BackboneStiffness k = r.backbone.effective_stiffness();
  // Values of ../shared/reference/README.md (the paper code's constants).
  EXPECT_NEAR(k.EI, 4.2424067e-3, 1e-9);
  EXPECT_NEAR(k.GJ, 3.2633898e-3, 1e-9);
  EXPECT_NEAR(k.EA, 1.0606e5, 1.0);
  EXPECT_NEAR(k.GA, 4.0792e4, 1.0);
  EXPECT_NEAR(paper::max_tension(r), 5.5532974, 1e-6);
}

TEST(PaperRobot, Configurations) {
  EXPECT_EQ(paper::configuration_tensions(1, 1.0), (std::vector<double>{0, 0, 0, 0}));
  EXPECT_EQ(paper::configuration_tensions(2, 1.0), (std::vector<double>{1, 0, 0, 0}));
  EXPECT_EQ(paper::configuration_tensions(5, 1.0), (std::vector<double>{0, 0, 1, 0}));
  EXPECT_EQ(paper::configuration_tensions(16, 1.0), (std::vector<double>{1, 1, 1, 1}));
}

TEST(TendonRouting, DisksAndEnds) {
  Robot r = paper::robot(3);
  r.segments[1].length = 0.02;
  const TendonRouting t = TendonRouting::from(r);
  ASSERT_EQ(t.disk_count(), 7);
  EXPECT_DOUBLE_EQ(t.disk_s[3], 0.05);
  EXPECT_DOUBLE_EQ(t.disk_s[6], 0.07);
  EXPECT_NEAR(t.disk_s[4], 0.05 + 0.02 / 3, 1e-15);
  EXPECT_EQ(t.tendons[0].end_disk, 3);
  EXPECT_EQ(t.tendons[3].end_disk, 6);
  EXPECT_EQ(t.tendons[2].segment, 1);
  EXPECT_TRUE(t.passes(2, 1));
  EXPECT_FALSE(t.passes(0, 4));
}

TEST(RobotValidation, NamesFieldAndValue) {
  auto expect_error = [](const Scene& s, const std::string& field, const std::string& value) {
    try {
      s.validate();
      FAIL() << "expected InputError for " << field;
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), field);
      EXPECT_NE(std::string(e.what()).find(value), std::string::npos) << e.what();
    }
  };
  Scene s = paper::scene(5, 2);
  s.validate();
  { Scene b = s; b.robot.segments[1].length = -0.05; expect_error(b, "robot.segments[1].length", "-0.05"); }
  { Scene b = s; b.robot.segments[0].disks = 0; expect_error(b, "robot.segments[0].disks", "0"); }
  { Scene b = s; b.actuation.values[2] = NAN; expect_error(b, "actuation.tensions[2]", "nan"); }
  { Scene b = s; b.actuation.values[0] = -1.0; expect_error(b, "actuation.tensions[0]", "-1"); }
  { Scene b = s; b.actuation.values.pop_back(); expect_error(b, "actuation.tensions", "3 values"); }
  { Scene b = s; b.robot.segments[0].tendons[1] = {0.0, 0.0}; expect_error(b, "robot.segments[0].tendons[1]", "(0, 0)"); }
  { Scene b = s; b.robot.backbone.outer_radius = 0.0; expect_error(b, "robot.backbone.outer_radius", "0"); }
  { Scene b = s; b.loads.tip_force.y() = INFINITY; expect_error(b, "loads.tip_force[1]", "inf"); }
  { Scene b = s; b.solver.rk4_steps = 0; expect_error(b, "solver.rk4_steps", "0"); }
}

TEST(SceneEffects, OnlyWhatTheSceneCallsFor) {
  Scene s = paper::scene(5, 2);
  SceneEffects e = s.active_effects();
  EXPECT_FALSE(e.tip_wrench);
  EXPECT_FALSE(e.gravity);
  s.loads.gravity = Vec3(0, 0, -9.81);
  EXPECT_FALSE(s.active_effects().gravity) << "gravity without mass costs nothing";
  s.robot.backbone.density = 6450;
  EXPECT_TRUE(s.active_effects().backbone_weight);
  s.loads.tip_moment = Vec3(0, 1e-3, 0);
  EXPECT_TRUE(s.active_effects().tip_wrench);
}

TEST(Metrics, Eq57) {
  const Frame a{Mat3::Identity(), Vec3(0, 0, 0.1)};
  const Frame b{lie::rot_x(0.1), Vec3(0, 0.003, 0.1)};
  const MeanTipError e = mean_tip_error({a, b}, {a, a}, 0.1);
  EXPECT_NEAR(e.e_p_percent, 1.5, 1e-12);
  EXPECT_NEAR(e.e_R_deg, 0.05 * 180 / M_PI, 1e-10);
  EXPECT_NEAR(e.max_p_percent, 3.0, 1e-12);
}
