#include "tdcr/models/tendon_physics.hpp"

#include <algorithm>
#include <cmath>

#include "physics/tendon_path.hpp"

namespace tdcr::tendon {

namespace {

// Eq. 30-33 (+ Eq. 58) with `tension(t, c)` the tension of tendon t's chord c (from disk c-1 to c).
template <class Tension>
DiskWrench wrench(int j, const Frame* frames, const TendonRouting& routing, Tension tension, bool remove_normal) {
  DiskWrench w;
  const Frame& fj = frames[j];
  const Vec3 z = fj.R.col(2);
  const double* s = routing.disk_s.data();
  for (const RoutedTendon& t : routing.tendons) {
    if (j > t.end_disk) continue;
    const double T = tension(t, j);
    if (T == 0.0) continue;
    const Vec3 a = fj.R * physics::tendon_offset(t, s[j]);  // hole in disk j from its centre
    // The chord to the hole of disk i, from the disk centres' difference and the holes' offsets,
    // not as the difference of two hole positions: those round at the scale of the robot (|p| ~
    // L), a relative error of ~ N eps in a chord L / N long (VCref's residual at the answer on the
    // paper robot with 100000 disks per segment: 4.2e-11 that way, 1.5e-11 this way).
    const auto chord = [&](int i) {
      return Vec3((frames[i].p - fj.p) + (frames[i].R * physics::tendon_offset(t, s[i]) - a));
    };
    // Eq. 30 / first term of Eq. 32: pull towards the hole in the previous disk.
    Vec3 F = T * chord(j - 1).normalized();
    if (j < t.end_disk) {
      // Eq. 32: pass-through, also pulled towards the next disk.
      F += tension(t, j + 1) * chord(j + 1).normalized();
      if (remove_normal) F -= F.dot(z) * z;  // Eq. 58: frictionless disk.
    }
    w.force += F;
    w.moment += a.cross(F);  // Eq. 31 / 33
  }
  return w;
}

}  // namespace

DiskWrench disk_wrench(int j, const Frame* frames, const TendonRouting& routing, const double* tensions,
                       bool remove_normal) {
  return wrench(j, frames, routing, [tensions](const RoutedTendon& t, int) { return tensions[t.index]; },
                remove_normal);
}

DiskWrench disk_wrench_friction(int j, const Frame* frames, const TendonRouting& routing, const double* chord,
                                bool remove_normal) {
  const int D = routing.disk_count();
  return wrench(j, frames, routing, [chord, D](const RoutedTendon& t, int c) { return chord[t.index * D + c]; },
                remove_normal);
}

void friction_tensions(const Frame* frames, const TendonRouting& routing, const double* base_tensions,
                       const TendonFriction& friction, double* chord, int up_to) {
  const int D = routing.disk_count();
  const double sign = friction.sign();
  const double* s = routing.disk_s.data();
  for (const RoutedTendon& t : routing.tendons) {
    double* c = chord + t.index * D;
    double T = base_tensions[t.index];
    const int last = std::min(t.end_disk, up_to);
    if (T == 0.0) {
      for (int j = 1; j <= last; ++j) c[j] = 0.0;
      continue;
    }
    const double k = sign * friction.of(t.index);
    Vec3 in = frames[0].R.col(2);  // from the actuator along the base disk's axis
    Vec3 P = physics::hole_position(frames[0], t, s[0]);
    for (int j = 1; j <= last; ++j) {
      const Vec3 Q = physics::hole_position(frames[j], t, s[j]);
      const Vec3 out = (Q - P).normalized();
      // Turning angle at the hole in disk j-1 (atan2: accurate for small angles too).
      T *= std::exp(k * std::atan2(in.cross(out).norm(), in.dot(out)));
      c[j] = T;
      in = out;
      P = Q;
    }
  }
}

std::vector<double> end_tensions(const TendonRouting& routing, const double* chord, int tendon_count) {
  std::vector<double> e(tendon_count, 0.0);
  const int D = routing.disk_count();
  for (const RoutedTendon& t : routing.tendons) e[t.index] = chord[t.index * D + t.end_disk];
  return e;
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

double chord_displacement(const Frame* frames, const TendonRouting& routing, int k,
                          Actuation::DisplacementConvention convention) {
  const RoutedTendon& t = routing.tendons[static_cast<std::size_t>(k)];
  int first = 0;
  if (convention == Actuation::DisplacementConvention::PerSegment && t.segment > 0)
    first = routing.segment_end_disk[t.segment - 1];
  const double straight = t.straight() ? routing.disk_s[t.end_disk] - routing.disk_s[first]
                                       : rest_chord_length(routing, k, first);
  return straight - chord_length(frames, routing, k, first);
}

std::vector<double> chord_displacements(const std::vector<Frame>& frames, const TendonRouting& routing,
                                        Actuation::DisplacementConvention convention) {
  std::vector<double> d(routing.tendons.size(), 0.0);
  for (std::size_t k = 0; k < routing.tendons.size(); ++k)
    d[k] = chord_displacement(frames.data(), routing, static_cast<int>(k), convention);
  return d;
}

void add_elastic_stretch(const Robot& robot, const TendonRouting& routing, const std::vector<double>& tensions,
                         std::vector<double>& displacements) {
  if (tensions.size() != routing.tendons.size() || displacements.size() != routing.tendons.size()) return;
  std::size_t k = 0;
  for (const Segment& seg : robot.segments)
    for (const TendonSpec& spec : seg.tendons) {
      if (spec.stiffness && tensions[k] != 0.0) {
        const RoutedTendon& t = routing.tendons[k];
        displacements[k] += tensions[k] * physics::rest_length(t, 0.0, routing.disk_s[t.end_disk]) / *spec.stiffness;
      }
      ++k;
    }
}

}  // namespace tdcr::tendon
