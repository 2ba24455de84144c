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

/// The inverse of a symmetric positive definite 3x3 matrix by cofactors.
EIGEN_ALWAYS_INLINE Mat3 spd_inverse(const Mat3& A) {
  const double c00 = A(1, 1) * A(2, 2) - A(1, 2) * A(1, 2);
  const double c01 = A(0, 2) * A(1, 2) - A(0, 1) * A(2, 2);
  const double c02 = A(0, 1) * A(1, 2) - A(0, 2) * A(1, 1);
  const double c11 = A(0, 0) * A(2, 2) - A(0, 2) * A(0, 2);
  const double c12 = A(0, 1) * A(0, 2) - A(0, 0) * A(1, 2);
  const double c22 = A(0, 0) * A(1, 1) - A(0, 1) * A(0, 1);
  const double inv_det = 1.0 / (A(0, 0) * c00 + A(0, 1) * c01 + A(0, 2) * c02);
  Mat3 B;
  B << c00, c01, c02, c01, c11, c12, c02, c12, c22;
  return B * inv_det;
}

/// K x = b for symmetric positive definite 3x3 K (a dual-number overload is found by ADL).
EIGEN_ALWAYS_INLINE Vec3 spd_solve(const Mat3& K, const Vec3& b) { return spd_inverse(K) * b; }

/// The factors of a symmetric positive definite block matrix [P, Q; Q^T, S] (3x3 blocks) by its
/// Schur complement: P^-1, X = P^-1 Q and (S - Q^T X)^-1, closed forms throughout.
struct SpdBlocks {
  Mat3 Pinv, X, Cinv;
  EIGEN_ALWAYS_INLINE SpdBlocks(const Mat3& P, const Mat3& Q, const Mat3& S) : Pinv(spd_inverse(P)) {
    X.noalias() = Pinv * Q;
    Mat3 C = S;
    C.noalias() -= Q.transpose() * X;
    Cinv = spd_inverse(C);
  }
  /// [P, Q; Q^T, S] (x1; x2) = (b1; b2) for one or several right-hand sides.
  template <typename B1, typename B2, typename X1, typename X2>
  EIGEN_ALWAYS_INLINE void solve(const Mat3& Q, const B1& b1, const B2& b2, X1& x1, X2& x2) const {
    const auto y1 = (Pinv * b1).eval();
    x2.noalias() = Cinv * (b2 - Q.transpose() * y1);
    x1 = y1;
    x1.noalias() -= X * x2;
  }
};

/// [P, Q; Q^T, S] (x1; x2) = (b1; b2), the matrix symmetric positive definite with 3x3 blocks
/// (a dual-number overload is found by ADL).
EIGEN_ALWAYS_INLINE void spd_block_solve(const Mat3& P, const Mat3& Q, const Mat3& S, const Vec3& b1, const Vec3& b2,
                                         Vec3& x1, Vec3& x2) {
  SpdBlocks(P, Q, S).solve(Q, b1, b2, x1, x2);
}

/// The tendons' sums of the rod's balance at one point, for the linear system in (v_s, u_s).
/// With t_k = q_k / |q_k|, c_k = T_k / |q_k| and w_k = r_k x t_k: A_k = c_k (I - t_k t_k^T),
/// A_k [r_k]x = c_k ([r_k]x + t_k w_k^T), [r_k]x A_k [r_k]x = c_k ([r_k]x^2 + w_k w_k^T), [r]x^2 =
/// r r^T - |r|^2 I: sums of scaled symmetric outer products instead of 3x3 matrix products. G
/// holds the lower triangle (row by row) of sum c_k g_k g_k^T, g_k = (t_k, w_k); H that of
/// sum c_k [r_k]x^2. Shared by the statics (rod_rhs) and VC's time steps (models/vc/vc_dynamics_rod.cpp).
template <typename T>
struct TendonSums {
  T G[21], H[6];
  T sum_c;
  Vec3T<T> sum_cr;  ///< sum c_k r_k
  Vec3T<T> suma;    ///< sum a_k
  Vec3T<T> sumra;   ///< sum r_k x a_k

