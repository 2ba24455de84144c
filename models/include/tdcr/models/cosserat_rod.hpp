/// @file cosserat_rod.hpp
/// @brief The Cosserat rod shared by VC and VCref (paper Eq. 2-3, 34-39): state layout,
/// constitutive law and the right-hand side of a rod free of distributed tendon loads.
///
/// State (18 doubles, all in the base frame): p (3), R (9, column-major), n (3), m (3), where n
/// and m are the rod's own internal force and moment at s (paper Eq. 34-35). Strains come from the
/// constitutive law: u = Kbt^-1 R^T m, v = Kse^-1 R^T n + e_z (Cosserat rod with shear and
/// extension) or v = e_z (inextensible, unshearable Kirchhoff rod). Then (Eq. 2-3, 38-39)
///   p' = R v,  R' = R [u]x,  n' = -f_e,  m' = -p' x n - l_e,
/// with f_e = rho A g the backbone weight when gravity is on. Internal wrenches as states make
/// jumps at disks (Eq. 40-41) plain additions, and the same state serves both rod variants.
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

/// @brief Constitutive data of a rod cross section, decided once per scene.
struct Section {
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

/// @brief Right-hand side of a rod with no distributed tendon load (a VCref subsegment, or any
/// rod portion with no tendon). Allocation-free, fixed-size.
class FreeRod final : public bvp::OdeSystem {
 public:
  /// @brief A rod of the given cross section (copied).
  explicit FreeRod(const Section& section) : section_(section) {}
  /// @brief kStateSize (18).
  int dimension() const override { return kStateSize; }
  /// @brief p' = R v, R' = R [u]x, n' = -f_e, m' = -p' x n (Eq. 2-3, 38-39 without tendon
  /// loads), strains from Section::curvature and Section::strain; f_e = Section::weight only
  /// when Section::gravity is set. `s` is unused (the rod is uniform).
  void rhs(double s, const double* y, double* dyds) const override;

 private:
  Section section_;
};

}  // namespace tdcr::cosserat
