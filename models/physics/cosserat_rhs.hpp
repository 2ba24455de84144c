// Private to models/: the Cosserat rod's right-hand side as a template (cosserat_rod.hpp,
// cosserat::rod_rhs), specialised at compile time for shear/extension and gravity so that the
// inner loop carries no branch for an effect that is off. Included where a rod ODE wants it
// inlined (the public rod_rhs and FreeRod dispatch to it at run time).
#pragma once

#include <Eigen/Cholesky>

#include "physics/tendon_path.hpp"
#include "tdcr/core/lie.hpp"
#include "tdcr/models/cosserat_rod.hpp"

namespace tdcr::cosserat::detail {

using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;

/// cosserat::rod_rhs for one combination of the section's shear/extension and gravity flags.
template <bool Shear, bool Gravity>
EIGEN_ALWAYS_INLINE Strains rod_rhs(const Section& S, const TendonLoad* tendons, int count, const double* y, double* dyds) {
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

}  // namespace tdcr::cosserat::detail
