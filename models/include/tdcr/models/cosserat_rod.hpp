/// @file cosserat_rod.hpp
/// @brief The Cosserat rod of VC and VCref (paper Eq. 2-3, 24-29, 34-39), written once: state
/// layout, constitutive law and the right-hand side, with an optional distributed load of fully
/// constrained tendons.
///
/// State (18 doubles, all in the base frame): p (3), R (9, column-major), n (3), m (3), where n
/// and m are the rod's own internal force and moment at s (paper Eq. 34-35). Strains come from the
/// constitutive law: u = Kbt^-1 R^T m, v = Kse^-1 R^T n + e_z (Cosserat rod with shear and
/// extension) or v = e_z (inextensible, unshearable Kirchhoff rod). Then (Eq. 2-3, 38-39)
///   p' = R v,  R' = R [u]x,  n' = -(sum f_k + f_e),  m' = -p' x n - sum l_k,
/// with f_e = rho A g the backbone weight when gravity is on and f_k, l_k the distributed force
/// and moment of tendon k (rod_rhs). Internal wrenches as states make jumps at disks
/// (Eq. 40-41) plain additions, and the same state serves both rod variants.
#pragma once

#include <Eigen/Core>

#include "tdcr/bvp/integrator.hpp"
#include "tdcr/core/robot.hpp"
#include "tdcr/core/scene.hpp"
#include "tdcr/core/types.hpp"

namespace tdcr::cosserat {

constexpr int kStateSize = 18;                          ///< p, R, n, m.
using State = Eigen::Matrix<double, kStateSize, 1>;     ///< Fixed-size rod state.

/// @name Views of the state's parts
/// Eigen maps onto the 18 doubles of a state (no copies): writable for `double*`, read-only
/// for `const double*`.
/// @{

/// @brief Backbone position p (m, base frame): y[0..2].
inline Eigen::Map<Vec3> position(double* y) { return Eigen::Map<Vec3>(y); }
/// @brief Backbone position p (m, base frame): y[0..2], read-only.
inline Eigen::Map<const Vec3> position(const double* y) { return Eigen::Map<const Vec3>(y); }
/// @brief Material frame orientation R (body to base frame): y[3..11], column-major.
inline Eigen::Map<Mat3> rotation(double* y) { return Eigen::Map<Mat3>(y + 3); }
/// @brief Material frame orientation R: y[3..11], column-major, read-only.
inline Eigen::Map<const Mat3> rotation(const double* y) { return Eigen::Map<const Mat3>(y + 3); }
/// @brief Internal force n (N, base frame; Eq. 34): y[12..14].
inline Eigen::Map<Vec3> force(double* y) { return Eigen::Map<Vec3>(y + 12); }
/// @brief Internal force n (N, base frame): y[12..14], read-only.
inline Eigen::Map<const Vec3> force(const double* y) { return Eigen::Map<const Vec3>(y + 12); }
/// @brief Internal moment m (N m, base frame; Eq. 35): y[15..17].
inline Eigen::Map<Vec3> moment(double* y) { return Eigen::Map<Vec3>(y + 15); }
/// @brief Internal moment m (N m, base frame): y[15..17], read-only.
inline Eigen::Map<const Vec3> moment(const double* y) { return Eigen::Map<const Vec3>(y + 15); }
/// @}

/// @brief Pack a frame and an internal wrench into a state.
State make_state(const Frame& f, const Vec3& n, const Vec3& m);
/// @brief The frame of a state.
Frame frame_of(const double* y);

/// @brief Constitutive data of a rod cross section and its distributed weight.
struct Section {
  Vec3 kbt = Vec3::Zero();      ///< EI, EI, GJ.
  Vec3 kse = Vec3::Zero();      ///< GA, GA, EA (unused without shear/extension).
  Vec3 inv_kbt = Vec3::Zero();  ///< 1/EI, 1/EI, 1/GJ.
  Vec3 inv_kse = Vec3::Zero();  ///< 1/GA, 1/GA, 1/EA (unused without shear/extension).
  bool shear_extension = true;  ///< Cosserat (true) or Kirchhoff (false) rod.
  Vec3 weight = Vec3::Zero();   ///< Distributed backbone weight rho A g (N/m, base frame).
  bool gravity = false;         ///< weight != 0: the term is skipped entirely when off.

