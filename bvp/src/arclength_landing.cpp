/// @file arclength_landing.cpp
/// @brief Pseudo-arclength continuation: snaps at folds (FoldAction::Snap), by Newton attempts
/// along the null vector and, as the last resort, by the damped landing of the overdamped motion.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "arclength_run.hpp"

namespace tdcr::bvp::detail {

// Jump from a fold to another branch at lambda slightly past it (see FoldAction::Snap). Close
// to the fold the vanished equilibrium leaves a local minimum of |F| that can hold every attempt
// (VCref on the scene fold_on_path); the landing then moves 10 times further past the fold, up to
// a tenth of the span (or the target).
bool ArclengthRun::snap(const CurvePoint& fold) {
  phi_ = fold.t.head(n_);
  const double norm = phi_.norm();
  if (!(norm > 0.0)) {
    stall("snap: no null vector at the fold");
    return false;
  }
  phi_ /= norm;
  if (opt_.fold_limit) {
    const std::string limit = opt_.fold_limit(fold.y.head(n_), lambda(fold));
    if (!limit.empty()) {
      stall("no snap tried at the fold: " + limit);
      return false;
    }
  }
  NewtonOptions attempt = nopt_;
  attempt.max_iterations = std::min(nopt_.max_iterations, opt_.snap_max_iterations);
  // Landing parameter `overshoot` of the span past the fold, at most the target.
  auto landing_at = [&](double overshoot) {
    const double l = lambda(fold) + dir_ * overshoot * std::abs(span_);
    return before_target(l) ? l : opt_.target;
  };
  for (double overshoot = opt_.snap_overshoot; overshoot <= std::max(0.1 + 1e-12, opt_.snap_overshoot); overshoot *= 10.0) {
    const double landing = landing_at(overshoot);
    double amplitude = opt_.snap_perturbation;
    for (int k = 0; k < opt_.snap_tries; ++k, amplitude *= 2.0) {
      for (double sign : {1.0, -1.0}) {
        xn_ = fold.y.head(n_) + sign * amplitude * phi_.cwiseQuotient(w_.head(n_));
        if (natural_solve(landing, xn_, &attempt) && accepted_landing(landing)) return land(fold, landing);
      }
    }
    if (landing == opt_.target) break;
  }
  const double landing = landing_at(opt_.snap_overshoot);
  NewtonOptions damped = nopt_;  // not the corrector's frozen Jacobians: each step damps anew
  damped.max_iterations = std::min(nopt_.max_iterations, opt_.corrector_max_iterations);
  if (const int steps = damped_landing(fold, landing, damped)) return land(fold, landing, steps);
  if (!why_.empty()) {
    res_.unlanded_snap = res_.limit.empty();
    return false;
  }
  res_.unlanded_snap = true;
  stall(rejected_.empty() ? "snap: no Newton solve past the fold converged"
                          : "snap: no Newton solve past the fold converged to an accepted landing (last rejected: " +
                                rejected_ + ")");
  return false;
}

// Whether xn_, converged at `landing`, passes ArclengthOptions::accept_landing.
bool ArclengthRun::accepted_landing(double landing) {
  if (!opt_.accept_landing) return true;
  const std::string why = opt_.accept_landing(xn_, landing);
  sys_.set_parameter(landing);
  if (why.empty()) return true;
  rejected_ = why;
  ++res_.rejected_landings;
  return false;
}

// xn_ solves the system at `landing`: a new branch starts there.
bool ArclengthRun::land(const CurvePoint& fold, double landing, int damped_steps) {
  const double jump = (xn_ - fold.y.head(n_)).cwiseProduct(w_.head(n_)).norm();
  cur_.y << xn_, landing;
  cur_.s = fold.s;
  y_pred_.setZero();
  y_pred_[n_] = dir_;
  if (!tangent(cur_, y_pred_)) {
    stall("snap: singular augmented Jacobian at the landing point");
    return false;
  }
  record(ArclengthEventType::Snap, cur_, true, jump, damped_steps);
  if (landing == opt_.target) {
    sol_ = cur_.y;
    res_.status = ArclengthStatus::Reached;
  }
  return true;
}

// Scaled residual norm at x without damping (at the current parameter); infinity if the
// residual cannot be evaluated.
double ArclengthRun::undamped_norm(const Eigen::VectorXd& x) {
  sys_.set_damping(x, 0.0);
  if (!sys_.residual(x, f_) || !f_.allFinite()) return std::numeric_limits<double>::infinity();
  return f_.cwiseProduct(f_scale_).norm();
}

// The snap's last resort: from the fold state at `landing`, implicit Euler steps of the
// overdamped motion (ParameterizedSystem::set_damping), the pseudo-time step steered by the move
// per step (ArclengthOptions::damped_landing_move), until the motion rests; then natural Newton. Where the vanished equilibrium leaves a slow passage or
// a local minimum of |F| that holds Newton's attempts, the motion still drifts through it, and it
// comes to rest at a stable equilibrium (it lowers the potential), not at whichever root Newton
// would find. xn_ gets the landing; returns the number of steps if it converged, else 0. The
// damping is off on return.
int ArclengthRun::damped_landing(const CurvePoint& fold, double landing, const NewtonOptions& attempt) {
  if (opt_.damped_landing_steps == 0) return 0;
  ref_ = fold.y.head(n_);
  if (!sys_.set_damping(ref_, 0.0)) return 0;
  f_.resize(n_);
  f_scale_.resize(n_);
  sys_.residual_scale(f_scale_);
  sys_.set_parameter(landing);
  constexpr double kRestRate = 1e-6, kMaxRate = 1e12, kFactor = 4.0;
  // Implicit Euler steps longer than 2 / (a saddle's unstable rate) converge to the saddle, and
  // the motion slows down near one, so its steps grow: after a rejected landing (a saddle,
  // ArclengthOptions::accept_landing) the pseudo-time step stays below 1 / min_rate, 4 times
  // shorter after each rejection, and the motion counts as at rest once a step moves less than
  // kRestMove of damped_landing_move.
  constexpr int kMaxRejections = 4;
  constexpr double kRestMove = 1e-3;
  // A snap can carry the structure far (VCref on s1004 of the loaded-scene suite with its loads
  // x 1.05: about 9 scaled units before T3 reaches its limit, 460 steps at damped_landing_move),
  // so the move per step grows while each step's Newton solve is easy (kEasyIterations) and
  // shrinks back where it is not, between damped_landing_move and kMaxMoveGrowth times it.
  constexpr int kEasyIterations = 3, kHardIterations = 10;
  constexpr double kMaxMoveGrowth = 16.0;
  double target_move = opt_.damped_landing_move;
  double rate = opt_.damped_landing_rate, min_rate = 0.0;
  double norm = undamped_norm(ref_);  // infinite: the residual cannot be evaluated there
  bool landed = false, resting = false;
  int rejections = 0;
  int k = 0;
  for (; k < opt_.damped_landing_steps && !landed && std::isfinite(norm); ++k) {
    const bool at_rest = rate <= kRestRate || resting;
    sys_.set_damping(ref_, at_rest ? 0.0 : rate);
    xn_ = ref_;
    const bool ok = natural_solve(landing, xn_, &attempt);
    if (at_rest) {  // a natural Newton solve from the resting state: the landing, if accepted
      resting = false;
      landed = ok && accepted_landing(landing);
      if (!ok) {
        rate = std::max(min_rate, kRestRate * kFactor);  // not at rest yet: damp again
      } else if (!landed) {
        if (++rejections == kMaxRejections) break;
        min_rate = opt_.damped_landing_rate * std::pow(kFactor, rejections);
        rate = min_rate;
      }
      continue;
    }
    const double next = ok ? undamped_norm(xn_) : std::numeric_limits<double>::infinity();
    if (!std::isfinite(next)) {
      rate *= kFactor;
      target_move = opt_.damped_landing_move;
      if (rate > kMaxRate) break;
      // A motion that has run into a limit of the system stops there (the steps would only
      // fail on, with the pseudo-time step quartered each time).
      sys_.set_damping(ref_, 0.0);
      if (opt_.fold_limit && !(res_.limit = opt_.fold_limit(ref_, landing)).empty()) break;
      continue;
    }
    const double move = (xn_ - ref_).cwiseProduct(w_.head(n_)).norm();
    ref_ = xn_;  // no re-centring here: the path's points keep the system's charts
    rate = std::max(min_rate, rate * std::clamp(move / target_move, 1.0 / kFactor, kFactor));
    if (res_.last.iterations <= kEasyIterations)
      target_move = std::min(1.5 * target_move, kMaxMoveGrowth * opt_.damped_landing_move);
    else if (res_.last.iterations > kHardIterations)
      target_move = std::max(0.5 * target_move, opt_.damped_landing_move);
    resting = min_rate > 0.0 && move < kRestMove * opt_.damped_landing_move;
    norm = next;
  }
  sys_.set_damping(ref_, 0.0);
  if (landed) return k;
  // Stuck: where the motion leads into a limit of the system, that is the answer.
  if (opt_.fold_limit && res_.limit.empty()) res_.limit = opt_.fold_limit(ref_, landing);
  if (!res_.limit.empty()) {
    stall("snap: the damped motion from the fold runs into a limit of the system (the result's limit)");
    return 0;
  }
  stall(rejections > 0 ? "snap: no Newton solve past the fold converged, and the damped motion from the fold came to "
                         "rest only at rejected landings (last: " + rejected_ + ")"
                       : "snap: no Newton solve past the fold converged, and the damped motion from the fold did not "
                         "come to rest");
  return 0;
}

}  // namespace tdcr::bvp::detail
