/// @file arclength.cpp
/// @brief Pseudo-arclength continuation: the path loop, event location, snaps and the final
/// solve at the target. The bordered system lives in bordered_system.cpp.
#include "tdcr/bvp/arclength.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>

#include "bordered_system.hpp"
#include "tdcr/core/error.hpp"

namespace tdcr::bvp {

void ArclengthOptions::validate() const {
  auto fail = [](const char* name, double v, const char* why) {
    throw InputError(std::string("arclength.") + name, format_value(v), why);
  };
  auto positive = [&](const char* name, double v) {
    if (!(v > 0.0 && std::isfinite(v))) fail(name, v, "must be positive and finite");
  };
  if (!std::isfinite(start)) fail("start", start, "must be finite");
  if (!std::isfinite(target) || target == start) fail("target", target, "must be finite and differ from start");
  positive("initial_step", initial_step);
  positive("min_step", min_step);
  positive("max_step", max_step);
  if (min_step > initial_step) fail("min_step", min_step, "must not exceed initial_step");
  if (initial_step > max_step) fail("initial_step", initial_step, "must not exceed max_step");
  if (!(growth >= 1.0 && std::isfinite(growth))) fail("growth", growth, "must be >= 1 and finite");
  if (!(shrink > 0.0 && shrink < 1.0)) fail("shrink", shrink, "must be in (0, 1)");
  if (easy_iterations < 0) fail("easy_iterations", easy_iterations, "must not be negative");
  if (!(max_turn > 0.0 && max_turn <= std::acos(-1.0))) fail("max_turn", max_turn, "must be in (0, pi]");
  if (max_steps < 1) fail("max_steps", max_steps, "must be at least 1");
  if (!(window >= 0.0 && std::isfinite(window))) fail("window", window, "must be >= 0 and finite");
  if (!(event_tolerance > 0.0 && event_tolerance < 1.0))
    fail("event_tolerance", event_tolerance, "must be in (0, 1)");
  if (max_refine_iterations < 1) fail("max_refine_iterations", max_refine_iterations, "must be at least 1");
  if (!(snap_overshoot > 0.0 && snap_overshoot < 1.0)) fail("snap_overshoot", snap_overshoot, "must be in (0, 1)");
  positive("snap_perturbation", snap_perturbation);
  if (snap_tries < 1) fail("snap_tries", snap_tries, "must be at least 1");
  if (snap_max_iterations < 1) fail("snap_max_iterations", snap_max_iterations, "must be at least 1");
  if (damped_landing_steps < 0) fail("damped_landing_steps", damped_landing_steps, "must not be negative");
  positive("damped_landing_rate", damped_landing_rate);
  positive("damped_landing_move", damped_landing_move);
  if (corrector_max_iterations < 1) fail("corrector_max_iterations", corrector_max_iterations, "must be at least 1");
  if (!(corrector_freeze_jacobian_below >= 0.0 && std::isfinite(corrector_freeze_jacobian_below)))
    fail("corrector_freeze_jacobian_below", corrector_freeze_jacobian_below, "must be >= 0 and finite");
}

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

namespace {

/// A point of the curve: y = (x, lambda), its unit scaled tangent t, the sign and log|.| of
/// the augmented determinant, and its scaled arclength s.
struct Point {
  Eigen::VectorXd y, t;
  int det_sign = 0;
  double det_log = 0.0;
  double s = 0.0;
  void resize(int n1) {
    y.resize(n1);
    t.resize(n1);
  }
};

/// One call of arclength_continuation(): the state shared by its steps.
class Run {
 public:
  Run(NewtonSolver& newton, ParameterizedSystem& system, const NewtonOptions& newton_options,
      const ArclengthOptions& options, ArclengthResult& result)
      : newton_(newton), sys_(system), nopt_(newton_options), opt_(options), res_(result),
        n_(system.size()), span_(options.target - options.start), dir_(span_ > 0.0 ? 1.0 : -1.0),
        bordered_(system, std::abs(span_), newton.tangent_lu()), w_(bordered_.weights()) {
    corrector_.max_iterations = std::min(nopt_.max_iterations, opt_.corrector_max_iterations);
    if (opt_.corrector_freeze_jacobian_below > corrector_.function_tolerance && !corrector_.reuse_jacobian)
      corrector_.freeze_jacobian_below = opt_.corrector_freeze_jacobian_below;
    for (Point* p : {&prev_, &cur_, &probe_, &best_, &fold_, &bif_, &a_, &b_}) p->resize(n_ + 1);
    y_pred_.resize(n_ + 1);
    guess_.resize(n_ + 1);
    xn_.resize(n_);
    phi_.resize(n_);
    sol_.resize(n_ + 1);
    res_.path.reserve(static_cast<size_t>(std::min(opt_.max_steps, 1000)) + 8);
  }

