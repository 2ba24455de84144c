// Seeded loaded scenes on the paper robot (the loaded-scene suite): the generator of
// tests/test_loaded_scenes.cpp. Every draw comes from a seeded std::mt19937_64 turned into
// doubles here (the std:: distributions differ between standard libraries), so a seed names the
// same scene everywhere.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "tdcr/core/paper_robot.hpp"
#include "tdcr/core/scene.hpp"
#include "tdcr/core/scene_io.hpp"
#include "tdcr/core/solution.hpp"

namespace tdcr::loaded {

constexpr double kPitch = 0.008;   // paper tendon offset r (m)
constexpr double kLength = 0.1;    // paper robot length L (m)

struct LoadedScene {
  std::string name;         // "s<seed>" or the reported example's name
  std::uint64_t seed = 0;   // 0 for the reported examples
  double stiffness_factor;  // f: E = 2.11e11 Pa x f
  int disks = 10;           // n per segment
  double load = 0.0;        // L^2 |F_tip| / EI
  double bend = 0.0;        // tendon-only curvature x offset, max over segments (|T-sum| r^2 / EI)
  bool beyond_limit = false;  // drawn with a tendon-only bend past 1 on purpose
  Scene scene;
};

inline double bending_stiffness(const Robot& robot) { return robot.backbone.effective_stiffness().EI; }

// Tendon-only curvature x offset of both segments (constant curvature, tip moment of the
// tensions): segment 2 bends by (T3 - T4) r / EI, segment 1 by (T1 - T2 + T3 - T4) r / EI.
inline double tendon_bend(const Scene& s) {
  const auto& T = s.actuation.values;
  const double k = kPitch * kPitch / bending_stiffness(s.robot);
  return std::max(std::abs(T[0] - T[1] + T[2] - T[3]), std::abs(T[2] - T[3])) * k;
}

// Largest curvature x offset c = 1 - dh . dp / |dp|^2 over disk intervals and the tendons that
// pass them, of a converged shape (1: a tendon at the centre of curvature, its geometric limit).
inline double max_bend(const Robot& robot, const Solution& sol) {
  const TendonRouting routing = TendonRouting::from(robot);
  double c = 0.0;
  for (int j = 1; j < routing.disk_count(); ++j) {
    const Frame& a = sol.disk_frames[static_cast<std::size_t>(j - 1)];
    const Frame& b = sol.disk_frames[static_cast<std::size_t>(j)];
    const Vec3 dp = b.p - a.p;
    for (const RoutedTendon& t : routing.tendons) {
      if (!routing.passes(t.index, j)) continue;
      const Vec3 dh = dp + b.R * t.r - a.R * t.r;
      c = std::max(c, 1.0 - dh.dot(dp) / dp.squaredNorm());
    }
  }
  return c;
}

inline double load_parameter(const Scene& s) {
  return kLength * kLength * s.loads.tip_force.norm() / bending_stiffness(s.robot);
}

// Scene `index` of the suite, drawn from seed = 1000 + index:
// - n cycles through 5, 10, 20 (index % 3); E x f with f log-uniform in [0.1, 1];
// - tendon-only bends c_i = curvature x offset of segment i uniform in [-0.9, 0.9]; every fourth
//   scene (index % 4 == 3) has one segment's |c| in [1.05, 1.4] instead (beyond the limit on
//   purpose); tensions T = c EI / r^2 on the pulling side of each segment, plus, with
//   probability 1/2, a co-tension uniform in [0, 0.3] EI / r^2 on both tendons of the segment;
// - a tip force uniform in direction, L^2 |F| / EI log-uniform in [0.1, 20].
inline LoadedScene random_scene(int index) {
  LoadedScene ls;
  ls.seed = 1000 + static_cast<std::uint64_t>(index);
  ls.name = "s" + std::to_string(ls.seed);
  std::mt19937_64 gen(ls.seed);
  auto uniform = [&gen](double a, double b) { return a + (b - a) * static_cast<double>(gen() >> 11) * 0x1.0p-53; };

  ls.disks = (index % 3 == 0) ? 5 : (index % 3 == 1) ? 10 : 20;
  ls.stiffness_factor = std::pow(10.0, uniform(-1.0, 0.0));
  ls.scene.robot = paper::robot(ls.disks, ls.stiffness_factor);
  const double t_star = bending_stiffness(ls.scene.robot) / (kPitch * kPitch);  // kappa r = 1

  double c[2] = {uniform(-0.9, 0.9), uniform(-0.9, 0.9)};
  ls.beyond_limit = index % 4 == 3;
  if (ls.beyond_limit) {
    const int seg = uniform(0.0, 1.0) < 0.5 ? 0 : 1;
    c[seg] = (uniform(0.0, 1.0) < 0.5 ? -1.0 : 1.0) * uniform(1.05, 1.4);
  }
  // Segment 2's pair sets c[1]; segment 1's pair adds c[0] - c[1] (the tip tensions bend it too).
  const double diff[2] = {(c[0] - c[1]) * t_star, c[1] * t_star};
  std::vector<double> T(4, 0.0);
  for (int seg = 0; seg < 2; ++seg) {
    const double co = uniform(0.0, 1.0) < 0.5 ? uniform(0.0, 0.3) * t_star : 0.0;
    T[2 * seg] = std::max(diff[seg], 0.0) + co;
    T[2 * seg + 1] = std::max(-diff[seg], 0.0) + co;
  }
  ls.scene.actuation.kind = Actuation::Kind::Tensions;
  ls.scene.actuation.values = T;

  const double z = uniform(-1.0, 1.0), phi = uniform(0.0, 2.0 * M_PI);
  const double rho = std::sqrt(1.0 - z * z);
  const double load = std::pow(10.0, uniform(std::log10(0.1), std::log10(20.0)));
  ls.scene.loads.tip_force = Vec3(rho * std::cos(phi), rho * std::sin(phi), z) *
                             (load * bending_stiffness(ls.scene.robot) / (kLength * kLength));
  ls.load = load_parameter(ls.scene);
  ls.bend = tendon_bend(ls.scene);
  return ls;
}

// A scene file of tests/data (the reported examples two_branches and fold_on_path).
inline LoadedScene file_scene(const std::string& name, const std::string& file) {
  LoadedScene ls;
  ls.name = name;
  ls.scene = load_scene(std::string(TDCR_TEST_DATA_DIR) + "/" + file);
  ls.stiffness_factor = ls.scene.robot.backbone.youngs_modulus / 2.11e11;
  ls.disks = ls.scene.robot.segments[0].disks;
  ls.load = load_parameter(ls.scene);
  ls.bend = tendon_bend(ls.scene);
  return ls;
}

// The "VC fails on feasible scenes" report's example: E x 0.1, n = 5, tensions (0.04, 0.15, 0.02, 0.71) T_M (T_M of the
// Table 3 robot), tip force (0.01, 0.01, 0.005) N ("VC fails on feasible scenes"); and its
// infeasible example: E x 0.1, n = 10, 1.5 T_M on tendon 1.
inline LoadedScene soft_scene(bool infeasible) {
  LoadedScene ls;
  const double tm = paper::max_tension(paper::robot(10));
  ls.stiffness_factor = 0.1;
  ls.disks = infeasible ? 10 : 5;
  ls.scene.robot = paper::robot(ls.disks, 0.1);
  ls.scene.actuation.kind = Actuation::Kind::Tensions;
  if (infeasible) {
    ls.name = "soft_beyond_limit";
    ls.scene.actuation.values = {1.5 * tm, 0.0, 0.0, 0.0};
    ls.beyond_limit = true;
  } else {
    ls.name = "soft_n5_tip_force";
    ls.scene.actuation.values = {0.04 * tm, 0.15 * tm, 0.02 * tm, 0.71 * tm};
    ls.scene.loads.tip_force = Vec3(0.01, 0.01, 0.005);
  }
  ls.load = load_parameter(ls.scene);
  ls.bend = tendon_bend(ls.scene);
  return ls;
}

// The suite: the four reported examples, then `count` seeded scenes.
inline std::vector<LoadedScene> suite(int count) {
  std::vector<LoadedScene> v = {file_scene("two_branches", "two_branches.json"), file_scene("fold_on_path", "fold_on_path.json"),
                                soft_scene(false), soft_scene(true)};
  for (int i = 0; i < count; ++i) v.push_back(random_scene(i));
  return v;
}

}  // namespace tdcr::loaded
