#include "tdcr/core/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "tdcr/core/lie.hpp"

namespace tdcr {

TipError tip_error(const Frame& tip, const Frame& reference) {
  return TipError{(tip.p - reference.p).norm(), lie::rotation_angle(tip.R, reference.R)};
}

MeanTipError mean_tip_error(const std::vector<Frame>& tips, const std::vector<Frame>& references,
                            double length) {
  if (tips.size() != references.size() || tips.empty())
    throw std::invalid_argument("mean_tip_error: need two non-empty lists of equal size");
  MeanTipError e;
  for (std::size_t i = 0; i < tips.size(); ++i) {
    const TipError t = tip_error(tips[i], references[i]);
    const double p = 100.0 * t.position / length, r = t.angle * 180.0 / M_PI;
    e.e_p_percent += p;
    e.e_R_deg += r;
    e.max_p_percent = std::max(e.max_p_percent, p);
    e.max_R_deg = std::max(e.max_R_deg, r);
  }
  e.e_p_percent /= static_cast<double>(tips.size());
  e.e_R_deg /= static_cast<double>(tips.size());
  return e;
}

}  // namespace tdcr
