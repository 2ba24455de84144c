#include "vc/vc_rhs.hpp"

#include "physics/cosserat_rhs.hpp"
#include "physics/tendon_path.hpp"

namespace tdcr::vc {

namespace {

const std::vector<cosserat::TendonLoad>& route_at(const std::vector<cosserat::TendonLoad>& loads,
                                                  const std::vector<const RoutedTendon*>& routed, double s,
                                                  std::vector<cosserat::TendonLoad>& out) {
  for (std::size_t k = 0; k < loads.size(); ++k) {
    cosserat::TendonLoad& o = out[k];
    o.T = loads[k].T;
    if (routed[k]->straight()) {
      o.r = loads[k].r;
      o.rx = loads[k].rx;
      o.dr.setZero();
      o.ddr.setZero();
      continue;
    }
    const physics::TendonPoint p = physics::tendon_path(*routed[k], s);
    o.r = p.r;
    o.rx = lie::hat(p.r);
    o.dr = p.dr;
    o.ddr = p.ddr;
  }
  return out;
}

}  // namespace

const std::vector<cosserat::TendonLoad>& SegmentLoads::tendons_at(double s) const {
  return all_straight ? tendons : route_at(tendons, routed, s, at_s);
}

const std::vector<cosserat::TendonLoad>& SegmentLoads::terminating_at(double s) const {
  return all_straight ? terminating : route_at(terminating, terminating_routed, s, terminating_at_s);
}

// The rod's right-hand side inlined, so that the strains feed the tendon lengths from registers.
template <bool Shear, bool Gravity>
void TendonRod::eval(double s, const double* y, double* dyds) const {
  const SegmentLoads& seg = *seg_;
  const std::vector<cosserat::TendonLoad>& loads = seg.tendons_at(s);
  const int count = static_cast<int>(loads.size());
  const auto e = seg.all_straight
                     ? cosserat::detail::rod_rhs<Shear, Gravity, false>(*section_, loads.data(), count, y, dyds)
                     : cosserat::detail::rod_rhs<Shear, Gravity, true>(*section_, loads.data(), count, y, dyds);
  if (watch_) {
    const double inv_v2 = 1.0 / e.v.squaredNorm();
    for (int k = 0; k < count; ++k) {
      const double c = -(e.u.cross(loads[k].r) + loads[k].dr).dot(e.v) * inv_v2;
      if (c > watch_->value) *watch_ = Degeneracy{c, s, seg.tendon_index[k]};
    }
  }
  if (!lengths_) return;
  double* dl = dyds + cosserat::kStateSize;
  for (int k = 0; k < tendon_count_; ++k) dl[k] = 0.0;
  if (seg.all_straight) {
    for (const LengthTerm& t : seg.lengths) dl[t.index] = physics::tendon_tangent(e.v, e.u, t.r).norm();
  } else {
    for (const LengthTerm& t : seg.lengths) {
      const physics::TendonPoint p = physics::tendon_path(*t.tendon, s);
      dl[t.index] = physics::tendon_tangent(e.v, e.u, p.r, p.dr).norm();
    }
  }
}

// flatten: GCC otherwise keeps the small Eigen products (outer products, 3x3 products, R^T n) and
// tendon_tangent as calls, most of the time of a shot.
#if defined(__GNUC__)
#define TDCR_FLATTEN __attribute__((flatten))
#else
#define TDCR_FLATTEN
#endif

TDCR_FLATTEN void TendonRod::rhs(double s, const double* y, double* dyds) const {
  // The section's flags follow the bound input (gravity), hence a run-time choice per call.
  if (section_->shear_extension) {
    if (section_->gravity)
      eval<true, true>(s, y, dyds);
    else
      eval<true, false>(s, y, dyds);
  } else if (section_->gravity) {
    eval<false, true>(s, y, dyds);
  } else {
    eval<false, false>(s, y, dyds);
  }
}

}  // namespace tdcr::vc
