#include "common/subsegment_statics.hpp"

#include <algorithm>

#include "tdcr/models/tendon_physics.hpp"

namespace tdcr::detail {

void SubsegmentLoads::set_load_factor(double lambda) {
  loads.set_load_factor(lambda);
  const std::vector<double>& full = loads.full_tensions();
  for (std::size_t k = 0; k < full.size(); ++k) tensions[k] = lambda * full[k];
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

void SubsegmentStatics::disk_load(const SubsegmentLoads& b, int j, const Frame* frames, Vec3& f, Vec3& m) const {
  const physics::LoadCase& L = b.loads;
  // Eq. 30-33 (+ Eq. 58): the tendon forces at disk j, moment about O_j.
  const tendon::DiskWrench w = friction_on_
                                   ? tendon::disk_wrench_friction(j, frames, *routing_, b.chord.data(), remove_normal_)
                                   : tendon::disk_wrench(j, frames, *routing_, b.tensions.data(), remove_normal_);
  f = w.force;
  m = w.moment;
  if (L.has_disk_weight()) f += L.disk_weight(j);
  if (j == n_ && L.has_tip_wrench()) {  // Eq. 44-45: the external tip wrench acts at O_n.
    f += L.tip_force();
    m += L.tip_moment();
  }
}

void SubsegmentStatics::distal_wrenches(const SubsegmentLoads& b, const Frame* frames, const Vec3* backbone_centroid,
                                        Vec3* F, Vec3* M) const {
  const int J = b.active;
  const bool bb = b.loads.has_backbone_weight();
  for (int j = J; j >= 1; --j) {
    Vec3 f, m;
    disk_load(b, j, frames, f, m);
    if (j < J) {
      // Eq. 46-47: propagate the wrench of the distal subsegments from O_{j+1} to O_j.
      const Vec3& pj = frames[j].p;
      f += F[j + 1];
      m += M[j + 1] + (frames[j + 1].p - pj).cross(F[j + 1]);
      if (bb) {
        const Vec3 W = backbone_weight(b, j + 1);
        f += W;
        m += (backbone_centroid[j + 1] - pj).cross(W);
      }
    }
    F[j] = f;
    M[j] = m;
  }
}

}  // namespace tdcr::detail
