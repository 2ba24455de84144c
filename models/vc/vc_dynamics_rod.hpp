// Private to models/vc: the right-hand side of VC's rod in one implicit time step (Till, Aloi and
// Rucker, IJRR 2019, with VC's fully constrained tendons of cosserat_rhs.hpp). The state adds the
// body-frame velocities q (linear) and w (angular) to the statics' p, R, n, m; each time
// derivative y_t of v, u, q, w is c0 y + y_h with y_h the history at the evaluation point.
#pragma once

#include <Eigen/Core>

#include "tdcr/models/cosserat_rod.hpp"

namespace tdcr::vc::dyn {

constexpr int kStateSize = 24;  ///< p, R, n, m (as the statics), q, w (body frame).
constexpr int kValues = 18;     ///< v, u, q, w, v_s, u_s: what a time step remembers per point.
using Values = Eigen::Matrix<double, kValues, 1>;

/// Offsets into Values.
enum : int { kV = 0, kU = 3, kQ = 6, kW = 9, kVs = 12, kUs = 15 };

/// The cross section of one time step: the statics' section, the Kelvin-Voigt damping B = tau K,
/// the effective stiffnesses K + c0 B of the implicit step, the mass per length and the rotary
/// inertia per length, and the drag.
struct StepSection {
  cosserat::Section S;                          ///< Statics' section (weight, flags, K).
  cosserat::Section Seff;                       ///< The same with K + c0 B (strains from wrenches within the step).
  Vec3 bse = Vec3::Zero(), bbt = Vec3::Zero();  ///< tau_se K_se, tau_bt K_bt.
  double c0 = 0.0;                              ///< y_t = c0 y + y_h (0: statics).
  double rho_a = 0.0;                           ///< kg/m.
  Vec3 rho_j = Vec3::Zero();                    ///< kg m (rho I, rho I, rho 2I).
  double drag = 0.0;                            ///< Quadratic drag coefficient, N s^2/m^3.

  /// Strains from the base-frame wrench with the history h of the point:
  /// n_b = K_se (v - e_z) + B_se v_t, m_b = K_bt u + B_bt u_t, v_t = c0 v + v_h.
  void strains(const Mat3& R, const Vec3& n, const Vec3& m, const Values& h, Vec3& v, Vec3& u) const {
    u = Seff.inv_kbt.cwiseProduct(R.transpose() * m - bbt.cwiseProduct(h.segment<3>(kU)));
    if (!S.shear_extension) {
      v = Vec3::UnitZ();
      return;
    }
    Vec3 hv = h.segment<3>(kV);
    hv.z() += c0;
    v = Seff.inv_kse.cwiseProduct(R.transpose() * n - bse.cwiseProduct(hv));
    v.z() += 1.0;
  }
  /// The shift z of the wrench that makes Seff's static strain law give the step's strains:
  /// strains(R, n, m, h) = Seff's law at (n - R z_n, m - R z_m) (the kinks reuse KinkMap).
  void shift(const Values& h, Vec3& zn, Vec3& zm) const {
    Vec3 hv = h.segment<3>(kV);
    hv.z() += c0;
    zn = S.shear_extension ? Vec3(bse.cwiseProduct(hv)) : Vec3::Zero();
    zm = bbt.cwiseProduct(h.segment<3>(kU));
  }
};

/// dyds = f(s, y) of the step at one evaluation point with history h; the values v, u, q, w,
/// v_s, u_s there into `out`. Routed: tendon offsets vary with s (loads evaluated at s).
/// Allocation-free.
void rhs(const StepSection& X, const cosserat::TendonLoad* tendons, int count, bool routed, const Values& h,
         const double* y, double* dyds, Values& out);

}  // namespace tdcr::vc::dyn
