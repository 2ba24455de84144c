// Private to models/: the Cosserat rod's right-hand side as a template (cosserat_rod.hpp,
// cosserat::rod_rhs), specialised at compile time for shear/extension and gravity so that the
// inner loop carries no branch for an effect that is off, and on the scalar type: double, or a
// forward-mode dual number (models/vc/vc_dual.hpp) for exact derivatives of a shot (VC's
// shooting Jacobian). Included where a rod ODE wants it inlined (the public rod_rhs and FreeRod
// dispatch to it at run time).
#pragma once

#include <type_traits>

#include <Eigen/Cholesky>

#include "physics/tendon_path.hpp"
#include "tdcr/core/lie.hpp"
#include "tdcr/models/cosserat_rod.hpp"

namespace tdcr::cosserat::detail {

using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;
template <typename T>
using Vec3T = Eigen::Matrix<T, 3, 1>;
template <typename T>
using Mat3T = Eigen::Matrix<T, 3, 3>;

/// The strains rod_rhs evaluated, in its scalar type.
template <typename T>
struct StrainsT {
  Vec3T<T> u;
  Vec3T<T> v;
};

/// a x b with b constant (a dual times a double costs a scaled derivative, not a product rule).
template <typename T>
EIGEN_ALWAYS_INLINE Vec3T<T> cross(const Vec3T<T>& a, const Vec3& b) {
  if constexpr (std::is_same_v<T, double>) {
    return a.cross(b);
  } else {
    return Vec3T<T>(a.y() * b.z() - a.z() * b.y(), a.z() * b.x() - a.x() * b.z(), a.x() * b.y() - a.y() * b.x());
  }
}

/// [u]x in the scalar type.
template <typename T>
EIGEN_ALWAYS_INLINE Mat3T<T> hat(const Vec3T<T>& u) {
  if constexpr (std::is_same_v<T, double>) {
    return lie::hat(u);
  } else {
    Mat3T<T> h;
    h << T(0.0), -u.z(), u.y(), u.z(), T(0.0), -u.x(), -u.y(), u.x(), T(0.0);
    return h;
  }
}

/// physics::tendon_tangent without offset rate (straight routing).
template <typename T>
EIGEN_ALWAYS_INLINE Vec3T<T> tangent(const Vec3T<T>& v, const Vec3T<T>& u, const Vec3& r) {
  if constexpr (std::is_same_v<T, double>) {
    return physics::tendon_tangent(v, u, r);
  } else {
    return v + cross(u, r);
  }
}
/// physics::tendon_tangent of a tendon load: v + u x r_k + r_k'.
template <typename T>
EIGEN_ALWAYS_INLINE Vec3T<T> tangent(const Vec3T<T>& v, const Vec3T<T>& u, const TendonLoad& t) {
  return tangent(v, u, t.r) + t.dr;
}

/// Section::curvature and Section::strain in the scalar type.
template <typename T>
EIGEN_ALWAYS_INLINE Vec3T<T> curvature(const Section& S, const Mat3T<T>& R, const Vec3T<T>& m) {
  return S.inv_kbt.cwiseProduct(R.transpose() * m);
}
template <typename T>
EIGEN_ALWAYS_INLINE Vec3T<T> strain(const Section& S, const Mat3T<T>& R, const Vec3T<T>& n) {
  if (!S.shear_extension) return Vec3T<T>(T(0.0), T(0.0), T(1.0));
  Vec3T<T> v = S.inv_kse.cwiseProduct(R.transpose() * n);
  v.z() += 1.0;
  return v;
}

/// K x = b for symmetric positive definite K (a dual-number overload is found by ADL).
template <typename T, int N>
EIGEN_ALWAYS_INLINE Eigen::Matrix<T, N, 1> spd_solve(const Eigen::Matrix<T, N, N>& K, const Eigen::Matrix<T, N, 1>& b) {
  return K.llt().solve(b);
}

/// cosserat::rod_rhs for one combination of the section's shear/extension and gravity flags.
/// Routed: the tendons' offsets vary along s (TendonLoad::dr, ddr, evaluated by the caller at
/// s): the general fully constrained path of Rucker & Webster 2011, tangent q_k = v + u x r_k +
/// r_k' and a_k = A_k (u x q_k + u x r_k' + r_k''); otherwise r_k' = r_k'' = 0 (straight).
template <bool Shear, bool Gravity, bool Routed = false, typename T>
EIGEN_ALWAYS_INLINE StrainsT<T> rod_rhs(const Section& S, const TendonLoad* tendons, int count, const T* y, T* dyds) {
  using V3 = Vec3T<T>;
  using M3 = Mat3T<T>;
  const Eigen::Map<const M3> R(y + 3);
  const Eigen::Map<const V3> n(y + 12);
  const Eigen::Map<const V3> m(y + 15);
  Eigen::Map<V3> dp_out(dyds), dn_out(dyds + 12), dm_out(dyds + 15);
  Eigen::Map<M3> dR_out(dyds + 3);
  const V3 nb = R.transpose() * n;
  const V3 mb = R.transpose() * m;
  const V3 u = S.inv_kbt.cwiseProduct(mb);
  V3 v(T(0.0), T(0.0), T(1.0));
  if constexpr (Shear) v += S.inv_kse.cwiseProduct(nb);
  const V3 dp = R * v;
  dp_out = dp;
  dR_out = R * hat(u);

  if (count == 0) {
    // Free rod: no tendon load, no linear solve.
    if constexpr (Gravity)
      dn_out = -S.weight;
    else
      dn_out.setZero();
    dm_out = -dp.cross(n);
    return {u, v};
  }
  M3 sumA = M3::Zero();    // sum A_k
  M3 sumAr = M3::Zero();   // sum A_k [r_k]x
  M3 sumrAr = M3::Zero();  // sum [r_k]x A_k [r_k]x
  V3 suma = V3::Zero();    // sum a_k
  V3 sumra = V3::Zero();   // sum r_k x a_k
  for (int k = 0; k < count; ++k) {
    const TendonLoad& t = tendons[k];
    V3 q = tangent(v, u, t.r);
    if constexpr (Routed) q += t.dr;
    const T inv_q = 1.0 / q.norm();
    const V3 tk = q * inv_q;
    const T c = t.T * inv_q;
    const M3 A = c * (M3::Identity() - tk * tk.transpose());
    V3 a = c * u.cross(q);  // = A_k (u x q_k): u x q_k is normal to q_k
    if constexpr (Routed) a += A * (cross(u, t.dr) + t.ddr);
    const M3 Ar = A * t.rx;
    if constexpr (Shear) sumA += A;
    sumAr += Ar;
    sumrAr.noalias() += t.rx * Ar;
    suma += a;
    if constexpr (std::is_same_v<T, double>)
      sumra += t.r.cross(a);
    else
      sumra -= cross(a, t.r);  // r_k x a_k
  }
  V3 fe_b = V3::Zero();
  if constexpr (Gravity) fe_b = R.transpose() * S.weight;
  const V3 b_m = -u.cross(mb) - v.cross(nb) - sumra;
  if constexpr (Shear) {
    Eigen::Matrix<T, 6, 6> K;
    K.template topLeftCorner<3, 3>() = sumA;
    K.template topLeftCorner<3, 3>().diagonal() += S.kse;
    K.template topRightCorner<3, 3>() = -sumAr;
    K.template bottomLeftCorner<3, 3>() = -sumAr.transpose();  // = sum [r]x A (A symmetric)
    K.template bottomRightCorner<3, 3>() = -sumrAr;
    K.template bottomRightCorner<3, 3>().diagonal() += S.kbt;
    Eigen::Matrix<T, 6, 1> b;
    b.template head<3>() = -u.cross(nb) - suma - fe_b;
    b.template tail<3>() = b_m;
    const Eigen::Matrix<T, 6, 1> x = spd_solve(K, b);
    const V3 vs = x.template head<3>();
    const V3 us = x.template tail<3>();
    dn_out = R * (S.kse.cwiseProduct(vs) + u.cross(nb));
    dm_out = R * (S.kbt.cwiseProduct(us) + u.cross(mb));
  } else {
    M3 K = -sumrAr;
    K.diagonal() += S.kbt;
    const V3 us = spd_solve(K, b_m);
    // Body-frame tendon force sum a_k + A_k (u_s x r_k) = sum a_k - (sum A_k [r_k]x) u_s.
    const V3 fb = suma - sumAr * us;
    V3 dn = -(R * fb);
    if constexpr (Gravity) dn -= S.weight;
    dn_out = dn;
    dm_out = R * (S.kbt.cwiseProduct(us) + u.cross(mb));
  }
  return {u, v};
}

}  // namespace tdcr::cosserat::detail
