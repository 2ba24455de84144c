// Tests of the obstacle geometry (core/contact_geometry.hpp): for every primitive, on random
// points, the gradient of the signed distance (central differences) is the reported normal, the
// closest point lies on the surface at that distance, and the signs say inside or outside.
// The contact points of the backbone and the disks; the scene checks of obstacles.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "tdcr/core/contact_geometry.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/core/paper_robot.hpp"
#include "tdcr/core/scene_io.hpp"

using namespace tdcr;

namespace {

std::vector<Obstacle> primitives() {
  std::vector<Obstacle> v;
  Obstacle plane;
  plane.type = Obstacle::Type::Plane;
  plane.point = Vec3(0.01, -0.02, 0.03);
  plane.normal = Vec3(1.0, 2.0, -0.5);
  v.push_back(plane);
  Obstacle sphere;
  sphere.type = Obstacle::Type::Sphere;
  sphere.center = Vec3(0.02, 0.01, 0.1);
  sphere.radius = 0.015;
  v.push_back(sphere);
  Obstacle cylinder;
  cylinder.type = Obstacle::Type::Cylinder;
  cylinder.ends[0] = Vec3(-0.03, 0.02, 0.05);
  cylinder.ends[1] = Vec3(0.04, 0.0, 0.09);
  cylinder.radius = 0.012;
  v.push_back(cylinder);
  Obstacle capsule = cylinder;
  capsule.type = Obstacle::Type::Capsule;
  v.push_back(capsule);
  Obstacle lumen;
  lumen.type = Obstacle::Type::Lumen;
  lumen.radius = 0.01;
  for (int k = 0; k <= 6; ++k) {  // a curved centreline: a quarter circle of radius 0.1
    const double a = 0.25 * M_PI * k / 6.0;
    lumen.centreline.push_back(Vec3(0.1 * (1.0 - std::cos(a)), 0.0, 0.1 * std::sin(a)));
  }
  v.push_back(lumen);
  return v;
}

const char* name(Obstacle::Type t) {
  switch (t) {
    case Obstacle::Type::Plane: return "plane";
    case Obstacle::Type::Sphere: return "sphere";
    case Obstacle::Type::Cylinder: return "cylinder";
    case Obstacle::Type::Capsule: return "capsule";
    case Obstacle::Type::Lumen: return "lumen";
  }
  return "";
}

}  // namespace

// The normal is the gradient of the signed distance: central differences (h = 1e-7 m) on 2000
// random points per primitive in a 0.2 m box, away from the sets where the distance is not
// differentiable (the medial axis: a point with two closest points; there the difference
// quotients straddle a kink, so points with a kink inside the stencil are recognised by the
// one-sided quotients disagreeing and skipped, at most 2 % of them).
TEST(ContactGeometry, GradientOfSignedDistanceIsTheNormal) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.1, 0.2);
  for (const Obstacle& o : primitives()) {
    int checked = 0, skipped = 0;
    for (int i = 0; i < 2000; ++i) {
      const Vec3 x(u(rng), u(rng), u(rng));
      const SignedDistance d = signed_distance(o, x);
      constexpr double h = 1e-7;
      Vec3 g, fwd, bwd;
      for (int k = 0; k < 3; ++k) {
        Vec3 e = Vec3::Zero();
        e[k] = h;
        const double p = signed_distance(o, x + e).distance, m = signed_distance(o, x - e).distance;
        g[k] = (p - m) / (2 * h);
        fwd[k] = (p - d.distance) / h;
        bwd[k] = (d.distance - m) / h;
      }
      if ((fwd - bwd).norm() > 1e-5) {
        ++skipped;
        continue;
      }
      ++checked;
      EXPECT_NEAR((g - d.normal).norm(), 0.0, 1e-6) << name(o.type) << " at " << x.transpose();
      EXPECT_NEAR(d.normal.norm(), 1.0, 1e-14);
      // The closest point is on the surface, at the distance, along the normal.
      EXPECT_NEAR(signed_distance(o, d.closest).distance, 0.0, 1e-12) << name(o.type);
      EXPECT_NEAR((x - d.closest - d.distance * d.normal).norm(), 0.0, 1e-12) << name(o.type);
    }
    EXPECT_LE(skipped, 40) << name(o.type);
    EXPECT_GE(checked, 1960) << name(o.type);
  }
}

