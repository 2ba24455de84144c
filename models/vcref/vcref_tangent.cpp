// VCref's shot derivatives (vcref_shooting.hpp, linearize_shot / shot_tangent): the free rod's
// flow commutes with translations and rotations of the whole start, so a Jacobian needs the
// derivative in the start wrench only: 6 integrations per interval instead of 9.
#include "vcref/vcref_shooting.hpp"

#include <algorithm>
#include <cmath>

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

}  // namespace tdcr
