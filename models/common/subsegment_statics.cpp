#include "common/subsegment_statics.hpp"

#include <algorithm>

#include "tdcr/models/tendon_physics.hpp"

namespace tdcr::detail {

SubsegmentStatics::SubsegmentStatics(const Scene& scene) {
  const Robot& robot = scene.robot;
  routing_ = TendonRouting::from(robot);
  tensions_ = scene.actuation.values;
  n_ = routing_.disk_count() - 1;
  const SceneEffects e = scene.active_effects();
  tip_wrench_on_ = e.tip_wrench;
  disk_weight_on_ = e.disk_weight;
  backbone_weight_on_ = e.backbone_weight;
  remove_normal_ = e.disk_normal_force_removed;
  tip_force_ = scene.loads.tip_force;
  tip_moment_ = scene.loads.tip_moment;

  length_.assign(n_ + 1, 0.0);
  disk_weight_.assign(n_ + 1, Vec3::Zero());
  backbone_weight_.assign(n_ + 1, Vec3::Zero());
  const double linear_mass = robot.backbone.linear_mass();
  for (int j = 1; j <= n_; ++j) {
    length_[j] = routing_.disk_s[j] - routing_.disk_s[j - 1];
    const int seg = routing_.disk_segment[j];
    if (disk_weight_on_) disk_weight_[j] = robot.segments[seg].disk_mass * scene.loads.gravity;
    if (backbone_weight_on_) backbone_weight_[j] = linear_mass * length_[j] * scene.loads.gravity;
  }

  // Last disk that carries any load: beyond it the robot is straight.
  if (tip_wrench_on_ || e.gravity) {
    active_ = n_;
  } else {
    active_ = 0;
    for (const RoutedTendon& t : routing_.tendons)
      if (tensions_[t.index] != 0.0) active_ = std::max(active_, t.end_disk);
  }
}

void SubsegmentStatics::distal_wrenches(const Frame* frames, const Vec3* backbone_centroid, Vec3* F,
                                        Vec3* M) const {
  const int J = active_;
  if (J == 0) return;
  for (int j = J; j >= 1; --j) {
    // Eq. 30-33 (+ Eq. 58): the tendon forces at disk j, moment about O_j.
    const tendon::DiskWrench w = tendon::disk_wrench(j, frames, routing_, tensions_.data(), remove_normal_);
    Vec3 f = w.force;
    Vec3 m = w.moment;
    if (disk_weight_on_) f += disk_weight_[j];
    if (j == n_) {
      if (tip_wrench_on_) {  // Eq. 44-45: the external tip wrench acts at O_n.
        f += tip_force_;
        m += tip_moment_;
      }
    } else if (j < J) {
      // Eq. 46-47: propagate the wrench of the distal subsegments from O_{j+1} to O_j.
      const Vec3& pj = frames[j].p;
      Vec3 fd = F[j + 1];
      m += M[j + 1] + (frames[j + 1].p - pj).cross(F[j + 1]);
      if (backbone_weight_on_) {
        fd += backbone_weight_[j + 1];
        m += (backbone_centroid[j + 1] - pj).cross(backbone_weight_[j + 1]);
      }
      f += fd;
    }
    F[j] = f;
    M[j] = m;
  }
}

}  // namespace tdcr::detail
