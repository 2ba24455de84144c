// The secant predictor of warm starts (secant_predictor.hpp).
#include "solve/secant_predictor.hpp"

namespace tdcr::detail {

void input_vector(const std::vector<double>& values, const Loads& loads, Eigen::VectorXd& u) {
  const auto m = static_cast<Eigen::Index>(values.size());
  u.resize(m + 9);
  for (Eigen::Index i = 0; i < m; ++i) u[i] = values[static_cast<std::size_t>(i)];
  u.segment<3>(m) = loads.tip_force;
  u.segment<3>(m + 3) = loads.tip_moment;
  u.segment<3>(m + 6) = loads.gravity;
}

// The last solve went from the input h.from (its warm start's) to h.input, its Newton from the
// model's warm guess h.guess to the answer h.unknowns. If this solve starts from that answer
// (`from` = h.input) and its input u moves on along the same line, u - h.input = alpha (h.input
// - h.from) + e with 0 < alpha <= 2 and |e| <= 0.1 |u - h.input|, the correction Newton made
// last time, scaled by alpha, is added to this solve's warm guess x: x + alpha (h.unknowns -
// h.guess). Where the warm guess is the previous answer itself (CCsub, PRB) that is the secant
// x1 + alpha (x1 - x0); VC's warm guess re-balances the base wrench for the new input, VCref's
// re-centres the disk rotations on the previous frames, and the last correction predicts what
// those guesses miss. x is the model's warm guess; true if it was changed (else left as is).
bool extrapolate(const SolveHistory& h, const Eigen::VectorXd& from, const Eigen::VectorXd& u,
                 Eigen::VectorXd& x) {
  if (!h.valid || x.size() == 0 || h.from.size() != u.size() || h.input.size() != u.size() ||
      from.size() != u.size() || x.size() != h.unknowns.size() || x.size() != h.guess.size() || from != h.input)
    return false;
  double d11 = 0.0, d12 = 0.0, d22 = 0.0;
  for (Eigen::Index i = 0; i < u.size(); ++i) {
    const double a = h.input[i] - h.from[i], b = u[i] - h.input[i];
    d11 += a * a;
    d12 += a * b;
    d22 += b * b;
  }
  if (!(d11 > 0.0 && d22 > 0.0)) return false;
  const double alpha = d12 / d11;
  const double off_line = d22 - d12 * d12 / d11;  // |e|^2
  if (!(alpha > 0.0 && alpha <= 2.0 && off_line <= 0.01 * d22)) return false;
  if (!(alpha * (h.unknowns - h.guess)).allFinite()) return false;
  x += alpha * (h.unknowns - h.guess);
  return true;
}

}  // namespace tdcr::detail
