// Private to models/: the path of a tendon relative to the backbone, the one place where tendon
// routing enters the models. Today every tendon is routed straight (a constant body-frame offset
// r_k); helical and general routing (r_k(s), r_k'(s), r_k''(s), hole positions per disk) plug in
// here.
#pragma once

#include "tdcr/core/robot.hpp"
#include "tdcr/core/types.hpp"

namespace tdcr::physics {

/// Body-frame offset r_k(s) of a tendon from the backbone (m).
inline Vec3 tendon_offset(const RoutedTendon& t, double /*s*/) { return t.r; }
/// Its derivative r_k'(s) along the arc length (straight routing: zero).
inline Vec3 tendon_offset_rate(const RoutedTendon& /*t*/, double /*s*/) { return Vec3::Zero(); }
/// Hole position of the tendon in a disk (base frame): p_j + R_j r_k(s_j).
inline Vec3 hole_position(const Frame& disk, const RoutedTendon& t, double s) {
  return disk.p + disk.R * tendon_offset(t, s);
}
/// Body-frame tangent of the fully constrained tendon path p + R r_k (Eq. 24-25):
/// q_k = v + u x r_k + r_k', with v, u the backbone's linear and angular strains.
inline Vec3 tendon_tangent(const Vec3& v, const Vec3& u, const Vec3& r, const Vec3& r_rate = Vec3::Zero()) {
  return v + u.cross(r) + r_rate;
}

}  // namespace tdcr::physics
