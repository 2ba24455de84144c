#include "physics/load_case.hpp"

#include <algorithm>
#include <cmath>

namespace tdcr::physics {

void LoadCase::bind(const Robot& robot, const TendonRouting& routing, const ModelInput& input) {
  const int N = routing.disk_count() - 1;
  const bool tensions = input.actuation.kind == Actuation::Kind::Tensions;
  tensions_.assign(robot.tendon_count(), 0.0);
  fixed_.clear();
  fixed_tension_.clear();
  if (tensions) std::copy(input.actuation.values.begin(), input.actuation.values.end(), tensions_.begin());
  any_tension_ = std::any_of(tensions_.begin(), tensions_.end(), [](double t) { return t != 0.0; });
  tip_force_ = input.loads.tip_force;
  tip_moment_ = input.loads.tip_moment;
  tip_wrench_ = tip_force_.squaredNorm() > 0.0 || tip_moment_.squaredNorm() > 0.0;
  const Vec3& g = input.loads.gravity;
  const bool gravity = g.squaredNorm() > 0.0;
  const double L = robot.total_length();
  backbone_weight_on_ = gravity && robot.backbone.linear_mass() > 0.0;
  backbone_weight_ = backbone_weight_on_ ? Vec3(robot.backbone.linear_mass() * g) : Vec3::Zero();
  disk_weight_.assign(N + 1, Vec3::Zero());
  disk_weight_on_ = false;
  double weight_sum = backbone_weight_.norm() * L;
  total_weight_ = backbone_weight_ * L;
  if (gravity)
    for (int j = 1; j <= N; ++j) {
      const double m = robot.segments[routing.disk_segment[j]].disk_mass;
      if (m <= 0.0) continue;
      disk_weight_on_ = true;
      disk_weight_[j] = m * g;
      weight_sum += disk_weight_[j].norm();
      total_weight_ += disk_weight_[j];
    }
  double tsum = 0.0, tmoment = 0.0;
  for (const RoutedTendon& t : routing.tendons) {
    tsum += std::abs(tensions_[t.index]);
    tmoment += std::abs(tensions_[t.index]) * t.r.norm();
  }
  force_scale_ = tsum + tip_force_.norm() + tip_moment_.norm() / L + weight_sum + 1e-3;
  moment_scale_ = tmoment + (tip_force_.norm() + weight_sum) * L + tip_moment_.norm() + 1e-3 * L;
  const double EI = robot.backbone.effective_stiffness().EI;
  load_parameter_ = L * L * (total_weight_.norm() + tip_force_.norm()) / EI;
  compression_parameter_ = L * L * std::max(0.0, -(tip_force_ + total_weight_).z()) / EI;
  lambda_ = 1.0;
}

void LoadCase::set_load_factor(double lambda) { lambda_ = lambda; }

}  // namespace tdcr::physics
