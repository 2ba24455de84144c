#include "vc/vc_rhs.hpp"

#include "physics/cosserat_rhs.hpp"
#include "physics/tendon_path.hpp"

namespace tdcr::vc {

// The rod's right-hand side inlined, so that the strains feed the tendon lengths from registers.
template <bool Shear, bool Gravity>
void TendonRod::eval(double s, const double* y, double* dyds) const {
  const auto e = cosserat::detail::rod_rhs<Shear, Gravity>(
      *section_, seg_->tendons.data(), static_cast<int>(seg_->tendons.size()), y, dyds);
  if (watch_) {
    const double inv_v2 = 1.0 / e.v.squaredNorm();
    for (std::size_t k = 0; k < seg_->tendons.size(); ++k) {
      const double c = -e.u.cross(seg_->tendons[k].r).dot(e.v) * inv_v2;
      if (c > watch_->value) *watch_ = Degeneracy{c, s, seg_->tendon_index[k]};
    }
  }
  if (!lengths_) return;
  double* dl = dyds + cosserat::kStateSize;
  for (int k = 0; k < tendon_count_; ++k) dl[k] = 0.0;
  for (const LengthTerm& t : seg_->lengths) dl[t.index] = physics::tendon_tangent(e.v, e.u, t.r).norm();
}

void TendonRod::rhs(double s, const double* y, double* dyds) const {
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
