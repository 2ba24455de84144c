// The contact tests' scenes and checks, shared by tests/test_contact_lumped.cpp (CCsub, PRB)
// and tests/test_contact_shooting.cpp (VC, VCref), so that the four models are tested on the same
// robot with the same measure of penetration.
#pragma once

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "tdcr/core/contact_geometry.hpp"
#include "tdcr/core/paper_robot.hpp"
#include "tdcr/core/robot.hpp"
#include "tdcr/models/static_model.hpp"

namespace contact_test {

using namespace tdcr;

// The paper robot (two 0.05 m segments, n disks each, EI = 4.24e-3 N m^2), default effects.
inline Scene robot_scene(const std::string& model, int n) {
  Scene s = paper::scene(n, 1, model);
  s.effects = Effects{};
  s.actuation.values = {0, 0, 0, 0};
  return s;
}

inline Solution run(const Scene& s, const Solution* warm = nullptr) { return tdcr::solve(s, warm); }

inline Obstacle sphere(const Vec3& c, double r) {
  Obstacle o;
  o.type = Obstacle::Type::Sphere;
  o.center = c;
  o.radius = r;
  return o;
}

inline Obstacle plane(const Vec3& p, const Vec3& n) {
  Obstacle o;
  o.type = Obstacle::Type::Plane;
  o.point = p;
  o.normal = n;
  return o;
}

// A curved lumen: a circular arc of radius 1 m in the x-z plane from the base, `arc` rad of it
// (0.15: 0.15 m), inner radius 3 mm: the robot's tip meets its wall.
inline Obstacle curved_lumen(double arc) {
  Obstacle lumen;
  lumen.type = Obstacle::Type::Lumen;
  lumen.radius = 0.003;
  for (int k = 0; k <= 40; ++k) {
    const double a = arc * k / 40.0;
    lumen.centreline.push_back(Vec3(1.0 - std::cos(a), 0, std::sin(a)));
  }
  return lumen;
}

// Obstacles robot_scene(model, 10) under tensions (0.5, 0, 0.3, 0) N and a 0.01 N tip force
// along x never touches: a wall below it, a sphere beside it, a wide lumen around it.
inline std::vector<Obstacle> untouched_obstacles() {
  std::vector<Obstacle> obstacles = {plane(Vec3(0, -0.05, 0), Vec3(0, 1, 0)), sphere(Vec3(0.05, -0.03, 0.05), 0.01)};
  Obstacle lumen;
  lumen.type = Obstacle::Type::Lumen;
  lumen.radius = 0.2;
  lumen.centreline = {Vec3(0, 0, -0.1), Vec3(0, 0, 0.3)};
  obstacles.push_back(lumen);
  return obstacles;
}

// The smallest gap of any body part (backbone at every disk, disk rims) to any obstacle.
inline double smallest_gap(const Scene& s, const Solution& sol) {
  const TendonRouting routing = TendonRouting::from(s.robot);
  double g = INFINITY;
  for (int j = 1; j < static_cast<int>(sol.disk_frames.size()); ++j)
    for (const Obstacle& o : s.environment.obstacles) {
      g = std::min(g, contact_point(o, sol.disk_frames[j], ContactBody::Backbone, s.robot.backbone.outer_radius).gap);
      const double r = s.robot.segments[routing.disk_segment[j]].disk_radius;
      if (r > 0.0) g = std::min(g, contact_point(o, sol.disk_frames[j], ContactBody::Disk, r).gap);
    }
  return g;
}

}  // namespace contact_test
