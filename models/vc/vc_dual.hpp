// Private to models/vc: the forward-mode dual number of VC's exact shooting Jacobian (a value and
// its derivatives with respect to the 6 base unknowns n(0), m(0)), and the kink map of a disk in
// either scalar type.
#pragma once

#include <cmath>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "physics/cosserat_rhs.hpp"
#include "tdcr/models/cosserat_rod.hpp"

namespace tdcr::vc {

using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;

/// A value and its derivatives with respect to the 6 base unknowns n(0), m(0): forward-mode
/// automatic differentiation on plain fixed arrays (no allocation, loops the compiler
/// vectorises).
struct Dual {
  double v = 0.0;
  double d[6];  ///< Uninitialised by the default constructor (every use writes it first).
  EIGEN_ALWAYS_INLINE Dual() {}  // NOLINT
  EIGEN_ALWAYS_INLINE Dual(double value) : v(value), d{0.0, 0.0, 0.0, 0.0, 0.0, 0.0} {}  // NOLINT: a constant converts implicitly, as in Eigen code
  /// The unknown `k` of 6 (seeded with a unit derivative).
  EIGEN_ALWAYS_INLINE static Dual variable(double value, int k) {
    Dual x(value);
    x.d[k] = 1.0;
    return x;
  }
  Eigen::Map<const Vec6> derivatives() const { return Eigen::Map<const Vec6>(d); }
  EIGEN_ALWAYS_INLINE Dual& operator+=(const Dual& b) {
    v += b.v;
    for (int k = 0; k < 6; ++k) d[k] += b.d[k];
    return *this;
  }
  EIGEN_ALWAYS_INLINE Dual& operator-=(const Dual& b) {
    v -= b.v;
    for (int k = 0; k < 6; ++k) d[k] -= b.d[k];
    return *this;
  }
  EIGEN_ALWAYS_INLINE Dual& operator*=(const Dual& b) {
    for (int k = 0; k < 6; ++k) d[k] = d[k] * b.v + v * b.d[k];
    v *= b.v;
    return *this;
  }
  EIGEN_ALWAYS_INLINE Dual& operator/=(const Dual& b) {
    const double inv = 1.0 / b.v;
    v *= inv;
    for (int k = 0; k < 6; ++k) d[k] = (d[k] - v * b.d[k]) * inv;
    return *this;
  }
};

EIGEN_ALWAYS_INLINE Dual operator+(Dual a, const Dual& b) { return a += b; }
EIGEN_ALWAYS_INLINE Dual operator-(Dual a, const Dual& b) { return a -= b; }
EIGEN_ALWAYS_INLINE Dual operator*(Dual a, const Dual& b) { return a *= b; }
EIGEN_ALWAYS_INLINE Dual operator/(Dual a, const Dual& b) { return a /= b; }
EIGEN_ALWAYS_INLINE Dual operator-(const Dual& a) {
  Dual r;
  r.v = -a.v;
  for (int k = 0; k < 6; ++k) r.d[k] = -a.d[k];
  return r;
}
EIGEN_ALWAYS_INLINE Dual operator+(Dual a, double b) { return a.v += b, a; }
EIGEN_ALWAYS_INLINE Dual operator+(double b, Dual a) { return a.v += b, a; }
EIGEN_ALWAYS_INLINE Dual operator-(Dual a, double b) { return a.v -= b, a; }
EIGEN_ALWAYS_INLINE Dual operator-(double b, const Dual& a) { return -a + b; }
EIGEN_ALWAYS_INLINE Dual operator*(Dual a, double b) {
  a.v *= b;
  for (int k = 0; k < 6; ++k) a.d[k] *= b;
  return a;
}
EIGEN_ALWAYS_INLINE Dual operator*(double b, const Dual& a) { return a * b; }
EIGEN_ALWAYS_INLINE Dual operator/(const Dual& a, double b) { return a * (1.0 / b); }
EIGEN_ALWAYS_INLINE Dual operator/(double a, const Dual& b) {
  Dual r;
  r.v = a / b.v;
  const double c = -r.v / b.v;
  for (int k = 0; k < 6; ++k) r.d[k] = c * b.d[k];
  return r;
}
EIGEN_ALWAYS_INLINE Dual sqrt(const Dual& a) {
  Dual r;
  r.v = std::sqrt(a.v);
  const double c = 0.5 / r.v;
  for (int k = 0; k < 6; ++k) r.d[k] = c * a.d[k];
  return r;
}
EIGEN_ALWAYS_INLINE bool isfinite(const Dual& a) { return std::isfinite(a.v) && a.derivatives().allFinite(); }

template <typename T>
using Vec3T = cosserat::detail::Vec3T<T>;
template <typename T>
using Mat3T = cosserat::detail::Mat3T<T>;
template <typename T>
using Vec6T = Eigen::Matrix<T, 6, 1>;

/// K x = b for symmetric positive definite K in dual numbers (found by rod_rhs through ADL):
/// one factorisation of the values, x' = K^-1 (b' - K' x) for the derivatives.
template <int N>
Eigen::Matrix<Dual, N, 1> spd_solve(const Eigen::Matrix<Dual, N, N>& K, const Eigen::Matrix<Dual, N, 1>& b) {
  Eigen::Matrix<double, N, N> Kv;
  Eigen::Matrix<double, N, 1> bv;
  for (int j = 0; j < N; ++j) {
    bv[j] = b[j].v;
    for (int i = 0; i < N; ++i) Kv(i, j) = K(i, j).v;
  }
  const Eigen::LLT<Eigen::Matrix<double, N, N>> llt(Kv);
  const Eigen::Matrix<double, N, 1> xv = llt.solve(bv);
  Eigen::Matrix<double, N, 6> rhs;
  for (int i = 0; i < N; ++i) {
    rhs.row(i) = b[i].derivatives().transpose();
    for (int j = 0; j < N; ++j) rhs.row(i) -= xv[j] * K(i, j).derivatives().transpose();
  }
  Eigen::Matrix<double, N, 6> dx;
  for (int k = 0; k < 6; ++k) dx.col(k) = llt.solve(rhs.col(k));  // vector solves: no blocked kernel
  Eigen::Matrix<Dual, N, 1> x;
  for (int i = 0; i < N; ++i) {
    x[i].v = xv[i];
    for (int k = 0; k < 6; ++k) x[i].d[k] = dx(i, k);
  }
  return x;
}

}  // namespace tdcr::vc

