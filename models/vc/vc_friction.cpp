// VC with capstan tendon friction (vc_friction.hpp).
#include "vc/vc_friction.hpp"

#include <cmath>

#include <Eigen/Cholesky>

#include "physics/tendon_path.hpp"
#include "vc/vc_shooting.hpp"

namespace tdcr::vc {

namespace {

/// Fixed-point iterations on the friction loads: the map contracts by about mu T r^2 / EI.
constexpr int kMaxFrictionIterations = 60;

/// Whether the fixed point has settled: a step at rounding level, or no longer shrinking.
bool settled(double step, double size, double& previous) {
  const bool done = !(step > 1e-14 * size) || !(step < 0.9 * previous);
  previous = step;
  return done;
}

/// Whether a settled fixed point is converged: its last step within 1e-10 of the strain rates.
/// One that stopped shrinking above that (the map does not contract: mu T r^2 / EI near 1 or more)
/// is not a solution of the balance; the right-hand side then returns NaN, so the shot fails
/// instead of integrating wrong strain rates.
bool converged(double step, double size) { return step <= 1e-10 * size + 1e-300; }

}  // namespace

FrictionRod::FrictionRod(const cosserat::Section& section, const SegmentLoads& segment, const TendonFriction& friction,
                         int tendon_count, bool lengths)
    : section_(&section),
      seg_(&segment),
      rate_(tendon_count),
      tendon_count_(tendon_count),
      lengths_(lengths),
      terms_(tendon_count) {
  for (int k = 0; k < tendon_count; ++k) rate_[k] = friction.sign() * friction.of(k);
}

// The strain rates x = (v_s, u_s) solve the rod's balance with the tendons' loads
//   force:  K_se v_s + u x n_b + sum_k (g_k + T_k' t_k) + R^T f_e = 0
//   moment: K_bt u_s + u x m_b + v x n_b + sum_k r_k x (g_k + T_k' t_k) = 0
// with g_k = a_k + A_k (v_s + u_s x r_k) = T_k (d(R t_k)/ds in the body frame), the normal force
// of Rucker & Webster, and T_k' = s mu_k |g_k|. Without the friction terms the system is linear
// (M x = b0, as cosserat::rod_rhs); |g_k| depends on x, so x is the fixed point of
// x = M^-1 (b0 - w(x)), w the friction wrench, iterated from the frictionless x.
void FrictionRod::rhs(double s, const double* y, double* dyds) const {
  const cosserat::Section& S = *section_;
  const SegmentLoads& seg = *seg_;
  const std::vector<cosserat::TendonLoad>& loads = seg.tendons_at(s);
  const int count = static_cast<int>(loads.size());
  const int off = tension_offset();
  const double* T = y + off;
  double* dT = dyds + off;
  for (int k = 0; k < tendon_count_; ++k) dT[k] = 0.0;

  const Eigen::Map<const Mat3> R(y + 3);
  const Eigen::Map<const Vec3> n(y + 12), m(y + 15);
  const Vec3 nb = R.transpose() * n, mb = R.transpose() * m;
  const Vec3 u = S.inv_kbt.cwiseProduct(mb);
  const Vec3 v = S.shear_extension ? Vec3(Vec3::UnitZ() + S.inv_kse.cwiseProduct(nb)) : Vec3(Vec3::UnitZ());
  cosserat::position(dyds) = R * v;
  cosserat::rotation(dyds) = R * lie::hat(u);

  // The balance matrix M (force rows only with shear/extension) and its right-hand side b0.
  using Mat6 = Eigen::Matrix<double, 6, 6>;
  using Vec6 = Eigen::Matrix<double, 6, 1>;
  Mat6 M = Mat6::Zero();
  Vec6 b0 = Vec6::Zero();
  M.topLeftCorner<3, 3>().diagonal() = S.kse;
  M.bottomRightCorner<3, 3>().diagonal() = S.kbt;
  for (int k = 0; k < count; ++k) {
    const cosserat::TendonLoad& L = loads[k];
    const Vec3 q = v + u.cross(L.r) + L.dr;
    const double len = q.norm();
    Term& e = terms_[k];
    e.t = q / len;
    const double c = T[seg.tendon_index[k]] / len;
    e.A = c * (Mat3::Identity() - e.t * e.t.transpose());
    e.a = c * u.cross(q) + e.A * (u.cross(L.dr) + L.ddr);
    const Mat3 Ar = e.A * L.rx;
    M.topLeftCorner<3, 3>() += e.A;
    M.topRightCorner<3, 3>() -= Ar;
    M.bottomLeftCorner<3, 3>() += L.rx * e.A;
    M.bottomRightCorner<3, 3>() -= L.rx * Ar;
    b0.head<3>() -= e.a;
    b0.tail<3>() -= L.r.cross(e.a);
  }
  b0.head<3>() -= u.cross(nb);
  if (S.gravity) b0.head<3>() -= R.transpose() * S.weight;
  b0.tail<3>() -= u.cross(mb) + v.cross(nb);

  // The friction wrench at strain rates x (and T_k' into dT).
  Vec3 sum_g = Vec3::Zero();
  const auto friction = [&](const Vec6& x) {
    Vec6 w = Vec6::Zero();
    sum_g.setZero();
    for (int k = 0; k < count; ++k) {
      const Term& e = terms_[k];
      const Vec3 g = e.a + e.A * (x.head<3>() + x.tail<3>().cross(loads[k].r));
      const int i = seg.tendon_index[k];
      dT[i] = rate_[i] * g.norm();
      const Vec3 F = dT[i] * e.t;
      sum_g += g;
      w.head<3>() += F;
      w.tail<3>() += loads[k].r.cross(F);
    }
    return w;
  };
  Vec6 x = Vec6::Zero();
  bool ok = true;
  if (S.shear_extension) {
    const Eigen::LLT<Mat6> llt(M);
    x = llt.solve(b0);
    double previous = INFINITY;
    for (int it = 0; it < kMaxFrictionIterations; ++it) {
      const Vec6 next = llt.solve(b0 - friction(x));
      const double step = (next - x).cwiseAbs().maxCoeff();
      x = next;
      if (settled(step, x.cwiseAbs().maxCoeff(), previous)) break;
    }
    ok = converged(previous, x.cwiseAbs().maxCoeff());
  } else {
    // Inextensible, unshearable: v_s = 0, the moment rows alone.
    const Eigen::LLT<Mat3> llt(M.bottomRightCorner<3, 3>());
    x.tail<3>() = llt.solve(b0.tail<3>());
    double previous = INFINITY;
    for (int it = 0; it < kMaxFrictionIterations; ++it) {
      const Vec3 next = llt.solve(b0.tail<3>() - friction(x).tail<3>());
      const double step = (next - x.tail<3>()).cwiseAbs().maxCoeff();
      x.tail<3>() = next;
      if (settled(step, next.cwiseAbs().maxCoeff(), previous)) break;
    }
    ok = converged(previous, x.tail<3>().cwiseAbs().maxCoeff());
  }
  if (!ok) {
    for (int i = 0; i < off + tendon_count_; ++i) dyds[i] = NAN;
    return;
  }
  const Vec6 w = friction(x);  // dT and sum_g at the final x
  if (S.shear_extension) {
    cosserat::force(dyds) = R * (S.kse.cwiseProduct(x.head<3>()) + u.cross(nb));
  } else {
    Vec3 dn = -(R * (sum_g + w.head<3>()));
    if (S.gravity) dn -= S.weight;
    cosserat::force(dyds) = dn;
  }
  cosserat::moment(dyds) = R * (S.kbt.cwiseProduct(x.tail<3>()) + u.cross(mb));

  if (watch_) {
    const double inv_v2 = 1.0 / v.squaredNorm();
    for (int k = 0; k < count; ++k) {
      const double c = -(u.cross(loads[k].r) + loads[k].dr).dot(v) * inv_v2;
      if (c > watch_->value) *watch_ = Degeneracy{c, s, seg.tendon_index[k]};
    }
  }
  if (!lengths_) return;
  double* dl = dyds + cosserat::kStateSize;
  for (int k = 0; k < tendon_count_; ++k) dl[k] = 0.0;
  for (const LengthTerm& t : seg.lengths) {
    const physics::TendonPoint p =
        seg.all_straight ? physics::TendonPoint{t.r, Vec3::Zero(), Vec3::Zero()} : physics::tendon_path(*t.tendon, s);
    dl[t.index] = physics::tendon_tangent(v, u, p.r, p.dr).norm();
  }
}

void begin_friction_shot(const VcWorkspace::Impl& W, const FrictionRod& rod, double* y) {
  double* T = y + rod.tension_offset();
  const Vec3 u0 = W.section.curvature(Mat3::Identity(), cosserat::moment(y));
  const Vec3 v0 = W.section.strain(Mat3::Identity(), cosserat::force(y));
  for (const RoutedTendon& t : W.model->routing().tendons) {
    const double T0 = W.loads.tension(t.index);
    T[t.index] = T0;
    if (!(T0 > 0.0)) continue;
    const physics::TendonPoint p = physics::tendon_path(t, 0.0);
    const Vec3 q = physics::tendon_tangent(v0, u0, p.r, p.dr);
    // The turn at the base hole from the actuator's direction (the base disk's axis).
    T[t.index] *= std::exp(rod.rate(t.index) * std::atan2(q.cross(Vec3::UnitZ()).norm(), q.z()));
  }
}

void friction_at_disk(VcWorkspace::Impl& W, const FrictionRod& rod, int i, int j, const double* y) {
  const double* T = y + rod.tension_offset();
  const int last = W.model->routing().segment_end_disk[i];
  SegmentLoads& seg = W.segments[i];
  if (j == last)
    for (std::size_t k = 0; k < seg.terminating.size(); ++k) seg.terminating[k].T = T[seg.terminating_index[k]];
  SegmentLoads* cont = nullptr;
  if (j < last)
    cont = &seg;
  else if (i + 1 < static_cast<int>(W.segments.size()))
    cont = &W.segments[i + 1];
  if (cont)
    for (std::size_t k = 0; k < cont->tendons.size(); ++k) cont->tendons[k].T = T[cont->tendon_index[k]];
}

void friction_end_tensions(const VcWorkspace::Impl& W, const FrictionRod& rod, const double* y,
                           std::vector<double>& tensions) {
  const double* T = y + rod.tension_offset();
  tensions.assign(T, T + W.tendon_count);
}

}  // namespace tdcr::vc
