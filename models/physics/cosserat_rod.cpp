// The Cosserat rod's right-hand side, written once (cosserat_rod.hpp): the free rod and the rod
// loaded by fully constrained tendons, specialised at compile time for shear/extension and
// gravity so that the inner loop carries no branch for an effect that is off.
#include "tdcr/models/cosserat_rod.hpp"

#include <Eigen/Cholesky>

#include "physics/tendon_path.hpp"
#include "tdcr/core/lie.hpp"

namespace tdcr::cosserat {

namespace {

using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;

template <bool Shear, bool Gravity>
Strains rhs_impl(const Section& S, const TendonLoad* tendons, int count, const double* y, double* dyds) {
  const Eigen::Map<const Mat3> R = rotation(y);
  const Vec3 n = force(y);
  const Vec3 m = moment(y);
  const Vec3 nb = R.transpose() * n;
  const Vec3 mb = R.transpose() * m;
  const Vec3 u = S.inv_kbt.cwiseProduct(mb);
  Vec3 v = Vec3::UnitZ();
  if constexpr (Shear) v += S.inv_kse.cwiseProduct(nb);
  const Vec3 dp = R * v;
  position(dyds) = dp;
  rotation(dyds) = R * lie::hat(u);

  if (count == 0) {
    // Free rod: no tendon load, no linear solve.
    if constexpr (Gravity)
      force(dyds) = -S.weight;
    else
      force(dyds).setZero();
    moment(dyds) = -dp.cross(n);
    return {u, v};
  }
  Mat3 sumA = Mat3::Zero();    // sum A_k
  Mat3 sumAr = Mat3::Zero();   // sum A_k [r_k]x
  Mat3 sumrAr = Mat3::Zero();  // sum [r_k]x A_k [r_k]x
  Vec3 suma = Vec3::Zero();    // sum a_k
  Vec3 sumra = Vec3::Zero();   // sum r_k x a_k
  for (int k = 0; k < count; ++k) {
    const TendonLoad& t = tendons[k];
    const Vec3 q = physics::tendon_tangent(v, u, t.r);
    const double inv_q = 1.0 / q.norm();
    const Vec3 tk = q * inv_q;
    const double c = t.T * inv_q;
    const Mat3 A = c * (Mat3::Identity() - tk * tk.transpose());
    const Vec3 a = c * u.cross(q);
    const Mat3 Ar = A * t.rx;
    if constexpr (Shear) sumA += A;
    sumAr += Ar;
    sumrAr.noalias() += t.rx * Ar;
    suma += a;
    sumra += t.r.cross(a);
  }
  Vec3 fe_b = Vec3::Zero();
  if constexpr (Gravity) fe_b = R.transpose() * S.weight;
  const Vec3 b_m = -u.cross(mb) - v.cross(nb) - sumra;
  if constexpr (Shear) {
    Mat6 K;
    K.topLeftCorner<3, 3>() = sumA;
    K.topLeftCorner<3, 3>().diagonal() += S.kse;
    K.topRightCorner<3, 3>() = -sumAr;
    K.bottomLeftCorner<3, 3>() = -sumAr.transpose();  // = sum [r]x A (A symmetric)
    K.bottomRightCorner<3, 3>() = -sumrAr;
    K.bottomRightCorner<3, 3>().diagonal() += S.kbt;
    Vec6 b;
    b.head<3>() = -u.cross(nb) - suma - fe_b;
    b.tail<3>() = b_m;
    const Vec6 x = K.llt().solve(b);
    const Vec3 vs = x.head<3>();
    const Vec3 us = x.tail<3>();
    force(dyds) = R * (S.kse.cwiseProduct(vs) + u.cross(nb));
    moment(dyds) = R * (S.kbt.cwiseProduct(us) + u.cross(mb));
  } else {
    Mat3 K = -sumrAr;
    K.diagonal() += S.kbt;
    const Vec3 us = K.llt().solve(b_m);
    // Body-frame tendon force sum a_k + A_k (u_s x r_k) = sum a_k - (sum A_k [r_k]x) u_s.
    const Vec3 fb = suma - sumAr * us;
    Vec3 dn = -(R * fb);
    if constexpr (Gravity) dn -= S.weight;
    force(dyds) = dn;
    moment(dyds) = R * (S.kbt.cwiseProduct(us) + u.cross(mb));
  }
  return {u, v};
}

}  // namespace

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

Strains rod_rhs(const Section& section, const TendonLoad* tendons, int count, const double* y, double* dyds) {
  if (section.shear_extension)
    return section.gravity ? rhs_impl<true, true>(section, tendons, count, y, dyds)
                           : rhs_impl<true, false>(section, tendons, count, y, dyds);
  return section.gravity ? rhs_impl<false, true>(section, tendons, count, y, dyds)
                         : rhs_impl<false, false>(section, tendons, count, y, dyds);
}

void FreeRod::rhs(double, const double* y, double* dyds) const { rod_rhs(section_, nullptr, 0, y, dyds); }

}  // namespace tdcr::cosserat