namespace Eigen {

template <>
struct NumTraits<tdcr::vc::Dual> : NumTraits<double> {
  using Real = tdcr::vc::Dual;
  using NonInteger = tdcr::vc::Dual;
  using Nested = tdcr::vc::Dual;
  using Literal = tdcr::vc::Dual;
  enum { IsComplex = 0, IsInteger = 0, IsSigned = 1, RequireInitialization = 1, ReadCost = 7, AddCost = 7, MulCost = 13 };
};
template <typename BinOp>
struct ScalarBinaryOpTraits<tdcr::vc::Dual, double, BinOp> {
  using ReturnType = tdcr::vc::Dual;
};
template <typename BinOp>
struct ScalarBinaryOpTraits<double, tdcr::vc::Dual, BinOp> {
  using ReturnType = tdcr::vc::Dual;
};

}  // namespace Eigen

namespace tdcr::vc {

/// cosserat::detail::spd_block_solve in dual numbers (found by rod_rhs through ADL): one
/// factorisation of the values, x' = K^-1 (b' - K' x) for the derivatives.
inline void spd_block_solve(const Mat3T<Dual>& P, const Mat3T<Dual>& Q, const Mat3T<Dual>& S, const Vec3T<Dual>& b1,
                            const Vec3T<Dual>& b2, Vec3T<Dual>& x1, Vec3T<Dual>& x2) {
  const auto value = [](const Dual& d) { return d.v; };
  const Mat3 Qv = Q.unaryExpr(value);
  const cosserat::detail::SpdBlocks F(P.unaryExpr(value), Qv, S.unaryExpr(value));
  Vec3 x1v, x2v;
  F.solve(Qv, Vec3(b1.unaryExpr(value)), Vec3(b2.unaryExpr(value)), x1v, x2v);
  Eigen::Matrix<double, 3, 6> r1, r2;
  for (int i = 0; i < 3; ++i) {
    r1.row(i) = b1[i].derivatives().transpose();
    r2.row(i) = b2[i].derivatives().transpose();
    for (int j = 0; j < 3; ++j) {
      r1.row(i) -= x1v[j] * P(i, j).derivatives().transpose() + x2v[j] * Q(i, j).derivatives().transpose();
      r2.row(i) -= x1v[j] * Q(j, i).derivatives().transpose() + x2v[j] * S(i, j).derivatives().transpose();
    }
  }
  Eigen::Matrix<double, 3, 6> d1, d2;
  F.solve(Qv, r1, r2, d1, d2);
  for (int i = 0; i < 3; ++i) {
    x1[i].v = x1v[i];
    x2[i].v = x2v[i];
    for (int k = 0; k < 6; ++k) {
      x1[i].d[k] = d1(i, k);
      x2[i].d[k] = d2(i, k);
    }
  }
}

/// The wrench just distal of a disk's kinks as a function of itself: z = (n+, m+) maps to the
/// wrench before the kinks minus the kink wrench of the continuing tendons at the strains z gives.
template <typename T>
struct KinkMap {
  const cosserat::Section& S;
  Mat3T<T> R;
  Vec3T<T> u;  ///< Strains just proximal of the disk.
  Vec3T<T> v;
  const std::vector<cosserat::TendonLoad>& tendons;
  Vec6T<T> base;  ///< The wrench before the kinks.
  Vec6T<T> operator()(const Vec6T<T>& z) const {
    using cosserat::detail::tangent;
    const Vec3T<T> up = cosserat::detail::curvature<T>(S, R, z.template tail<3>());
    const Vec3T<T> vp = cosserat::detail::strain<T>(S, R, z.template head<3>());
    Vec6T<T> g = base;
    for (const cosserat::TendonLoad& t : tendons) {
      const Vec3T<T> qm = tangent(v, u, t);
      const Vec3T<T> qp = tangent(vp, up, t);
      const Vec3T<T> K = t.T * (R * (qp / qp.norm() - qm / qm.norm()));
      g.template head<3>() -= K;
      g.template tail<3>() -= (R * t.r).cross(K);
    }
    return g;
  }
};

}  // namespace tdcr::vc
