// VCref's derivatives (vcref_shooting.hpp). The shots (linearize_shot / shot_tangent): the free
// rod's flow commutes with translations and rotations of the whole start, so a Jacobian needs the
// derivative in the start wrench only: 6 integrations per interval instead of 9. The tendon
// wrenches on the disks (begin_linearization, disk_wrench_derivative): exact derivatives in the
// disk poses.
#include "vcref/vcref_shooting.hpp"

#include <algorithm>
#include <cmath>

#include "physics/tendon_path.hpp"
#include "tdcr/core/lie.hpp"

namespace tdcr {

bool VcrefShooting::linearize_shot(int k, bvp::Integrator& integrator, const double* y0, const double* end) const {
  if (section_.gravity || !dynamic_cast<bvp::Rk4Integrator*>(&integrator)) return false;
  const double fd_scale[2] = {fd_comp_[2], fd_comp_[3]};  // force, moment
  cosserat::State y;
  for (int i = 0; i < 6; ++i) {
    const double value = y0[12 + i];
    const double h = fd_rel_ * std::max(std::abs(value), fd_scale[i / 3]);
    y = Eigen::Map<const cosserat::State>(y0);
    y[12 + i] = value + h;
    if (!integrator.integrate(rod_, node(k), node(k + 1), y.data())) return false;
    shot_d_.col(i) = (y - Eigen::Map<const cosserat::State>(end)) / h;
  }
  shot_start_ = Eigen::Map<const cosserat::State>(y0);
  shot_end_ = Eigen::Map<const cosserat::State>(end);
  return true;
}

// Without gravity: end(p0, Q R0, Q n0, Q m0) = (p0 + Q (p1 - p0), Q R1, Q n1, Q m1) for every
// rotation Q, for RK4's map as for the exact flow (RK4 commutes with the linear maps the
// right-hand side commutes with), and a shift of p0 shifts p1. A start change (dp, dR, dn, dm) is
// the rotation omega = vee(skew(dR R0^T)) of the whole start, a shift dp, and the wrench change
// (dn - omega x n0, dm - omega x m0) at the unrotated start.
void VcrefShooting::shot_tangent(int, const double* dy, double* dend) const {
  using namespace cosserat;
  const double* y0 = shot_start_.data();
  const double* e = shot_end_.data();
  const Mat3 A = Eigen::Map<const Mat3>(dy + 3) * rotation(y0).transpose();
  const Vec3 omega(0.5 * (A(2, 1) - A(1, 2)), 0.5 * (A(0, 2) - A(2, 0)), 0.5 * (A(1, 0) - A(0, 1)));
  Eigen::Matrix<double, 6, 1> dw;
  dw.head<3>() = Eigen::Map<const Vec3>(dy + 12) - omega.cross(force(y0));
  dw.tail<3>() = Eigen::Map<const Vec3>(dy + 15) - omega.cross(moment(y0));
  Eigen::Map<State>(dend).noalias() = shot_d_ * dw;
  position(dend) += Eigen::Map<const Vec3>(dy) + omega.cross(position(e) - position(y0));
  rotation(dend) += lie::hat(omega) * rotation(e);
  force(dend) += omega.cross(force(e));
  moment(dend) += omega.cross(moment(e));
}

// Eq. 30-33 (+ Eq. 58) as tendon::disk_wrench, differentiated. A pose change of disk i is
// (dp_i, dtheta_i), R_i -> R_i exp(dtheta_i), so a body vector v moves by -hat(R_i v) R_i dtheta_i.
// Per tendon, with a = R_j r_j and the chord c_i = (p_i - p_j) + (R_i r_i - a) to disk i = j -+ 1
// (u = c / |c|): dG = sum_i T (I - u u^T) / |c| dc_i; Eq. 58 projects G onto the disk plane (z =
// R_j e_z): F = G - (G.z) z, dF = (I - z z^T) dG - (z G^T + (G.z) I) dz; M = a x F.
void VcrefShooting::disk_wrench_derivative(int j, const Frame* frames, tendon::DiskWrench& w,
                                           Eigen::Matrix<double, 6, 18>& D) const {
  const double* s = d_.routing->disk_s.data();
  const Frame& fj = frames[j];
  const Vec3 z = fj.R.col(2);
  w = tendon::DiskWrench{};
  D.setZero();
  Eigen::Matrix<double, 3, 18> dG, dF;
  for (const RoutedTendon& t : active_.tendons) {
    if (j > t.end_disk) continue;
    const double T = tension_[t.index];
    if (T == 0.0) continue;
    const Vec3 a = fj.R * physics::tendon_offset(t, s[j]);
    const bool passes = j < t.end_disk;
    Vec3 G = Vec3::Zero();
    dG.setZero();
    for (int i = 0; i < (passes ? 3 : 1); i += 2) {  // disks j - 1 and j + 1
      const Frame& fi = frames[j - 1 + i];
      const Vec3 b = fi.R * physics::tendon_offset(t, s[j - 1 + i]);
      const Vec3 c = (fi.p - fj.p) + (b - a);
      const double n = c.norm();
      const Vec3 u = c / n;
      G += T * u;
      const Mat3 P = (T / n) * (Mat3::Identity() - u * u.transpose());
      dG.block<3, 3>(0, 6 * i) += P;
      dG.block<3, 3>(0, 6 * i + 3) -= P * lie::hat(b) * fi.R;
      dG.block<3, 3>(0, 6) -= P;
      dG.block<3, 3>(0, 9) += P * lie::hat(a) * fj.R;
    }
    Vec3 F = G;
    dF = dG;
    if (passes && d_.remove_normal) {
      F -= G.dot(z) * z;
      dF -= z * (z.transpose() * dG);
      dF.block<3, 3>(0, 9) += (z * G.transpose() + G.dot(z) * Mat3::Identity()) * lie::hat(z) * fj.R;
    }
    w.force += F;
    w.moment += a.cross(F);
    // dM = da x F + a x dF, da = -hat(a) R_j dtheta_j.
    D.topRows<3>() += dF;
    D.bottomRows<3>() += lie::hat(a) * dF;
    D.block<3, 3>(3, 9) += lie::hat(F) * lie::hat(a) * fj.R;
  }
}

}  // namespace tdcr
