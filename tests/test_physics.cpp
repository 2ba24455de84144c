// The physics written once for every model (models/physics, tendon_physics.hpp), against values
// computed by hand.
#include <gtest/gtest.h>

#include <vector>

#include "physics/load_case.hpp"
#include "tdcr/core/robot.hpp"
#include "tdcr/core/scene.hpp"
#include "tdcr/models/tendon_physics.hpp"

using namespace tdcr;

namespace {

void expect_vec(const Vec3& a, const Vec3& b, double tol = 1e-12) {
  EXPECT_LE((a - b).norm(), tol) << "got " << a.transpose() << ", expected " << b.transpose();
}

// L = 1 m in two segments of one disk each; EI = 0.02 N m^2; 0.5 kg/m; disks of 0.1 and 0.2 kg.
// Tendon 0 at (0.03, 0.04) (|r| = 0.05) ends at disk 1, tendon 1 at (0, 0.1) at disk 2.
Robot load_robot() {
  Robot r;
  r.backbone.stiffness = BackboneStiffness{0.02, 0.015, 100.0, 40.0};
  r.backbone.mass_per_length = 0.5;
  r.segments = {Segment{0.5, 1, {TendonSpec{0.03, 0.04}}, 0.1}, Segment{0.5, 1, {TendonSpec{0.0, 0.1}}, 0.2}};
  return r;
}

ModelInput load_input() {
  ModelInput in;
  in.actuation.values = {2.0, 1.0};
  in.loads.tip_force = Vec3(3.0, 0.0, -4.0);  // 5 N
  in.loads.tip_moment = Vec3(0.0, 0.0, 2.0);  // 2 N m
  in.loads.gravity = Vec3(0.0, 0.0, -10.0);
  return in;
}

TEST(LoadCase, WeightsScalesAndParametersByHand) {
  const Robot robot = load_robot();
  physics::LoadCase lc;
  lc.bind(robot, TendonRouting::from(robot), load_input());
  EXPECT_TRUE(lc.has_tension() && lc.has_tip_wrench() && lc.has_disk_weight() && lc.has_backbone_weight());
  EXPECT_TRUE(lc.has_gravity());
  EXPECT_DOUBLE_EQ(lc.tension(0), 2.0);
  EXPECT_DOUBLE_EQ(lc.tension(1), 1.0);
  expect_vec(lc.backbone_weight(), Vec3(0, 0, -5));  // 0.5 kg/m * g
  expect_vec(lc.disk_weight(1), Vec3(0, 0, -1));
  expect_vec(lc.disk_weight(2), Vec3(0, 0, -2));
  expect_vec(lc.total_weight(), Vec3(0, 0, -8));  // 5 N of backbone + 1 N + 2 N
  // F_s = sum T + |F| + |M| / L + |w| L + sum |W_j| + 1 mN = 3 + 5 + 2 + 5 + 3 + 0.001.
  EXPECT_NEAR(lc.force_scale(), 18.001, 1e-12);
  // M_s = sum T |r| + (|F| + weight sum) L + |M| + 1 mN L = 0.2 + 13 + 2 + 0.001.
  EXPECT_NEAR(lc.moment_scale(), 15.201, 1e-12);
  // P = L^2 (|W| + |F|) / EI = 13 / 0.02; P_c = L^2 max(0, -(F + W)_z) / EI = 12 / 0.02.
  EXPECT_NEAR(lc.load_parameter(), 650.0, 1e-9);
  EXPECT_NEAR(lc.compression_parameter(), 600.0, 1e-9);
}

TEST(LoadCase, LoadFactorScalesEveryLoadButNotTheFullLoadTotals) {
  const Robot robot = load_robot();
  physics::LoadCase lc;
  lc.bind(robot, TendonRouting::from(robot), load_input());
  lc.set_load_factor(0.5);
  EXPECT_DOUBLE_EQ(lc.load_factor(), 0.5);
  EXPECT_DOUBLE_EQ(lc.tension(0), 1.0);
  expect_vec(lc.tip_force(), Vec3(1.5, 0, -2));
  expect_vec(lc.tip_moment(), Vec3(0, 0, 1));
  expect_vec(lc.disk_weight(2), Vec3(0, 0, -1));
  expect_vec(lc.backbone_weight(), Vec3(0, 0, -2.5));
  expect_vec(lc.total_weight(), Vec3(0, 0, -8));
  EXPECT_EQ(lc.full_tensions(), (std::vector<double>{2.0, 1.0}));
  // bind() starts again at full load.
  lc.bind(robot, TendonRouting::from(robot), load_input());
  EXPECT_DOUBLE_EQ(lc.load_factor(), 1.0);
}

TEST(LoadCase, UnloadedAndDisplacementInput) {
  const Robot robot = load_robot();
  physics::LoadCase lc;
  ModelInput in;
  in.actuation.kind = Actuation::Kind::Displacements;
  in.actuation.values = {0.001, -0.002};
  lc.bind(robot, TendonRouting::from(robot), in);
  EXPECT_FALSE(lc.has_tension() || lc.has_tip_wrench() || lc.has_gravity());
  EXPECT_EQ(lc.full_tensions(), (std::vector<double>{0.0, 0.0}));
  EXPECT_NEAR(lc.force_scale(), 1e-3, 1e-15);
  EXPECT_NEAR(lc.moment_scale(), 1e-3, 1e-15);  // 1 mN times L = 1 m
  EXPECT_EQ(lc.load_parameter(), 0.0);
  EXPECT_EQ(lc.compression_parameter(), 0.0);
  // Gravity on a massless robot is no load.
  in.loads.gravity = Vec3(0, 0, -9.81);
  Robot light = robot;
  light.backbone.mass_per_length = 0.0;
  for (Segment& s : light.segments) s.disk_mass = 0.0;
  lc.bind(light, TendonRouting::from(light), in);
  EXPECT_FALSE(lc.has_gravity());
}

// Two segments of one disk each, 40 mm long. Tendon A at (0.01, 0) ends at disk 1; tendon B at
// (0, 0.01) ends at disk 2 and passes through disk 1. Frames (rotation identity): base at 0,
// disk 1 at (0, 0, 0.04), disk 2 at (0, 0.03, 0.08), so B's chord from disk 1 to disk 2 is
// (0, 0.03, 0.04): 50 mm along (0, 0.6, 0.8).
struct TwoDisks {
  Robot robot;
  TendonRouting routing;
  std::vector<Frame> frames;
  std::vector<double> tensions = {3.0, 2.0};  // T_A, T_B
  TwoDisks() {
    robot.segments = {Segment{0.04, 1, {TendonSpec{0.01, 0.0}}, 0.0}, Segment{0.04, 1, {TendonSpec{0.0, 0.01}}, 0.0}};
    routing = TendonRouting::from(robot);
    frames.resize(3);
    frames[1].p = Vec3(0, 0, 0.04);
    frames[2].p = Vec3(0, 0.03, 0.08);
  }
  tendon::DiskWrench at(int j, bool eq58) const {
    return tendon::disk_wrench(j, frames.data(), routing, tensions.data(), eq58);
  }
};

TEST(DiskWrench, TerminatingTendonPullsTowardsThePreviousHole) {
  const TwoDisks d;
  // Disk 2: only B ends there, T_B (P1 - P2) / |P1 - P2| = 2 (0, -0.6, -0.8); its moment about
  // the disk centre (0, 0.01, 0) x (0, -1.2, -1.6) = (-0.016, 0, 0). Eq. 58 does not apply.
  for (bool eq58 : {false, true}) {
    const tendon::DiskWrench w = d.at(2, eq58);
    expect_vec(w.force, Vec3(0, -1.2, -1.6));
    expect_vec(w.moment, Vec3(-0.016, 0, 0));
  }
}

TEST(DiskWrench, PassThroughWithAndWithoutEq58) {
  const TwoDisks d;
  // Disk 1: A ends there: 3 (0, 0, -1), moment (0.01, 0, 0) x (0, 0, -3) = (0, 0.03, 0).
  // B passes: 2 ((0, 0, -1) + (0, 0.6, 0.8)) = (0, 1.2, -0.4), moment (0, 0.01, 0) x that =
  // (-0.004, 0, 0).
  const tendon::DiskWrench kept = d.at(1, false);
  expect_vec(kept.force, Vec3(0, 1.2, -3.4));
  expect_vec(kept.moment, Vec3(-0.004, 0.03, 0));
  // Eq. 58: B's force loses its component along the disk normal z = (0, 0, 1): (0, 1.2, 0),
  // whose moment about the centre (0, 0.01, 0) x (0, 1.2, 0) is zero; A is untouched.
  const tendon::DiskWrench removed = d.at(1, true);
  expect_vec(removed.force, Vec3(0, 1.2, -3.0));
  expect_vec(removed.moment, Vec3(0, 0.03, 0));
}

TEST(DiskWrench, SlackTendonsApplyNothing) {
  TwoDisks d;
  d.tensions = {0.0, 0.0};
  for (int j : {1, 2}) {
    expect_vec(d.at(j, true).force, Vec3::Zero(), 0.0);
    expect_vec(d.at(j, true).moment, Vec3::Zero(), 0.0);
  }
}

}  // namespace