  void run(Eigen::VectorXd& x);

 private:
  double lambda(const Point& p) const { return p.y[n_]; }
  bool before_target(double l) const { return dir_ * (l - opt_.target) < 0.0; }
  double scaled_distance(const Eigen::VectorXd& a, const Eigen::VectorXd& b) const {
    return (a - b).cwiseProduct(w_).norm();
  }
  void count(const NewtonResult& r, bool natural);
  bool natural_solve(double lambda, Eigen::VectorXd& x, const NewtonOptions* options = nullptr);
  bool correct(const Point& from, double sigma, const Eigen::VectorXd& guess, Point& out);
  bool tangent(Point& p, const Eigen::VectorXd& border) {
    return bordered_.tangent(p.y, border, p.t, p.det_sign, p.det_log);
  }
  int push(const Point& p);
  void record(ArclengthEventType type, const Point& p, bool refined, double jump = 0.0, int damped_steps = 0);
  double test_value(ArclengthEventType type, const Point& p, double ref_log) const;
  bool refine(ArclengthEventType type, Point& event);
  bool finish(const Point& a, const Point& b, bool b_is_fold);
  bool snap(const Point& fold);
  bool land(const Point& fold, double landing, int damped_steps = 0);
  bool accepted_landing(double landing);
  int damped_landing(const Point& fold, double landing, const NewtonOptions& attempt);
  double undamped_norm(const Eigen::VectorXd& x);
  bool step_events(bool& done);
  void reach(const Point& p) {
    push(p);
    sol_ = p.y;
    res_.status = ArclengthStatus::Reached;
  }
  void stall(const std::string& why) {
    res_.status = ArclengthStatus::Stalled;
    why_ = why;
  }

