// Private to models/: the path of a tendon relative to the backbone, the one place where tendon
// routing enters the models. The body-frame offset r_k(s) (z = 0) is constant for straight
// routing, a helix of constant radius, or a natural cubic spline through given hole positions
// (RoutedTendon, built by TendonRouting::from). VC uses r_k, r_k', r_k'' (Rucker & Webster 2011);
// the disk-based models use the hole positions r_k(s_j).
#pragma once

#include <algorithm>
#include <cmath>

#include "tdcr/core/robot.hpp"
#include "tdcr/core/types.hpp"

namespace tdcr::physics {

/// r_k(s), r_k'(s), r_k''(s) in the body frame (m, 1, 1/m).
struct TendonPoint {
  Vec3 r;
  Vec3 dr;
  Vec3 ddr;
};

/// The offset of tendon `t` and its first two arc-length derivatives at s in [0, s_end].
inline TendonPoint tendon_path(const RoutedTendon& t, double s) {
  using Type = TendonRoutingSpec::Type;
  TendonPoint p{t.r, Vec3::Zero(), Vec3::Zero()};
  if (t.routing == Type::Helical) {
    const double a = t.helix_phase + t.helix_rate * s, w = t.helix_rate;
    const double c = std::cos(a), sn = std::sin(a);
    p.r = t.helix_radius * Vec3(c, sn, 0.0);
    p.dr = (t.helix_radius * w) * Vec3(-sn, c, 0.0);
    p.ddr = -(w * w) * p.r;
  } else if (t.routing == Type::Points) {
    const int n = static_cast<int>(t.spline.size());
    const int i = std::clamp(static_cast<int>(std::upper_bound(t.knots.begin(), t.knots.end(), s) - t.knots.begin()) - 1,
                             0, n - 1);
    const double x = s - t.knots[i];
    const auto& k = t.spline[i];
    for (int c = 0; c < 2; ++c) {
      const double* q = k.data() + 4 * c;
      p.r[c] = q[0] + x * (q[1] + x * (q[2] + x * q[3]));
      p.dr[c] = q[1] + x * (2.0 * q[2] + 3.0 * x * q[3]);
      p.ddr[c] = 2.0 * q[2] + 6.0 * x * q[3];
    }
    if (s >= t.knots.back()) p.r = t.holes.back();  // the end hole exactly
  }
  return p;
}

/// Body-frame offset r_k(s) of a tendon from the backbone (m).
inline Vec3 tendon_offset(const RoutedTendon& t, double s) { return t.straight() ? t.r : tendon_path(t, s).r; }
/// Its derivative r_k'(s) along the arc length (straight routing: zero).
inline Vec3 tendon_offset_rate(const RoutedTendon& t, double s) {
  return t.straight() ? Vec3::Zero() : tendon_path(t, s).dr;
}
/// Hole position of the tendon in a disk (base frame): p_j + R_j r_k(s_j).
inline Vec3 hole_position(const Frame& disk, const RoutedTendon& t, double s) {
  return disk.p + disk.R * tendon_offset(t, s);
}
/// Body-frame tangent of the fully constrained tendon path p + R r_k (Eq. 24-25):
/// q_k = v + u x r_k + r_k', with v, u the backbone's linear and angular strains.
inline Vec3 tendon_tangent(const Vec3& v, const Vec3& u, const Vec3& r, const Vec3& r_rate = Vec3::Zero()) {
  return v + u.cross(r) + r_rate;
}

/// The largest distance of the tendon from the backbone axis over its length (m).
inline double max_offset(const RoutedTendon& t) {
  double r = t.r.norm();
  for (const Vec3& h : t.holes) r = std::max(r, h.norm());
  return r;
}

/// Unit tangent of the fully constrained path on the straight, unloaded robot at s:
/// (e_z + r_k') / |e_z + r_k'|.
inline Vec3 rest_tangent(const RoutedTendon& t, double s) {
  return t.straight() ? Vec3(Vec3::UnitZ()) : Vec3((Vec3::UnitZ() + tendon_offset_rate(t, s)).normalized());
}

/// Length of the fully constrained tendon path on the straight, unloaded robot from s0 to s1:
/// the integral of |e_z + r_k'| (Gauss-Legendre, 5 points per spline interval: exact to
/// rounding for the slowly varying integrand of a cubic).
inline double rest_length(const RoutedTendon& t, double s0, double s1) {
  using Type = TendonRoutingSpec::Type;
  if (t.routing == Type::Straight) return s1 - s0;
  if (t.routing == Type::Helical) return std::hypot(1.0, t.helix_radius * t.helix_rate) * (s1 - s0);
  static constexpr double kX[5] = {-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831,
                                   0.9061798459386640};
  static constexpr double kW[5] = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889, 0.4786286704993665,
                                   0.2369268850561891};
  double L = 0.0;
  for (std::size_t i = 0; i + 1 < t.knots.size(); ++i) {
    const double a = std::max(s0, t.knots[i]), b = std::min(s1, t.knots[i + 1]);
    if (!(b > a)) continue;
    for (int g = 0; g < 5; ++g) {
      const Vec3 dr = tendon_path(t, 0.5 * (a + b) + 0.5 * (b - a) * kX[g]).dr;
      L += 0.5 * (b - a) * kW[g] * std::hypot(1.0, std::hypot(dr.x(), dr.y()));
    }
  }
  return L;
}

}  // namespace tdcr::physics
