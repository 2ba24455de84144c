// The rod of one implicit time step (vc_dynamics_rod.hpp). The tendon terms are those of
// cosserat::detail::rod_rhs (same sums, same block solve); the step adds inertia, drag and the
// Kelvin-Voigt terms:
//   K_eff v_s + B_se v_hs + u x n_b = rho A (w x q + q_t) - f_e^b - f_tendons^b
//   K_eff u_s + B_bt u_hs + u x m_b = w x (rho J w) + rho J w_t - v x n_b - l_tendons^b
// with K_eff = K + c0 B and v_hs, u_hs the s-derivatives of the history (the same combination
// of the past v_s, u_s), because n_b = K_se (v - e_z) + B_se (c0 v + v_h) differentiates to
// n_b' = K_eff v_s + B_se v_hs.
#include "vc/vc_dynamics_rod.hpp"

#include "physics/cosserat_rhs.hpp"

namespace tdcr::vc::dyn {

namespace {

using cosserat::detail::spd_block_solve;
using cosserat::detail::spd_solve;

}  // namespace

#if defined(__GNUC__)
__attribute__((flatten))
#endif
void rhs(const StepSection& X, const cosserat::TendonLoad* tendons, int count, bool routed, const Values& h,
         const double* y, double* dyds, Values& out) {
  const cosserat::Section& S = X.S;
  const Eigen::Map<const Mat3> R(y + 3);
  const Eigen::Map<const Vec3> n(y + 12), m(y + 15), q(y + 18), w(y + 21);
  const Vec3 nb = R.transpose() * n;
  const Vec3 mb = R.transpose() * m;
  Vec3 v, u;
  X.strains(R, n, m, h, v, u);
  const bool shear = S.shear_extension;
  const Vec3 vt = shear ? Vec3(X.c0 * v + h.segment<3>(kV)) : Vec3::Zero();
  const Vec3 ut = X.c0 * u + h.segment<3>(kU);
  const Vec3 qt = X.c0 * q + h.segment<3>(kQ);
  const Vec3 wt = X.c0 * w + h.segment<3>(kW);
  const Vec3 vhs = h.segment<3>(kVs), uhs = h.segment<3>(kUs);

  const auto out3 = [dyds](int offset) { return Eigen::Map<Vec3>(dyds + offset); };
  out3(0) = R * v;
  Eigen::Map<Mat3> dR(dyds + 3);
  dR = R * lie::hat(u);
  out3(18) = vt - u.cross(q) + w.cross(v);
  out3(21) = ut - u.cross(w);

  // Inertia and external distributed loads, body frame.
  const Vec3 in_n = X.rho_a * (w.cross(q) + qt);
  const Vec3 jw = X.rho_j.cwiseProduct(w);
  const Vec3 in_m = w.cross(jw) + X.rho_j.cwiseProduct(wt);
  Vec3 fe = Vec3::Zero();
  if (S.gravity) fe = R.transpose() * S.weight;
  if (X.drag > 0.0) fe -= X.drag * q.norm() * q;  // air drag -c |V| V, V = R q

  Vec3 vs = Vec3::Zero(), us;
  if (count == 0) {
    // Free rod: R^T n' = in_n - f_e, R^T m' = in_m - v x n_b.
    const Vec3 dnb = in_n - fe;
    const Vec3 dmb = in_m - v.cross(nb);
    out3(12) = R * dnb;
    out3(15) = R * dmb;
    if (shear) vs = X.Seff.inv_kse.cwiseProduct(dnb - u.cross(nb) - X.bse.cwiseProduct(vhs));
    us = X.Seff.inv_kbt.cwiseProduct(dmb - u.cross(mb) - X.bbt.cwiseProduct(uhs));
  } else {
    // The tendon sums of the statics (cosserat::detail::tendon_sums, see there for the algebra).
    cosserat::detail::TendonSums<double> sums;
    if (routed)
      cosserat::detail::tendon_sums<true>(tendons, count, v, u, sums);
    else
      cosserat::detail::tendon_sums<false>(tendons, count, v, u, sums);
    const Mat3 sumAr = sums.sum_a_r();
    const Mat3 K22 = sums.k22(X.Seff.kbt);
    const Vec3 b_m = -u.cross(mb) - v.cross(nb) - sums.sumra + in_m - X.bbt.cwiseProduct(uhs);
    if (shear) {
      const Mat3 K11 = sums.k11(X.Seff.kse);
      const Vec3 b_n = -u.cross(nb) - sums.suma - fe + in_n - X.bse.cwiseProduct(vhs);
      spd_block_solve(K11, Mat3(-sumAr), K22, b_n, b_m, vs, us);
      out3(12) = R * (X.Seff.kse.cwiseProduct(vs) + X.bse.cwiseProduct(vhs) + u.cross(nb));
    } else {
      us = spd_solve(K22, b_m);
      const Vec3 fb = sums.suma - sumAr * us;  // tendon force, body frame
      out3(12) = R * (in_n - fe - fb);
    }
    out3(15) = R * (X.Seff.kbt.cwiseProduct(us) + X.bbt.cwiseProduct(uhs) + u.cross(mb));
  }
  out.segment<3>(kV) = v;
  out.segment<3>(kU) = u;
  out.segment<3>(kQ) = q;
  out.segment<3>(kW) = w;
  out.segment<3>(kVs) = vs;
  out.segment<3>(kUs) = us;
}

}  // namespace tdcr::vc::dyn
