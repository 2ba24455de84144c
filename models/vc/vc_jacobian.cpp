// VC single shooting's exact Jacobian (vc_shooting.hpp, shoot_jacobian): the shot of `shoot`
// repeated in dual numbers that carry d/d(n(0), m(0)) through every RK4 stage, disk point load
// and kink fixed point, so the Jacobian is the exact derivative of the discrete map the residual
// evaluates (Newton converges quadratically) at the cost of about one shot.
#include <cmath>
#include <limits>

#include "vc/vc_shooting.hpp"

namespace tdcr::vc {

namespace {

constexpr int kN = cosserat::kStateSize;

// Eigen's functors are only `inline` on GCC and Clang, and too many of them stay calls on dual
// numbers: flatten inlines the whole right-hand side.
#if defined(__GNUC__)
#define TDCR_FLATTEN __attribute__((flatten))
#else
#define TDCR_FLATTEN
#endif

/// The segment's rod (TendonRod without length states) in dual numbers, at arc length s.
template <bool Routed>
TDCR_FLATTEN void dual_rhs(const cosserat::Section& S, const SegmentLoads& seg, double s, const Dual* y, Dual* dyds) {
  const std::vector<cosserat::TendonLoad>& loads = seg.tendons_at(s);
  const cosserat::TendonLoad* t = loads.data();
  const int count = static_cast<int>(loads.size());
  if (S.shear_extension) {
    if (S.gravity)
      cosserat::detail::rod_rhs<true, true, Routed>(S, t, count, y, dyds);
    else
      cosserat::detail::rod_rhs<true, false, Routed>(S, t, count, y, dyds);
  } else if (S.gravity) {
    cosserat::detail::rod_rhs<false, true, Routed>(S, t, count, y, dyds);
  } else {
    cosserat::detail::rod_rhs<false, false, Routed>(S, t, count, y, dyds);
  }
}

void dual_rhs(const cosserat::Section& S, const SegmentLoads& seg, double s, const Dual* y, Dual* dyds) {
  if (seg.all_straight)
    dual_rhs<false>(S, seg, s, y, dyds);
  else
    dual_rhs<true>(S, seg, s, y, dyds);
}

/// The steps of bvp::Rk4Integrator::integrate from s0 to s1, operation for operation.
bool rk4(const bvp::Rk4Integrator& integ, const cosserat::Section& S, const SegmentLoads& seg, double s0, double s1,
         Dual* y) {
  int steps = integ.steps();
  if (std::isfinite(integ.max_step()))
    steps = std::max(steps, static_cast<int>(std::ceil(std::abs(s1 - s0) / integ.max_step() - 1e-9)));
  const double h = (s1 - s0) / steps;
  Dual k1[kN], k2[kN], k3[kN], k4[kN], t[kN];
  for (int step = 0; step < steps; ++step) {
    // The stage points of bvp::Rk4Integrator.
    const double s = s0 + step * h;
    const double s_mid = s + 0.5 * h;
    const double s_end = (step + 1 == steps) ? s1 : s0 + (step + 1) * h;
    dual_rhs(S, seg, s, y, k1);
    for (int i = 0; i < kN; ++i) t[i] = y[i] + 0.5 * h * k1[i];
    dual_rhs(S, seg, s_mid, t, k2);
    for (int i = 0; i < kN; ++i) t[i] = y[i] + 0.5 * h * k2[i];
    dual_rhs(S, seg, s_mid, t, k3);
    for (int i = 0; i < kN; ++i) t[i] = y[i] + h * k3[i];
    dual_rhs(S, seg, s_end, t, k4);
    for (int i = 0; i < kN; ++i) y[i] += (h / 6.0) * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i]);
  }
  for (int i = 0; i < kN; ++i)
    if (!isfinite(y[i])) return false;
  return true;
}

}  // namespace

bool has_exact_jacobian(const VcWorkspace::Impl& W) {
  // Friction: the tension states and the friction fixed point are not in dual numbers.
  return !W.friction && dynamic_cast<const bvp::Rk4Integrator*>(W.shot_integrator.get()) != nullptr;
}

bool shoot_jacobian(VcWorkspace::Impl& W, const Vec6& x, Vec6& res, Mat6& J) {
  const auto* integ = dynamic_cast<const bvp::Rk4Integrator*>(W.shot_integrator.get());
  if (!integ) return false;
  Dual y[kN];
  for (int i = 0; i < kN; ++i) y[i] = Dual(0.0);
    for (int i = 0; i < 3; ++i) y[3 + 4 * i] = Dual(1.0);  // R = I
  for (int i = 0; i < 6; ++i) y[12 + i] = Dual::variable(x[i], i);
  const TendonRouting& rt = W.model->routing();
  const int nseg = static_cast<int>(W.segments.size());
  for (int i = 0; i < nseg; ++i) {
    const SegmentLoads& seg = W.segments[i];
    const int last = rt.segment_end_disk[i];
    const int first = i == 0 ? 1 : rt.segment_end_disk[i - 1] + 1;
    for (int j = first; j <= last; ++j) {
      if (!rk4(*integ, W.section, seg, rt.disk_s[j - 1], rt.disk_s[j], y)) return false;
      if (!disk_point_loads(W, i, j, y)) return false;
    }
  }
  for (int r = 0; r < 6; ++r) {
    res[r] = y[12 + r].v;
    J.row(r) = y[12 + r].derivatives().transpose();
  }
  if (W.loads.has_tip_wrench()) {
    res.head<3>() -= W.loads.tip_force();
    res.tail<3>() -= W.loads.tip_moment();
  }
  return res.allFinite() && J.allFinite();
}

}  // namespace tdcr::vc
