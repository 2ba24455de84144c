/// @file arclength_events.cpp
/// @brief Pseudo-arclength continuation: the events between two accepted points (folds and
/// bifurcations, located by regula falsi, and a snap where the path folds back) and the final
/// solve where the path passes the target.
#include <algorithm>
#include <cmath>
#include <utility>

#include "arclength_run.hpp"

namespace tdcr::bvp::detail {

// Fold: lambda component of the unit tangent. Bifurcation: det relative to ref_log (O(1) near
// the bracket, whatever the size of the determinant).
double ArclengthRun::test_value(ArclengthEventType type, const CurvePoint& p, double ref_log) const {
  if (type == ArclengthEventType::Fold) return p.t[n_];
  return p.det_sign * std::exp(std::clamp(p.det_log - ref_log, -300.0, 300.0));
}

// Locate an event between prev_ and cur_ by regula falsi (Illinois) on the arclength measured
// along prev_'s tangent; event gets the best point found. True if converged to tolerance.
bool ArclengthRun::refine(ArclengthEventType type, CurvePoint& event) {
  const double ref = prev_.det_log;
  a_ = prev_;
  b_ = cur_;
  IllinoisBracket br{0.0, cur_.s - prev_.s, test_value(type, a_, ref), test_value(type, b_, ref)};
  const double tol = opt_.event_tolerance * std::max(std::abs(br.ga), std::abs(br.gb));
  const bool a_best = std::abs(br.ga) <= std::abs(br.gb);
  event = a_best ? a_ : b_;
  double best_g = a_best ? std::abs(br.ga) : std::abs(br.gb);
  for (int it = 0; it < opt_.max_refine_iterations; ++it) {
    const double sigma = br.next();
    guess_ = a_.y + (sigma - br.sa) / (br.sb - br.sa) * (b_.y - a_.y);
    if (!correct(prev_, sigma, guess_, probe_)) return false;
    const double g = test_value(type, probe_, ref);
    if (std::abs(g) < best_g) {
      best_g = std::abs(g);
      event = probe_;
    }
    if (best_g <= tol) return true;
    std::swap(br.update(sigma, g) ? a_ : b_, probe_);
    if (br.sb - br.sa <= 1e-14 * (cur_.s - prev_.s)) return true;
  }
  return false;
}

// The target lies between a and b. Unless b is a fold, natural Newton at exactly the target
// from the linear interpolation; otherwise, or if that fails, first the point of the curve at
// the target by regula falsi along a's tangent (so the answer stays on the branch between a and
// b, even next to a fold where the natural Newton could pick the other root), then natural
// Newton from there.
bool ArclengthRun::finish(const CurvePoint& a, const CurvePoint& b, bool b_is_fold) {
  const double theta = (opt_.target - lambda(a)) / (lambda(b) - lambda(a));
  phi_ = a.y.head(n_) + theta * (b.y.head(n_) - a.y.head(n_));
  bool ok = !b_is_fold && natural_solve(opt_.target, phi_);
  if (!ok) {
    a_ = a;
    b_ = b;
    IllinoisBracket br{0.0, a.t.dot((b.y - a.y).cwiseProduct(w_)), dir_ * (lambda(a) - opt_.target),
                       dir_ * (lambda(b) - opt_.target)};
    bool located = false;
    for (int it = 0; it < opt_.max_refine_iterations && !located; ++it) {
      const double sigma = br.next();
      guess_ = a_.y + (sigma - br.sa) / (br.sb - br.sa) * (b_.y - a_.y);
      if (!correct(a, sigma, guess_, probe_)) break;
      const double g = dir_ * (lambda(probe_) - opt_.target);
      located = std::abs(g) * w_[n_] <= 1e-13 || br.sb - br.sa <= 1e-14 * std::abs(br.sb);
      if (located) best_ = probe_;
      std::swap(br.update(sigma, g) ? a_ : b_, probe_);
    }
    phi_ = best_.y.head(n_);
    ok = located && natural_solve(opt_.target, phi_);
  }
  if (!ok) {
    stall("Newton at the target failed, from the interpolated and the located point");
    return false;
  }
  probe_.y << phi_, opt_.target;
  probe_.s = a.s + theta * (b.s - a.s);
  probe_.t = a.t + theta * (b.t - a.t);
  reach(probe_);
  return true;
}

// Events between prev_ and an accepted cur_; done = the run ended (reached or stalled).
// Returns true if cur_ was replaced by a snap landing (a new branch starts there).
bool ArclengthRun::step_events(bool& done) {
  done = false;
  const bool fold = (prev_.t[n_] > 0.0) != (cur_.t[n_] > 0.0);
  const bool bif = opt_.detect_bifurcations && prev_.det_sign != cur_.det_sign;
  bool fold_ok = false, bif_ok = false;
  if (fold) fold_ok = refine(ArclengthEventType::Fold, fold_);
  if (bif) bif_ok = refine(ArclengthEventType::Bifurcation, bif_);
  // The interval's points in path order: prev_, events by arclength, cur_.
  const CurvePoint* seq[4] = {&prev_, nullptr, nullptr, &cur_};
  bool ok[4] = {true, fold_ok, bif_ok, true};
  ArclengthEventType type[4] = {ArclengthEventType::Fold, ArclengthEventType::Fold,
                                ArclengthEventType::Bifurcation, ArclengthEventType::Fold};
  if (fold) seq[1] = &fold_;
  if (bif) seq[2] = &bif_;
  if (fold && bif && bif_.s < fold_.s) {
    std::swap(seq[1], seq[2]);
    std::swap(ok[1], ok[2]);
    std::swap(type[1], type[2]);
  }
  const bool snapping = fold && opt_.at_fold == FoldAction::Snap && dir_ * prev_.t[n_] > 0.0;
  const CurvePoint* last = &prev_;
  for (int k = 1; k < 4; ++k) {
    if (!seq[k]) continue;
    if (!before_target(lambda(*seq[k]))) {  // the target lies between last and seq[k]
      done = true;
      finish(*last, *seq[k], seq[k] == &fold_);
      return false;
    }
    if (k == 3) break;
    record(type[k], *seq[k], ok[k]);
    last = seq[k];
    if (snapping && seq[k] == &fold_) {
      done = !snap(fold_) || res_.status == ArclengthStatus::Reached;
      return true;
    }
  }
  push(cur_);
  return false;
}

}  // namespace tdcr::bvp::detail