  NewtonSolver& newton_;
  ParameterizedSystem& sys_;
  const NewtonOptions& nopt_;
  NewtonOptions corrector_ = nopt_;  // nopt_ with ArclengthOptions::corrector_max_iterations
  const ArclengthOptions& opt_;
  ArclengthResult& res_;
  const int n_;
  const double span_, dir_;
  detail::BorderedSystem bordered_;
  const Eigen::VectorXd& w_;
  Point prev_, cur_, probe_, best_, fold_, bif_, a_, b_;
  Eigen::VectorXd y_pred_, guess_, xn_, phi_, sol_, f_, f_scale_, ref_;
  std::string why_;
  std::string rejected_;  // why the last snap landing was rejected (ArclengthOptions::accept_landing)
  bool start_ok = false;
};

void Run::count(const NewtonResult& r, bool natural) {
  ++res_.newton_solves;
  res_.iterations += r.iterations;
  if (natural) {  // bordered solves are counted inside the bordered system
    res_.residual_evaluations += r.residual_evaluations + r.fd_residual_evaluations;
    res_.jacobian_evaluations += r.jacobian_evaluations;
  }
  res_.last = r;
}

bool Run::natural_solve(double lambda, Eigen::VectorXd& x, const NewtonOptions* options) {
  sys_.set_parameter(lambda);
  count(newton_.solve(sys_, x, options ? *options : nopt_), true);
  return res_.last.converged() && x.allFinite();
}

// Corrector on the hyperplane t_from^T (z - z_from) = sigma; out gets its tangent (bordered by
// t_from, which keeps the orientation) and determinant.
bool Run::correct(const Point& from, double sigma, const Eigen::VectorXd& guess, Point& out) {
  y_pred_ = from.y + sigma * from.t.cwiseQuotient(w_);
  bordered_.set_border(from.t, y_pred_);
  out.y = guess;
  count(newton_.solve(bordered_, out.y, corrector_), false);
  out.s = from.s + sigma;
  return res_.last.converged() && out.y.allFinite() && tangent(out, from.t);
}

int Run::push(const Point& p) {
  ArclengthPoint q;
  q.lambda = lambda(p);
  xn_ = p.y.head(n_);
  q.value = opt_.output ? opt_.output(xn_, q.lambda) : xn_.norm();
  q.arclength = p.s;
  q.tangent_lambda = p.t[n_];
  res_.path.push_back(q);
  return static_cast<int>(res_.path.size()) - 1;
}

void Run::record(ArclengthEventType type, const Point& p, bool refined, double jump, int damped_steps) {
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

// A bracket [sa, sb] of a root of g for regula falsi with the Illinois modification (halve the
// stale end's value when the same end moves twice), so convergence stays superlinear.
struct IllinoisBracket {
  double sa, sb, ga, gb;
  int side = 0;
  double next() const {
    const double s = (sa * gb - sb * ga) / (gb - ga);
    return s > sa && s < sb ? s : 0.5 * (sa + sb);
  }
  // Move the end whose g has the sign of g(sigma); true if that is the a end.
  bool update(double sigma, double g) {
    if ((g > 0.0) == (ga > 0.0)) {
      sa = sigma;
      ga = g;
      if (side == -1) gb *= 0.5;
      side = -1;
      return true;
    }
    sb = sigma;
    gb = g;
    if (side == +1) ga *= 0.5;
    side = +1;
    return false;
  }
};

// Fold: lambda component of the unit tangent. Bifurcation: det relative to ref_log (O(1) near
// the bracket, whatever the size of the determinant).
double Run::test_value(ArclengthEventType type, const Point& p, double ref_log) const {
  if (type == ArclengthEventType::Fold) return p.t[n_];
  return p.det_sign * std::exp(std::clamp(p.det_log - ref_log, -300.0, 300.0));
}

// Locate an event between prev_ and cur_ by regula falsi (Illinois) on the arclength measured
// along prev_'s tangent; event gets the best point found. True if converged to tolerance.
bool Run::refine(ArclengthEventType type, Point& event) {
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
bool Run::finish(const Point& a, const Point& b, bool b_is_fold) {
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

// Jump from a fold to another branch at lambda slightly past it (see FoldAction::Snap). Close
// to the fold the vanished equilibrium leaves a local minimum of |F| that can hold every attempt
// (VCref on the scene fold_on_path); the landing then moves 10 times further past the fold, up to
// a tenth of the span (or the target).
bool Run::snap(const Point& fold) {
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
bool Run::accepted_landing(double landing) {
  if (!opt_.accept_landing) return true;
  const std::string why = opt_.accept_landing(xn_, landing);
  sys_.set_parameter(landing);
  if (why.empty()) return true;
  rejected_ = why;
  ++res_.rejected_landings;
  return false;
}

// xn_ solves the system at `landing`: a new branch starts there.
bool Run::land(const Point& fold, double landing, int damped_steps) {
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
double Run::undamped_norm(const Eigen::VectorXd& x) {
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
int Run::damped_landing(const Point& fold, double landing, const NewtonOptions& attempt) {
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

// Events between prev_ and an accepted cur_; done = the run ended (reached or stalled).
// Returns true if cur_ was replaced by a snap landing (a new branch starts there).
bool Run::step_events(bool& done) {
  done = false;
  const bool fold = (prev_.t[n_] > 0.0) != (cur_.t[n_] > 0.0);
  const bool bif = opt_.detect_bifurcations && prev_.det_sign != cur_.det_sign;
  bool fold_ok = false, bif_ok = false;
  if (fold) fold_ok = refine(ArclengthEventType::Fold, fold_);
  if (bif) bif_ok = refine(ArclengthEventType::Bifurcation, bif_);
  // The interval's points in path order: prev_, events by arclength, cur_.
  const Point* seq[4] = {&prev_, nullptr, nullptr, &cur_};
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
  const Point* last = &prev_;
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

void Run::run(Eigen::VectorXd& x) {
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

}  // namespace

ArclengthResult arclength_continuation(NewtonSolver& newton, ParameterizedSystem& system, Eigen::VectorXd& x,
                                       const NewtonOptions& newton_options, const ArclengthOptions& options) {
  options.validate();
  if (x.size() != system.size()) throw InputError("arclength.x", std::to_string(x.size()), "must have size system.size()");
  ArclengthResult res;
  Run(newton, system, newton_options, options, res).run(x);
  return res;
}

}  // namespace tdcr::bvp
