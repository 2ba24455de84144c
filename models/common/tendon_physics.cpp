#include "tdcr/models/tendon_physics.hpp"

#include "physics/tendon_path.hpp"

namespace tdcr::tendon {

DiskWrench disk_wrench(int j, const Frame* frames, const TendonRouting& routing, const double* tensions,
                       bool remove_normal) {
  DiskWrench w;
  const Frame& fj = frames[j];
  const Vec3 z = fj.R.col(2);
  const double* s = routing.disk_s.data();
  for (const RoutedTendon& t : routing.tendons) {
    if (j > t.end_disk) continue;
    const double T = tensions[t.index];
    if (T == 0.0) continue;
    const Vec3 P = physics::hole_position(fj, t, s[j]);
    // Eq. 30 / first term of Eq. 32: pull towards the hole in the previous disk.
    Vec3 F = T * (physics::hole_position(frames[j - 1], t, s[j - 1]) - P).normalized();
    if (j < t.end_disk) {
      // Eq. 32: pass-through, also pulled towards the next disk.
      F += T * (physics::hole_position(frames[j + 1], t, s[j + 1]) - P).normalized();
      if (remove_normal) F -= F.dot(z) * z;  // Eq. 58: frictionless disk.
    }
    w.force += F;
    w.moment += (P - fj.p).cross(F);  // Eq. 31 / 33
  }
  return w;
}

double chord_length(const Frame* frames, const TendonRouting& routing, int k, int first) {
  const RoutedTendon& t = routing.tendons[k];
  double L = 0.0;
  for (int j = first + 1; j <= t.end_disk; ++j)
    L += (physics::hole_position(frames[j], t, routing.disk_s[j]) -
          physics::hole_position(frames[j - 1], t, routing.disk_s[j - 1]))
             .norm();
  return L;
}

namespace {

/// chord_length on the straight, unloaded robot (disk j at s_j e_z).
double rest_chord_length(const TendonRouting& routing, int k, int first) {
  const RoutedTendon& t = routing.tendons[k];
  double L = 0.0;
  for (int j = first + 1; j <= t.end_disk; ++j) {
    const double h = routing.disk_s[j] - routing.disk_s[j - 1];
    L += (h * Vec3::UnitZ() + physics::tendon_offset(t, routing.disk_s[j]) -
          physics::tendon_offset(t, routing.disk_s[j - 1]))
             .norm();
  }
  return L;
}

}  // namespace

std::vector<double> chord_displacements(const std::vector<Frame>& frames, const TendonRouting& routing,
                                        Actuation::DisplacementConvention convention) {
  std::vector<double> d(routing.tendons.size(), 0.0);
  for (std::size_t k = 0; k < routing.tendons.size(); ++k) {
    const RoutedTendon& t = routing.tendons[k];
    int first = 0;
    if (convention == Actuation::DisplacementConvention::PerSegment && t.segment > 0)
      first = routing.segment_end_disk[t.segment - 1];
    const double straight = t.straight() ? routing.disk_s[t.end_disk] - routing.disk_s[first]
                                         : rest_chord_length(routing, static_cast<int>(k), first);
    d[k] = straight - chord_length(frames.data(), routing, static_cast<int>(k), first);
  }
  return d;
}

}  // namespace tdcr::tendon
