// Phase 1 of the inverse solve (inverse_solver.hpp): reach the target, by bounded Levenberg-
// Marquardt steps, from other starts where that ends at a local minimum of the distance.
#include "services/inverse_solver.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace tdcr::detail::inverse {

namespace {

std::vector<int> all_tendons(Eigen::Index m) {
  std::vector<int> v(static_cast<std::size_t>(m));
  for (Eigen::Index i = 0; i < m; ++i) v[static_cast<std::size_t>(i)] = static_cast<int>(i);
  return v;
}

// The k-th point (k >= 1) of the van der Corput sequence in base b, in [0, 1).
double halton(int k, int b) {
  double f = 1.0, x = 0.0;
  for (int i = k; i > 0; i /= b) {
    f /= b;
    x += f * (i % b);
  }
  return x;
}

}  // namespace

// Phase 1 from cur and, where it ends at a local minimum of the distance that misses the
// target (or stalls), from up to kRestarts other starts: of the first kCandidates points of a
// Halton sequence in [0, box]^m, box = max(10 tension scale, 2 max T_start), each time the one
// farthest from the starts tried and where they ended (a target on a branch that the start's
// valley does not lead to: a tip force across the bending plane). True when reached (cur
// there); else the result is finished with the closest pose of all.
bool Solver::reach(Point& cur) {
  const VectorXd T_first = cur.T;
  std::string why;
  Reach how = reach_target(cur, why);
  if (how == Reach::Reached) return true;
  Point best = std::move(cur);
  const Eigen::Index m = best.T.size();
  const double box = std::max(10.0 * tension_scale_, 2.0 * input_start_max_);
  int tried = 0;
  auto local = [](Reach h) { return h == Reach::Stationary || h == Reach::Stalled; };
  Reach best_how = how;
  // Candidates: the first kCandidates Halton points; each start the one farthest from the
  // points tried so far and where they ended (maximin).
  std::vector<VectorXd> candidates, seen = {T_first, best.T};
  for (int k = 1; k <= kCandidates; ++k) {
    VectorXd c(m);
    for (Eigen::Index i = 0; i < m; ++i) c[i] = box * halton(k, kPrimes[static_cast<std::size_t>(i) % kPrimes.size()]);
    candidates.push_back(c);
  }
  for (int k = 1; local(how) && k <= kRestarts; ++k) {
    std::size_t pick = 0;
    double far = -1.0;
    for (std::size_t c = 0; c < candidates.size(); ++c) {
      double d = std::numeric_limits<double>::infinity();
      for (const VectorXd& v : seen) d = std::min(d, (candidates[c] - v).norm());
      if (d > far) {
        far = d;
        pick = c;
      }
    }
    const VectorXd T = candidates[pick];
    candidates.erase(candidates.begin() + static_cast<std::ptrdiff_t>(pick));
    seen.push_back(T);
    Point p;
    ++tried;
    if (!evaluate(T, nullptr, p) || !jacobian(p)) continue;
    std::string w;
    how = reach_target(p, w);
    seen.push_back(p.T);
    if (how == Reach::Reached) {
      cur = std::move(p);
      return true;
    }
    if (how == Reach::Failed) {  // this start went where the forward solve fails: next one
      how = Reach::Stationary;
      continue;
    }
    if (p.merit() < best.merit()) {
      best = std::move(p);
      why = w;
      best_how = how;
    }
    if (how == Reach::Limit) {
      best_how = how;
      why = w + " (" + std::to_string(tried) + " other starts tried): the closest pose found";
    }
  }
  if (tried > 0 && local(how)) why += "; " + std::to_string(tried) + " other starts did not reach it either";
  finish(best, best_how == Reach::Stationary ? InverseStatus::Unreachable
               : best_how == Reach::Failed   ? InverseStatus::ForwardFailed
                                             : InverseStatus::MaxIterations,
         why);
  return false;
}

// Levenberg-Marquardt with T >= 0: each step the non-negative least-squares problem
// min |J d + e|^2 + lambda |d|^2; kept if the error drops; lambda by the gain ratio (Nielsen).
// J by differences at the start, then Broyden's update along each kept step that halved the
// error; differenced again after a slower step, where a step fails on the updated J, before a
// claim of stationarity and once reached.
// Reached, or why not (in `why`).
Solver::Reach Solver::reach_target(Point& cur, std::string& why) {
  const std::vector<int> all = all_tendons(cur.T.size());
  double lambda = 1e-3 * std::max(cur.J.colwise().squaredNorm().maxCoeff(), std::numeric_limits<double>::min());
  double nu = 2.0;
  bool exact = true;  // cur.J is by differences at cur (not updated)
  std::vector<double> kept;  // the error after each kept step
  auto refresh = [&]() {
    if (!jacobian(cur)) {
      why = "the Jacobian by differences of forward solves could not be formed";
      return false;
    }
    exact = true;
    return true;
  };
  while (!cur.reached) {
    // Stationary for the distance: not even the undamped linear model gets closer.
    const double e2 = cur.e.squaredNorm();
    const VectorXd y0 = damped_step(cur.J, cur.e, cur.T, lambda_floor(cur.J), all);
    if ((cur.J * (y0 - cur.T) + cur.e).squaredNorm() >= e2 * (1.0 - 1e-12)) {
      if (!exact) {
        if (!refresh()) return Reach::Failed;
        continue;
      }
      why = "no step with non-negative tensions gets closer: the closest pose found (a local minimum of the distance)";
      return Reach::Stationary;
    }
    if (exhausted()) {
      why = "iteration limit before the target was reached";
      return Reach::Limit;
    }
    const VectorXd y = damped_step(cur.J, cur.e, cur.T, std::max(lambda, lambda_floor(cur.J)), all);
    const VectorXd d = y - cur.T;
    if (d.cwiseAbs().maxCoeff() <= 1e-14 * (cur.T.cwiseAbs().maxCoeff() + tension_scale_)) {
      if (!exact) {
        if (!refresh()) return Reach::Failed;
        continue;
      }
      why = "no step with non-negative tensions gets closer: the closest pose found (the steps vanish)";
      return Reach::Stationary;
    }
    const double predicted = e2 - (cur.J * d + cur.e).squaredNorm();
    ++r_.iterations;
    Point trial;
    if (evaluate(y, &cur, trial) && trial.merit() < cur.merit()) {
      const double rho = (e2 - trial.e.squaredNorm()) / std::max(predicted, std::numeric_limits<double>::min());
      // Broyden's update after a step that at least halved the error; a slower one differences J.
      const bool fast = trial.merit() <= 0.5 * cur.merit();
      trial.J = cur.J + (trial.e - cur.e - cur.J * d) * d.transpose() / d.squaredNorm();
      cur = std::move(trial);
      exact = false;
      if (!fast && !refresh()) return Reach::Failed;
      ++r_.accepted_steps;
      kept.push_back(cur.merit());
      if (!cur.reached && kept.size() > kStallSteps && cur.merit() > 0.5 * kept[kept.size() - 1 - kStallSteps]) {
        why = "the distance stopped falling (by less than half over " + std::to_string(kStallSteps) +
              " steps): the closest pose found";
        return Reach::Stalled;
      }
      lambda *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * std::min(rho, 1.0) - 1.0, 3));
      nu = 2.0;
    } else if (!exact) {  // the updated J may be what failed: difference it before damping more
      if (!refresh()) return Reach::Failed;
    } else {
      lambda = std::max(lambda, lambda_floor(cur.J)) * nu;
      nu *= 2.0;
    }
  }
  return exact || refresh() ? Reach::Reached : Reach::Failed;
}

}  // namespace tdcr::detail::inverse
