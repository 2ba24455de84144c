#include "tdcr/models/cosserat_rod.hpp"

#include "tdcr/core/lie.hpp"

namespace tdcr::cosserat {

State make_state(const Frame& f, const Vec3& n, const Vec3& m) {
  State y;
  position(y.data()) = f.p;
  rotation(y.data()) = f.R;
  force(y.data()) = n;
  moment(y.data()) = m;
  return y;
}

Frame frame_of(const double* y) { return Frame{rotation(y), position(y)}; }

Section Section::from(const Robot& robot, const Effects& effects, const Vec3& weight) {
  Section s;
  const BackboneStiffness k = robot.backbone.effective_stiffness();
  s.inv_kbt = Vec3(1.0 / k.EI, 1.0 / k.EI, 1.0 / k.GJ);
  s.inv_kse = Vec3(1.0 / k.GA, 1.0 / k.GA, 1.0 / k.EA);
  s.shear_extension = effects.shear_extension;
  s.gravity = weight.squaredNorm() > 0.0;
  s.weight = weight;
  return s;
}

Section Section::from(const Scene& scene) {
  const SceneEffects e = scene.active_effects();
  const Vec3 w = e.backbone_weight ? Vec3(scene.robot.backbone.linear_mass() * scene.loads.gravity) : Vec3::Zero();
  return from(scene.robot, scene.effects, w);
}

void FreeRod::rhs(double, const double* y, double* dyds) const {
  const Eigen::Map<const Mat3> R = rotation(y);
  const Vec3 n = force(y);
  const Vec3 u = section_.curvature(R, moment(y));
  const Vec3 v = section_.strain(R, n);
  const Vec3 dp = R * v;
  position(dyds) = dp;
  rotation(dyds) = R * lie::hat(u);
  if (section_.gravity) {
    force(dyds) = -section_.weight;
  } else {
    force(dyds).setZero();
  }
  moment(dyds) = -dp.cross(n);
}

}  // namespace tdcr::cosserat