// Signs and values at points whose distances are known.
TEST(ContactGeometry, KnownDistances) {
  Obstacle s;
  s.type = Obstacle::Type::Sphere;
  s.center = Vec3(0, 0, 1);
  s.radius = 0.5;
  EXPECT_DOUBLE_EQ(signed_distance(s, Vec3(0, 0, 0)).distance, 0.5);
  EXPECT_DOUBLE_EQ(signed_distance(s, Vec3(0, 0, 1.25)).distance, -0.25);
  Obstacle c;
  c.type = Obstacle::Type::Cylinder;
  c.ends[0] = Vec3(0, 0, 0);
  c.ends[1] = Vec3(0, 0, 1);
  c.radius = 0.5;
  EXPECT_DOUBLE_EQ(signed_distance(c, Vec3(1, 0, 0.5)).distance, 0.5);   // beside the mantle
  EXPECT_DOUBLE_EQ(signed_distance(c, Vec3(0, 0, 1.5)).distance, 0.5);   // above a cap
  EXPECT_DOUBLE_EQ(signed_distance(c, Vec3(0.8, 0, 1.4)).distance, 0.5); // beyond the rim: 3-4-5
  EXPECT_DOUBLE_EQ(signed_distance(c, Vec3(0, 0, 0.9)).distance, -0.1);  // inside, nearest the cap
  Obstacle k = c;
  k.type = Obstacle::Type::Capsule;
  EXPECT_DOUBLE_EQ(signed_distance(k, Vec3(0, 0, 1.5)).distance, 0.0);
  Obstacle l;
  l.type = Obstacle::Type::Lumen;
  l.radius = 0.5;
  l.centreline = {Vec3(0, 0, 0), Vec3(0, 0, 1)};
  EXPECT_DOUBLE_EQ(signed_distance(l, Vec3(0.2, 0, 0.5)).distance, 0.3);
  EXPECT_DOUBLE_EQ(signed_distance(l, Vec3(0.2, 0, 7.0)).distance, 0.3);  // open ends: the tube goes on
  EXPECT_DOUBLE_EQ(signed_distance(l, Vec3(0.7, 0, 0.5)).distance, -0.2);
  EXPECT_NEAR((signed_distance(l, Vec3(0.2, 0, 0.5)).normal - Vec3(-1, 0, 0)).norm(), 0.0, 1e-15);
}

// The backbone touches with its surface, a disk with the rim point facing the obstacle.
TEST(ContactGeometry, BackboneAndDiskContactPoints) {
  Obstacle wall;
  wall.type = Obstacle::Type::Plane;
  wall.point = Vec3(0.01, 0, 0);
  wall.normal = Vec3(-1, 0, 0);  // solid at x > 0.01
  Frame f;
  f.p = Vec3(0, 0, 0.05);
  const ContactPoint b = contact_point(wall, f, ContactBody::Backbone, 0.0004);
  EXPECT_NEAR(b.gap, 0.0096, 1e-15);
  EXPECT_NEAR((b.point - Vec3(0.0004, 0, 0.05)).norm(), 0.0, 1e-15);
  EXPECT_NEAR((b.normal - Vec3(-1, 0, 0)).norm(), 0.0, 1e-15);
  // A disk tilted by 30 deg about y: its rim towards +x reaches x = r cos 30.
  f.R = Eigen::AngleAxisd(M_PI / 6, Vec3::UnitY()).toRotationMatrix();
  const ContactPoint d = contact_point(wall, f, ContactBody::Disk, 0.008);
  EXPECT_NEAR(d.gap, 0.01 - 0.008 * std::cos(M_PI / 6), 1e-15);
  // Facing a plane squarely, the disk's centre plane is its distance.
  Obstacle floor;
  floor.type = Obstacle::Type::Plane;
  floor.point = Vec3(0, 0, 0.06);
  floor.normal = Vec3(0, 0, -1);
  EXPECT_NEAR(contact_point(floor, Frame{Mat3::Identity(), Vec3(0, 0, 0.05)}, ContactBody::Disk, 0.008).gap, 0.01,
              1e-15);
}

