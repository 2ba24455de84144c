#include "vc/vc_rhs.hpp"

#include "physics/tendon_path.hpp"

namespace tdcr::vc {

void TendonRod::rhs(double, const double* y, double* dyds) const {
  const cosserat::Strains e = cosserat::rod_rhs(*section_, seg_->tendons.data(),
                                                static_cast<int>(seg_->tendons.size()), y, dyds);
  if (!lengths_) return;
  double* dl = dyds + cosserat::kStateSize;
  for (int k = 0; k < tendon_count_; ++k) dl[k] = 0.0;
  for (const LengthTerm& t : seg_->lengths) dl[t.index] = physics::tendon_tangent(e.v, e.u, t.r).norm();
}

}  // namespace tdcr::vc
