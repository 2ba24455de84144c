#include "lumped/subsegment_statics.hpp"

#include <algorithm>

#include "physics/tendon_path.hpp"
#include "tdcr/models/tendon_physics.hpp"

namespace tdcr::detail {

void SubsegmentLoads::set_load_factor(double lambda) {
  loads.set_load_factor(lambda);
  for (std::size_t k = 0; k < tensions.size(); ++k) tensions[k] = loads.tension(static_cast<int>(k));
  if (!stretch.empty()) update_stretch();
}

void SubsegmentLoads::update_stretch() {
  // N_j = the tensions of the tendons ending at disk j or beyond: their sum from the tip down.
  const int N = static_cast<int>(stretch.size()) - 1;
  std::fill(stretch.begin(), stretch.end(), 0.0);
  for (std::size_t k = 0; k < tendon_end.size(); ++k) stretch[static_cast<std::size_t>(tendon_end[k])] += tensions[k];
  double through = 0.0;
  for (int j = N; j >= 1; --j) {
    through += stretch[static_cast<std::size_t>(j)];
    stretch[static_cast<std::size_t>(j)] = 1.0 - through * axial_compliance;
  }
  stretch[0] = 1.0;
}

SubsegmentStatics::SubsegmentStatics(const Robot& robot, const TendonRouting& routing, const Effects& effects)
    : robot_(&robot), routing_(&routing) {
  n_ = routing.disk_count() - 1;
  remove_normal_ = effects.disk_normal_force == DiskNormalForce::Removed;
  friction_on_ = effects.tendon_friction.on();
  friction_ = effects.tendon_friction;
  length_.assign(n_ + 1, 0.0);
  for (int j = 1; j <= n_; ++j) length_[j] = routing.disk_s[j] - routing.disk_s[j - 1];
}

void SubsegmentStatics::bind(const ModelInput& input, SubsegmentLoads& out) const {
  out.loads.bind(*robot_, *routing_, input);
  out.tensions = out.loads.full_tensions();
  if (friction_on_) out.chord.assign(out.tensions.size() * routing_->disk_count(), 0.0);
  const std::size_t slots = routing_->tendons.size() * static_cast<std::size_t>(routing_->disk_count());
  out.holes.resize(slots);
  out.chords.resize(slots);
  if (axial_compliance_ > 0.0) {
    out.axial_compliance = axial_compliance_;
    out.tendon_end.assign(out.tensions.size(), 0);
    for (const RoutedTendon& t : routing_->tendons) out.tendon_end[static_cast<std::size_t>(t.index)] = t.end_disk;
    out.stretch.assign(static_cast<std::size_t>(n_) + 1, 1.0);
    out.update_stretch();
  } else {
    out.stretch.clear();
  }
  // Last disk that carries any load: beyond it the robot is straight.
  if (out.loads.has_tip_wrench() || out.loads.has_gravity()) {
    out.active = n_;
  } else {
    out.active = 0;
    for (const RoutedTendon& t : routing_->tendons)
      if (out.tensions[t.index] != 0.0) out.active = std::max(out.active, t.end_disk);
  }
}

void SubsegmentStatics::update_friction(SubsegmentLoads& b, const Frame* frames) const {
  tendon::friction_tensions(frames, *routing_, b.tensions.data(), friction_, b.chord.data());
}

void SubsegmentStatics::disk_loads(SubsegmentLoads& b, const Frame* frames, Vec3* f, Vec3* m, int first,
                                   int last_disk, int fresh_from) const {
  const int J = b.active;
  const int D = routing_->disk_count();
  const double* s = routing_->disk_s.data();
  first = std::max(first, 1);
  const int L = last_disk < 0 ? J : std::min(last_disk, J);
  for (int j = first; j <= L; ++j) f[j] = m[j] = Vec3::Zero();
  // Eq. 30-33 (+ Eq. 58) as tendon::disk_wrench, tendon by tendon in the same order and with
  // the same operations (the pull towards disk j+1 is minus the chord towards disk j).
  for (const RoutedTendon& t : routing_->tendons) {
    const double* chord = friction_on_ ? b.chord.data() + t.index * D : nullptr;
    const double T0 = b.tensions[t.index];
    if (!chord && T0 == 0.0) continue;
    auto tension = [&](int c) { return chord ? chord[c] : T0; };
    Vec3* H = b.holes.data() + t.index * D;
    Vec3* C = b.chords.data() + t.index * D;
    const int last = std::min(t.end_disk, L + 1);
    // Disks j >= first read the chords c >= first, i.e. the holes c >= first - 1.
    const int c0 = first - 1;
    if (c0 >= fresh_from) H[c0] = physics::hole_position(frames[c0], t, s[c0]);
    for (int c = c0 + 1; c <= last; ++c) {
      if (c < fresh_from) continue;
      H[c] = physics::hole_position(frames[c], t, s[c]);
      C[c] = (H[c - 1] - H[c]).normalized();
    }
    const int end = std::min(t.end_disk, L);
    for (int j = first; j <= end; ++j) {
      const double T = tension(j);
      if (T == 0.0) continue;
      Vec3 F = T * C[j];
      if (j < t.end_disk) {
        F += tension(j + 1) * (-C[j + 1]);
        if (remove_normal_) {
          const Vec3 z = frames[j].R.col(2);
          F -= F.dot(z) * z;
        }
      }
      f[j] += F;
      m[j] += (H[j] - frames[j].p).cross(F);
    }
  }
  const physics::LoadCase& lc = b.loads;
  if (lc.has_disk_weight())
    for (int j = first; j <= L; ++j) f[j] += lc.disk_weight(j);
  if (J == n_ && L == J && lc.has_tip_wrench()) {  // Eq. 44-45: the external tip wrench acts at O_n.
    f[J] += lc.tip_force();
    m[J] += lc.tip_moment();
  }
}

void SubsegmentStatics::distal_wrenches(SubsegmentLoads& b, const Frame* frames, const Vec3* backbone_centroid,
                                        Vec3* F, Vec3* M) const {
  disk_loads(b, frames, F, M);
  accumulate_distal(b, frames, backbone_centroid, F, M);
}

void SubsegmentStatics::distal_wrenches(const SubsegmentLoads& b, const Frame* frames, const Vec3* backbone_centroid,
                                        const Vec3* disk_f, const Vec3* disk_m, Vec3* F, Vec3* M) const {
  for (int j = 1; j <= b.active; ++j) {
    F[j] = disk_f[j];
    M[j] = disk_m[j];
  }
  accumulate_distal(b, frames, backbone_centroid, F, M);
}

void SubsegmentStatics::accumulate_distal(const SubsegmentLoads& b, const Frame* frames, const Vec3* backbone_centroid,
                                          Vec3* F, Vec3* M) const {
  const int J = b.active;
  const bool bb = b.loads.has_backbone_weight();
  for (int j = J - 1; j >= 1; --j) {
    // Eq. 46-47: propagate the wrench of the distal subsegments from O_{j+1} to O_j.
    const Vec3& pj = frames[j].p;
    F[j] += F[j + 1];
    M[j] += M[j + 1] + (frames[j + 1].p - pj).cross(F[j + 1]);
    if (bb) {
      const Vec3 W = backbone_weight(b, j + 1);
      F[j] += W;
      M[j] += (backbone_centroid[j + 1] - pj).cross(W);
    }
  }
}

}  // namespace tdcr::detail