  /// @brief From a robot's stiffness, the shear/extension effect and the backbone weight per
  /// unit length rho A g (N/m, base frame; zero: no gravity term).
  static Section from(const Robot& robot, const Effects& effects, const Vec3& weight);
  /// @brief From a validated scene (stiffness, shear/extension effect, backbone weight).
  static Section from(const Scene& scene);
  /// @brief Curvature u = Kbt^-1 R^T m (body frame, rad/m).
  Vec3 curvature(const Mat3& R, const Vec3& m) const { return inv_kbt.cwiseProduct(R.transpose() * m); }
  /// @brief Strain v = Kse^-1 R^T n + e_z (body frame); e_z for a Kirchhoff rod.
  Vec3 strain(const Mat3& R, const Vec3& n) const {
    if (!shear_extension) return Vec3::UnitZ();
    Vec3 v = inv_kse.cwiseProduct(R.transpose() * n);
    v.z() += 1.0;
    return v;
  }
};

/// @brief A tensioned tendon fully constrained along the rod (paper Eq. 24-29): body-frame offset
/// r_k (physics/tendon_path.hpp), its cross-product matrix and its tension.
struct TendonLoad {
  Vec3 r = Vec3::Zero();   ///< Body-frame offset r_k (m).
  Mat3 rx = Mat3::Zero();  ///< [r_k]x.
  double T = 0.0;          ///< Tension (N).
  Vec3 dr = Vec3::Zero();  ///< r_k' (general routing; rod_rhs reads it only when routed).
  Vec3 ddr = Vec3::Zero(); ///< r_k'' (idem).
  /// @brief The load of a tendon at offset r with tension T.
  static TendonLoad make(const Vec3& r, double T);
};

/// @brief The strains of the state rod_rhs() evaluated.
struct Strains {
  Vec3 u;  ///< Curvature (body frame, rad/m).
  Vec3 v;  ///< Linear strain (body frame).
};

/// @brief The rod's right-hand side (Eq. 2-3, 24-29, 34-39), written once; allocation-free.
///
/// Without tendons (`count` 0) the free rod: n' = -f_e, m' = -p' x n. With `count` tendons of
/// tension T_k (fully constrained: tangent q_k = v + u x r_k), tendon k applies
/// f_k = T_k d/ds(R q_k / |q_k|) and l_k = (R r_k) x f_k. In the body frame
/// f_k^b = (T_k / |q_k|) (u x q_k + P_k (v_s + u_s x r_k)), P_k = I - t_k t_k^T, linear in
/// (v_s, u_s); equilibrium with the constitutive law gives the symmetric positive definite system
///   [Kse + sum A_k,        -sum A_k [r_k]x          ] [v_s]   [-u x n_b - sum a_k - f_e^b        ]
///   [sum [r_k]x A_k,  Kbt - sum [r_k]x A_k [r_k]x  ] [u_s] = [-u x m_b - v x n_b - sum r_k x a_k ]
/// (A_k = T_k P_k / |q_k|, a_k = T_k (u x q_k) / |q_k|, n_b = R^T n, m_b = R^T m; the 3x3 lower
/// block without shear/extension), then n' = R (Kse v_s + u x n_b), m' = R (Kbt u_s + u x m_b);
/// without shear/extension n' = -(R sum f_k^b + f_e). f_e = Section::weight when
/// Section::gravity is set. A tendon list is used as given (a zero tension still takes the
/// tendon path): a caller with no tensioned tendon passes `count` 0.
/// @return The strains u, v at y.
Strains rod_rhs(const Section& section, const TendonLoad* tendons, int count, const double* y, double* dyds);

/// @brief The right-hand side of a rod with no distributed tendon load (a VCref subsegment, or
/// any rod portion with no tendon). Allocation-free, fixed-size.
class FreeRod final : public bvp::OdeSystem {
 public:
  /// @brief A rod of the given cross section (copied).
  explicit FreeRod(const Section& section) : section_(section) {}
  /// @brief kStateSize (18).
  int dimension() const override { return kStateSize; }
  /// @brief rod_rhs() without tendons. `s` is unused (the rod is uniform).
  void rhs(double s, const double* y, double* dyds) const override;

 private:
  Section section_;
};

}  // namespace tdcr::cosserat