// Scene checks: an obstacle through the base, a negative radius, a zero normal, an unknown key,
// a key of another obstacle type: InputError naming the field and value.
TEST(ContactGeometry, ObstacleInputErrors) {
  const auto error_of = [](const std::string& environment) -> std::string {
    Scene s = paper::scene(5, 1, "ccsub");
    std::string text = scene_to_json(s);
    text = text.substr(0, text.rfind('}')) + ", \"environment\": " + environment + "}";
    try {
      parse_scene(text).validate();
    } catch (const InputError& e) {
      return e.field() + " | " + e.value() + " | " + e.what();
    }
    return "no error";
  };
  const std::string base = error_of(R"({"obstacles": [{"type": "sphere", "center": [0, 0, 0], "radius": 0.01}]})");
  EXPECT_NE(base.find("environment.obstacles[0]"), std::string::npos) << base;
  EXPECT_NE(base.find("intersects the robot's base"), std::string::npos) << base;
  const std::string wall = error_of(R"({"obstacles": [{"type": "plane", "point": [0.0002, 0, 0], "normal": [-1, 0, 0]}]})");
  EXPECT_NE(wall.find("environment.obstacles[0]"), std::string::npos) << wall;
  const std::string radius = error_of(R"({"obstacles": [{"type": "sphere", "center": [1, 0, 0], "radius": -0.01}]})");
  EXPECT_NE(radius.find("environment.obstacles[0].radius | -0.01"), std::string::npos) << radius;
  const std::string normal = error_of(R"({"obstacles": [{"type": "plane", "point": [1, 0, 0], "normal": [0, 0, 0]}]})");
  EXPECT_NE(normal.find("environment.obstacles[0].normal"), std::string::npos) << normal;
  const std::string key = error_of(R"({"obstacles": [{"type": "sphere", "centre": [1, 0, 0], "radius": 0.01}]})");
  EXPECT_NE(key.find("centre"), std::string::npos) << key;
  const std::string other = error_of(R"({"obstacles": [{"type": "sphere", "center": [1, 0, 0], "radius": 0.01, "normal": [1, 0, 0]}]})");
  EXPECT_NE(other.find("environment.obstacles[0].normal"), std::string::npos) << other;
  const std::string type = error_of(R"({"obstacles": [{"type": "cube"}]})");
  EXPECT_NE(type.find("environment.obstacles[0].type"), std::string::npos) << type;
  const std::string lumen = error_of(R"({"obstacles": [{"type": "lumen", "radius": 0.01, "centreline": [[0, 0, 0]]}]})");
  EXPECT_NE(lumen.find("environment.obstacles[0].centreline"), std::string::npos) << lumen;
  const std::string stiffness = error_of(R"({"contact": {"stiffness": -5}})");
  EXPECT_NE(stiffness.find("environment.contact.stiffness | -5"), std::string::npos) << stiffness;
  EXPECT_EQ(error_of(R"({"obstacles": [{"type": "lumen", "radius": 0.01, "centreline": [[0, 0, 0], [0, 0, 1]]}]})"),
            "no error");
}

// A scene with obstacles is written back as it was read.
TEST(ContactGeometry, SceneFileRoundTrip) {
  Scene s = paper::scene(5, 1, "ccsub");
  s.robot.segments[0].disk_radius = 0.006;
  for (const Obstacle& o : primitives()) s.environment.obstacles.push_back(o);
  s.environment.obstacles[1].center = Vec3(0.5, 0, 0);  // away from the base
  s.environment.contact.stiffness = 1e4;
  const std::string text = scene_to_json(s);
  const Scene back = parse_scene(text);
  EXPECT_EQ(scene_to_json(back), text);
  ASSERT_EQ(back.environment.obstacles.size(), 5u);
  EXPECT_EQ(back.environment.obstacles[4].centreline.size(), 7u);
  EXPECT_EQ(back.robot.segments[0].disk_radius, 0.006);
}
