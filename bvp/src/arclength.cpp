/// @file arclength.cpp
/// @brief Pseudo-arclength continuation: the entry point and the path loop (predictor,
/// corrector, step control). Events and the final solve at the target are in
/// arclength_events.cpp, snaps in arclength_landing.cpp, the option checks in
/// arclength_options.cpp, the bordered system in bordered_system.cpp.
#include "tdcr/bvp/arclength.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

#include "arclength_run.hpp"
#include "tdcr/core/error.hpp"

namespace tdcr::bvp {

std::string to_string(ArclengthEventType t) {
  switch (t) {
    case ArclengthEventType::Fold: return "fold";
    case ArclengthEventType::Bifurcation: return "bifurcation";
    case ArclengthEventType::Snap: return "snap";
  }
  return "unknown";
}

std::string to_string(ArclengthStatus s) {
  switch (s) {
    case ArclengthStatus::Reached: return "reached";
    case ArclengthStatus::Stalled: return "stalled";
    case ArclengthStatus::StepLimit: return "step_limit";
  }
  return "unknown";
}

int ArclengthResult::count(ArclengthEventType type) const {
  return static_cast<int>(std::count_if(events.begin(), events.end(),
                                        [type](const ArclengthEvent& e) { return e.type == type; }));
}

namespace detail {

ArclengthRun::ArclengthRun(NewtonSolver& newton, ParameterizedSystem& system, const NewtonOptions& newton_options,
         const ArclengthOptions& options, ArclengthResult& result)
    : newton_(newton), sys_(system), nopt_(newton_options), opt_(options), res_(result),
      n_(system.size()), span_(options.target - options.start), dir_(span_ > 0.0 ? 1.0 : -1.0),
      bordered_(system, std::abs(span_), newton.tangent_lu()), w_(bordered_.weights()) {
  corrector_.max_iterations = std::min(nopt_.max_iterations, opt_.corrector_max_iterations);
  if (opt_.corrector_freeze_jacobian_below > corrector_.function_tolerance && !corrector_.reuse_jacobian)
    corrector_.freeze_jacobian_below = opt_.corrector_freeze_jacobian_below;
  for (CurvePoint* p : {&prev_, &cur_, &probe_, &best_, &fold_, &bif_, &a_, &b_}) p->resize(n_ + 1);
  y_pred_.resize(n_ + 1);
  guess_.resize(n_ + 1);
  xn_.resize(n_);
  phi_.resize(n_);
  sol_.resize(n_ + 1);
  res_.path.reserve(static_cast<size_t>(std::min(opt_.max_steps, 1000)) + 8);
}

void ArclengthRun::count(const NewtonResult& r, bool natural) {
  ++res_.newton_solves;
  res_.iterations += r.iterations;
  if (natural) {  // bordered solves are counted inside the bordered system
    res_.residual_evaluations += r.residual_evaluations + r.fd_residual_evaluations;
    res_.jacobian_evaluations += r.jacobian_evaluations;
  }
  res_.last = r;
}

bool ArclengthRun::natural_solve(double lambda, Eigen::VectorXd& x, const NewtonOptions* options) {
  sys_.set_parameter(lambda);
  count(newton_.solve(sys_, x, options ? *options : nopt_), true);
  return res_.last.converged() && x.allFinite();
}

// Corrector on the hyperplane t_from^T (z - z_from) = sigma; out gets its tangent (bordered by
// t_from, which keeps the orientation) and determinant.
bool ArclengthRun::correct(const CurvePoint& from, double sigma, const Eigen::VectorXd& guess, CurvePoint& out) {
  y_pred_ = from.y + sigma * from.t.cwiseQuotient(w_);
  bordered_.set_border(from.t, y_pred_);
  out.y = guess;
  count(newton_.solve(bordered_, out.y, corrector_), false);
  out.s = from.s + sigma;
  return res_.last.converged() && out.y.allFinite() && tangent(out, from.t);
}

int ArclengthRun::push(const CurvePoint& p) {
  ArclengthPoint q;
  q.lambda = lambda(p);
  xn_ = p.y.head(n_);
  q.value = opt_.output ? opt_.output(xn_, q.lambda) : xn_.norm();
  q.arclength = p.s;
  q.tangent_lambda = p.t[n_];
  res_.path.push_back(q);
  return static_cast<int>(res_.path.size()) - 1;
}

void ArclengthRun::record(ArclengthEventType type, const CurvePoint& p, bool refined, double jump, int damped_steps) {
  ArclengthEvent e;
  e.type = type;
  e.lambda = lambda(p);
  e.index = push(p);
  e.jump = jump;
  e.refined = refined;
  e.damped_steps = damped_steps;
  e.x = p.y.head(n_);
  if (opt_.event_output) e.output = opt_.event_output(e.x, e.lambda);
  res_.events.push_back(std::move(e));
}

void ArclengthRun::run(Eigen::VectorXd& x) {
  res_.parameter = opt_.start;
  xn_ = x;
  y_pred_.setZero();
  y_pred_[n_] = dir_;  // initial border: move lambda towards the target
  if (!natural_solve(opt_.start, xn_)) {
    stall("no solution at the start parameter from the given x");
  } else {
    start_ok = true;
    prev_.y << xn_, opt_.start;
    prev_.s = 0.0;
    if (!tangent(prev_, y_pred_)) stall("singular augmented Jacobian at the start");
  }
  double step = opt_.initial_step;
  const double cos_turn = std::cos(opt_.max_turn);
  bool done = !why_.empty();
  if (!done) push(prev_);
  while (!done) {
    if (res_.steps >= opt_.max_steps) {
      res_.status = ArclengthStatus::StepLimit;
      why_ = "max_steps corrector solves spent";
      break;
    }
    ++res_.steps;
    double sigma = step;
    const double tmu = prev_.t[n_];
    const double to_target = (opt_.target - lambda(prev_)) * w_[n_] / tmu;
    bool ok;
    if (tmu * dir_ > 0.0 && to_target <= sigma) {
      // The predictor passes the target: land it there and solve at exactly the target.
      sigma = to_target;
      y_pred_ = prev_.y + sigma * prev_.t.cwiseQuotient(w_);
      xn_ = y_pred_.head(n_);
      ok = natural_solve(opt_.target, xn_) &&
           (xn_ - y_pred_.head(n_)).cwiseProduct(w_.head(n_)).norm() <= std::max(sigma, opt_.min_step);
      if (ok) {  // an accepted point at the target; step_events() finishes there
        cur_.y << xn_, opt_.target;
        cur_.s = prev_.s + sigma;
        ok = tangent(cur_, prev_.t) && prev_.t.dot(cur_.t) >= cos_turn;
      }
    } else {
      y_pred_ = prev_.y + sigma * prev_.t.cwiseQuotient(w_);
      guess_ = y_pred_;
      ok = correct(prev_, sigma, guess_, cur_) && scaled_distance(cur_.y, y_pred_) <= sigma &&
           prev_.t.dot(cur_.t) >= cos_turn;
    }
    res_.last_step = sigma;
    if (!ok) {
      step = sigma * opt_.shrink;
      if (step < opt_.min_step) {
        stall("step below min_step");
        break;
      }
      continue;
    }
    const bool easy = res_.last.iterations <= opt_.easy_iterations;
    ++res_.accepted_steps;
    res_.arclength += sigma;
    const bool snapped = step_events(done);
    if (done) break;
    std::swap(prev_, cur_);
    if (snapped) {
      step = opt_.initial_step;
      continue;
    }
    // Charts that drifted far are re-centred at the accepted point; its tangent (and
    // determinant, whose sign a chart change of positive Jacobian keeps) in the new coordinates,
    // oriented by the old one (its lambda component and the unknowns outside the charts are
    // unchanged); the corrector's factored Jacobian belongs to the old coordinates.
    if (sys_.recenter(prev_.y.head(n_))) {
      newton_.forget_jacobian();
      guess_ = prev_.t;
      if (!tangent(prev_, guess_)) {
        stall("singular augmented Jacobian after re-centring the charts");
        break;
      }
    }
    const double rel = (lambda(prev_) - opt_.start) / span_;
    if (rel < -opt_.window || rel > 1.0 + opt_.window) {
      stall("the path left the parameter window");
      break;
    }
    if (easy) step = std::min(opt_.max_step, step * opt_.growth);
  }
  if (res_.status != ArclengthStatus::Reached) sol_ = prev_.y;
  if (start_ok) {
    x = sol_.head(n_);
    res_.parameter = sol_[n_];
    sys_.set_parameter(res_.parameter);
    sys_.accept_step(x);
  }
  res_.residual_evaluations += bordered_.inner_evaluations;
  res_.jacobian_evaluations += bordered_.jacobian_evaluations;
  char buf[240];
  const int folds = res_.count(ArclengthEventType::Fold), bifs = res_.count(ArclengthEventType::Bifurcation),
            snaps = res_.count(ArclengthEventType::Snap);
  std::snprintf(buf, sizeof buf, "%s parameter %.6g after %d steps (%d accepted), %d folds, %d bifurcations, %d snaps",
                res_.status == ArclengthStatus::Reached ? "reached" : "stopped at", res_.parameter, res_.steps,
                res_.accepted_steps, folds, bifs, snaps);
  res_.message = buf;
  if (res_.rejected_landings > 0)
    res_.message += ", " + std::to_string(res_.rejected_landings) + " snap landings rejected (last: " + rejected_ + ")";
  if (res_.status != ArclengthStatus::Reached)
    res_.message = to_string(res_.status) + ": " + why_ + "; " + res_.message + "; last solve: " + res_.last.message;
}

}  // namespace detail

ArclengthResult arclength_continuation(NewtonSolver& newton, ParameterizedSystem& system, Eigen::VectorXd& x,
                                       const NewtonOptions& newton_options, const ArclengthOptions& options) {
  options.validate();
  if (x.size() != system.size()) throw InputError("arclength.x", std::to_string(x.size()), "must have size system.size()");
  ArclengthResult res;
  detail::ArclengthRun(newton, system, newton_options, options, res).run(x);
  return res;
}

}  // namespace tdcr::bvp
