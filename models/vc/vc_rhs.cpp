#include "vc/vc_rhs.hpp"

#include "physics/cosserat_rhs.hpp"
#include "physics/tendon_path.hpp"

namespace tdcr::vc {

// The rod's right-hand side inlined, so that the strains feed the tendon lengths from registers.
template <bool Shear, bool Gravity>
void TendonRod::eval(const double* y, double* dyds) const {
  const cosserat::Strains e = cosserat::detail::rod_rhs<Shear, Gravity>(
      *section_, seg_->tendons.data(), static_cast<int>(seg_->tendons.size()), y, dyds);
  if (!lengths_) return;
  double* dl = dyds + cosserat::kStateSize;
  for (int k = 0; k < tendon_count_; ++k) dl[k] = 0.0;
  for (const LengthTerm& t : seg_->lengths) dl[t.index] = physics::tendon_tangent(e.v, e.u, t.r).norm();
}

void TendonRod::rhs(double, const double* y, double* dyds) const {
  // The section's flags follow the bound input (gravity), hence a run-time choice per call.
  if (section_->shear_extension) {
    if (section_->gravity)
      eval<true, true>(y, dyds);
    else
      eval<true, false>(y, dyds);
  } else if (section_->gravity) {
    eval<false, true>(y, dyds);
  } else {
    eval<false, false>(y, dyds);
  }
}

}  // namespace tdcr::vc
