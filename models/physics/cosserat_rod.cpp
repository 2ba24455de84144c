// The Cosserat rod of cosserat_rod.hpp: state helpers, section, and the run-time dispatch of its
// right-hand side (physics/cosserat_rhs.hpp).
#include "tdcr/models/cosserat_rod.hpp"

#include "physics/cosserat_rhs.hpp"
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
  s.kbt = Vec3(k.EI, k.EI, k.GJ);
  s.kse = Vec3(k.GA, k.GA, k.EA);
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

TendonLoad TendonLoad::make(const Vec3& r, double T) { return TendonLoad{r, lie::hat(r), T}; }

// flatten: GCC otherwise keeps the small Eigen products (R^T n, R hat(u), crosses) as calls in
// this large function, a quarter of VCref's time at few disks.
#if defined(__GNUC__) && !defined(__clang__)
#define TDCR_FLATTEN __attribute__((flatten))
#else
#define TDCR_FLATTEN
#endif

TDCR_FLATTEN Strains rod_rhs(const Section& section, const TendonLoad* tendons, int count, const double* y,
                             double* dyds) {
  detail::StrainsT<double> e;
  if (section.shear_extension)
    e = section.gravity ? detail::rod_rhs<true, true>(section, tendons, count, y, dyds)
                        : detail::rod_rhs<true, false>(section, tendons, count, y, dyds);
  else
    e = section.gravity ? detail::rod_rhs<false, true>(section, tendons, count, y, dyds)
                        : detail::rod_rhs<false, false>(section, tendons, count, y, dyds);
  return {e.u, e.v};
}

void FreeRod::rhs(double, const double* y, double* dyds) const { rod_rhs(section_, nullptr, 0, y, dyds); }

}  // namespace tdcr::cosserat