  /// sum A_k [r_k]x = hat(sum c_k r_k) + sum c_k t_k w_k^T.
  EIGEN_ALWAYS_INLINE Mat3T<T> sum_a_r() const {
    Mat3T<T> out = hat(sum_cr);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) out(i, j) += G[(3 + j) * (4 + j) / 2 + i];
    return out;
  }
  /// K_bt - sum [r_k]x A_k [r_k]x.
  EIGEN_ALWAYS_INLINE Mat3T<T> k22(const Vec3& kbt) const {
    Mat3T<T> K;
    for (int i = 0, e = 0; i < 3; ++i)
      for (int j = 0; j <= i; ++j, ++e) K(i, j) = K(j, i) = -(H[e] + G[(3 + i) * (4 + i) / 2 + 3 + j]);
    K.diagonal() += kbt;
    return K;
  }
  /// K_se + sum A_k.
  EIGEN_ALWAYS_INLINE Mat3T<T> k11(const Vec3& kse) const {
    Mat3T<T> K;
    for (int i = 0, e = 0; i < 3; ++i)
      for (int j = 0; j <= i; ++j, ++e) K(i, j) = K(j, i) = -G[e];
    K.diagonal().array() += sum_c;
    K.diagonal() += kse;
    return K;
  }
};

/// The tendon sums of `count` tendons at strains (v, u). Routed: see rod_rhs.
template <bool Routed, typename T>
EIGEN_ALWAYS_INLINE void tendon_sums(const TendonLoad* tendons, int count, const Vec3T<T>& v, const Vec3T<T>& u,
                                     TendonSums<T>& S) {
  using V3 = Vec3T<T>;
  for (T& g : S.G) g = T(0.0);
  for (T& h : S.H) h = T(0.0);
  S.sum_c = T(0.0);
  S.sum_cr = V3::Zero();
  S.suma = V3::Zero();
  S.sumra = V3::Zero();
  for (int k = 0; k < count; ++k) {
    const TendonLoad& t = tendons[k];
    V3 q = tangent(v, u, t.r);
    if constexpr (Routed) q += t.dr;
    const T inv_q = 1.0 / q.norm();
    const V3 tk = q * inv_q;
    const T c = t.T * inv_q;
    const V3 w = -cross(tk, t.r);  // r_k x t_k
    const T g[6] = {tk.x(), tk.y(), tk.z(), w.x(), w.y(), w.z()};
    for (int i = 0, e = 0; i < 6; ++i) {
      const T cg = c * g[i];
      for (int j = 0; j <= i; ++j, ++e) S.G[e] += cg * g[j];
    }
    const Vec3& r = t.r;
    const double r2 = r.squaredNorm();
    const double rr[6] = {r.x() * r.x() - r2, r.y() * r.x(), r.y() * r.y() - r2,
                          r.z() * r.x(), r.z() * r.y(), r.z() * r.z() - r2};
    for (int e = 0; e < 6; ++e) S.H[e] += c * rr[e];
    S.sum_c += c;
    S.sum_cr += c * r;
    V3 a = c * u.cross(q);  // = A_k (u x q_k): u x q_k is normal to q_k
    if constexpr (Routed) {
      const V3 z = cross(u, t.dr) + t.ddr;
      a += c * (z - tk * tk.dot(z));  // A_k z
    }
    S.suma += a;
    if constexpr (std::is_same_v<T, double>)
      S.sumra += r.cross(a);
    else
      S.sumra -= cross(a, r);  // r_k x a_k
  }
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
  TendonSums<T> sums;
  tendon_sums<Routed>(tendons, count, v, u, sums);
  const M3 sumAr = sums.sum_a_r();
  const M3 K22 = sums.k22(S.kbt);
  V3 fe_b = V3::Zero();
  if constexpr (Gravity) fe_b = R.transpose() * S.weight;
  const V3 b_m = -u.cross(mb) - v.cross(nb) - sums.sumra;
  if constexpr (Shear) {
    const M3 K11 = sums.k11(S.kse);
    const V3 b_n = -u.cross(nb) - sums.suma - fe_b;
    V3 vs, us;
    spd_block_solve(K11, M3(-sumAr), K22, b_n, b_m, vs, us);
    dn_out = R * (S.kse.cwiseProduct(vs) + u.cross(nb));
    dm_out = R * (S.kbt.cwiseProduct(us) + u.cross(mb));
  } else {
    const V3 us = spd_solve(K22, b_m);
    // Body-frame tendon force sum a_k + A_k (u_s x r_k) = sum a_k - (sum A_k [r_k]x) u_s.
    const V3 fb = sums.suma - sumAr * us;
    V3 dn = -(R * fb);
    if constexpr (Gravity) dn -= S.weight;
    dn_out = dn;
    dm_out = R * (S.kbt.cwiseProduct(us) + u.cross(mb));
  }
  return {u, v};
}

}  // namespace tdcr::cosserat::detail
