#include "tdcr/core/paper_robot.hpp"

#include <cctype>
#include <cmath>

namespace tdcr::paper {

namespace {
constexpr double kSegmentLength = 0.05;  // L (m), Table 3
constexpr double kPitchRadius = 0.008;   // r_d (m), Table 3
}  // namespace

Robot robot(int disks_per_segment, double stiffness_factor) {
  Robot r;
  r.backbone.youngs_modulus = 2.11e11 * stiffness_factor;
  r.backbone.poisson_ratio = 0.3;
  r.backbone.outer_radius = 0.0004;
  for (int i = 0; i < 2; ++i) {
    Segment s;
    s.length = kSegmentLength;
    s.disks = disks_per_segment;
    s.tendons = {TendonSpec{0.0, kPitchRadius}, TendonSpec{0.0, -kPitchRadius}};
    r.segments.push_back(s);
  }
  return r;
}

double max_tension(const Robot& robot) {
  // Eq. 55 with theta_M = pi/2: the proximal tendon's moment r_d T acts on both segments, the
  // distal one's on the distal segment, giving theta = 3 r_d T L / EI for T1 = T3 = T.
  const double EI = robot.backbone.effective_stiffness().EI;
  const double r_d = robot.segments.front().tendons.front().y;
  const double L = robot.segments.front().length;
  return (M_PI / 2.0) * EI / (3.0 * std::abs(r_d) * L);
}

std::vector<double> configuration_tensions(int c, double t_max) {
  std::vector<double> t(4, 0.0);
  for (int k = 0; k < 4; ++k)
    if (((c - 1) >> k) & 1) t[k] = t_max;
  return t;
}

Effects effects(const std::string& model) {
  Effects e;
  std::string m = model;
  for (char& c : m) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  // The paper's lumped models (Eq. 43-51) keep their subsegments' lengths.
  if (m == "ccsub" || m == "prb") e.shear_extension = false;
  // The paper's case study removes the normal component at the disks (its Eq. 58); the library's
  // default keeps it (docs/models.md, "The tendon force at a disk"). Unloaded, the two coincide.
  e.disk_normal_force = DiskNormalForce::Removed;
  return e;
}

Scene scene(int disks_per_segment, int configuration, const std::string& model) {
  Scene s;
  s.robot = robot(disks_per_segment);
  s.actuation.kind = Actuation::Kind::Tensions;
  s.actuation.values = configuration_tensions(configuration, max_tension(s.robot));
  s.model = model;
  s.effects = effects(model);
  return s;
}

}  // namespace tdcr::paper
