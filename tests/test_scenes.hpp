// Scenes shared by several test files (one definition each).
#pragma once

#include "tdcr/core/paper_robot.hpp"
#include "tdcr/core/scene.hpp"

namespace test_scenes {

/// Hard case 14: a long soft robot under gravity. Three 0.2 m segments of the paper robot's
/// section with E = 1e9 Pa (EI = 2e-5 N m^2), steel density 6450 kg/m^3, 0.1 g disks, gravity
/// along -y scaled by `gravity_fraction`, a light pull T1 = 0.01 N. At full gravity
/// w L^3 / (8 EI) ~ 40 and L^2 |W| / EI ~ 870: the robot hangs from its base, and a direct solve
/// from the straight robot can converge to another equilibrium branch.
inline tdcr::Scene long_soft_robot(int disks = 10, double gravity_fraction = 1.0) {
  tdcr::Scene s;
  s.robot = tdcr::paper::robot(disks);
  s.robot.segments.push_back(s.robot.segments.back());
  s.robot.backbone.youngs_modulus = 1e9;
  s.robot.backbone.density = 6450;
  for (tdcr::Segment& g : s.robot.segments) {
    g.length = 0.2;
    g.disk_mass = 1e-4;
  }
  s.actuation.values = {0.01, 0, 0, 0, 0, 0};
  s.loads.gravity = tdcr::Vec3(0, -9.81 * gravity_fraction, 0);
  return s;
}

}  // namespace test_scenes
