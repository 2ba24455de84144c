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
    // The tendon sums of cosserat::detail::rod_rhs (see there for the algebra).
    double G[21] = {}, H[6] = {};
    double sum_c = 0.0;
    Vec3 sum_cr = Vec3::Zero(), suma = Vec3::Zero(), sumra = Vec3::Zero();
    for (int k = 0; k < count; ++k) {
      const cosserat::TendonLoad& t = tendons[k];
      Vec3 qk = v + u.cross(t.r);
      if (routed) qk += t.dr;
      const double inv_q = 1.0 / qk.norm();
      const Vec3 tk = qk * inv_q;
      const double c = t.T * inv_q;
      const Vec3 wk = t.r.cross(tk);
      const double g[6] = {tk.x(), tk.y(), tk.z(), wk.x(), wk.y(), wk.z()};
      for (int i = 0, e = 0; i < 6; ++i) {
        const double cg = c * g[i];
        for (int j = 0; j <= i; ++j, ++e) G[e] += cg * g[j];
      }
      const Vec3& r = t.r;
      const double r2 = r.squaredNorm();
      const double rr[6] = {r.x() * r.x() - r2, r.y() * r.x(), r.y() * r.y() - r2,
                            r.z() * r.x(),      r.z() * r.y(), r.z() * r.z() - r2};
      for (int e = 0; e < 6; ++e) H[e] += c * rr[e];
      sum_c += c;
      sum_cr += c * r;
      Vec3 a = c * u.cross(qk);
      if (routed) {
        const Vec3 z = u.cross(t.dr) + t.ddr;
        a += c * (z - tk * tk.dot(z));
      }
      suma += a;
      sumra += r.cross(a);
    }
    Mat3 sumAr = lie::hat(sum_cr);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) sumAr(i, j) += G[(3 + j) * (4 + j) / 2 + i];
    Mat3 K22;
    for (int i = 0, e = 0; i < 3; ++i)
      for (int j = 0; j <= i; ++j, ++e) K22(i, j) = K22(j, i) = -(H[e] + G[(3 + i) * (4 + i) / 2 + 3 + j]);
    K22.diagonal() += X.Seff.kbt;
    const Vec3 b_m = -u.cross(mb) - v.cross(nb) - sumra + in_m - X.bbt.cwiseProduct(uhs);
    if (shear) {
      Mat3 K11;
      for (int i = 0, e = 0; i < 3; ++i)
        for (int j = 0; j <= i; ++j, ++e) K11(i, j) = K11(j, i) = -G[e];
      K11.diagonal().array() += sum_c;
      K11.diagonal() += X.Seff.kse;
      const Vec3 b_n = -u.cross(nb) - suma - fe + in_n - X.bse.cwiseProduct(vhs);
      spd_block_solve(K11, Mat3(-sumAr), K22, b_n, b_m, vs, us);
      out3(12) = R * (X.Seff.kse.cwiseProduct(vs) + X.bse.cwiseProduct(vhs) + u.cross(nb));
    } else {
      us = spd_solve(K22, b_m);
      const Vec3 fb = suma - sumAr * us;  // tendon force, body frame
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
