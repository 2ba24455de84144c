// The solve driver's mesh policies for the models on an RK4 mesh (rk4_refinement.hpp):
// accuracy-driven RK4, which refines the mesh until the tip error estimate meets
// SolverOptions::tip_tolerance, and coarse loading paths, which follow a cold solve's loading
// path on a coarse mesh before the requested one (docs/models.md).
#include "solve/rk4_refinement.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <string>
#include <utility>

#include "solve/newton_summary.hpp"
#include "solve/stability_rule.hpp"
#include "tdcr/core/error.hpp"

namespace tdcr::detail {

namespace {

// --- Accuracy-driven RK4 (IntegratorKind::AccuracyDrivenRK4, SolverOptions::tip_tolerance). ---

// RK4 steps of one integration over `length` (bvp::Rk4Integrator's rule).
int rk4_steps_over(double length, int steps, double max_step) {
  if (!std::isfinite(max_step)) return steps;
  return std::max(steps, static_cast<int>(std::ceil(length / max_step - 1e-9)));
}

// The smallest ratio of steps per disk interval between the mesh (f steps, max_step / f) and
// (steps, max_step), f = 2^halvings: ceil() makes it less than f on some intervals (1.5 for
// f = 2 at worst), and the Richardson factor must use the worst one.
double refinement_ratio(const Robot& robot, int steps, double max_step, int factor) {
  double r = factor;
  for (const Segment& seg : robot.segments) {
    const double len = seg.length / seg.disks;
    r = std::min(r, static_cast<double>(rk4_steps_over(len, factor * steps, max_step / factor)) /
                        rk4_steps_over(len, steps, max_step));
  }
  return r;
}

// The largest ratio of steps per disk interval between the meshes of `fine` and `coarse`
// halvings of the first mesh (coarse <= fine): RK4's tip error on the coarse mesh is at most its
// fourth power times the fine mesh's, interval by interval.
double coarsening_ratio(const Robot& robot, int coarse, int fine) {
  double r = 1.0;
  for (const Segment& seg : robot.segments) {
    const double len = seg.length / seg.disks;
    const int sc = rk4_steps_over(len, SolverOptions::kFirstMeshRk4Steps << coarse,
                                  SolverOptions::kFirstMeshRk4MaxStep / (1 << coarse));
    const int sf = rk4_steps_over(len, SolverOptions::kFirstMeshRk4Steps << fine,
                                  SolverOptions::kFirstMeshRk4MaxStep / (1 << fine));
    r = std::max(r, static_cast<double>(sf) / sc);
  }
  return r;
}

// Cold solves that follow their loading path from rest follow it on the mesh of the fixed mesh's
// coarse loading path (2 steps per disk interval, h <= 4 mm: one halving of the first mesh), and
// if that fails on the fixed mesh's default (8 steps, h <= 1 mm: three halvings), as the fixed
// mesh's cold rule does: on the first mesh, 1 step and 8 mm, curvature near a tendon's limit is
// judged too coarsely (VC called a feasible loaded scene infeasible at 99 % of its load).
constexpr int kPathHalvings = 1;
constexpr int kFinePathHalvings = 3;

// A cold guess that solves the continuous equations (ColdStart::guess_is_answer) is checked on
// the mesh of two halvings (4 steps per disk interval, h <= 2 mm): there the paper robot's
// residual at the guess is its integration error, 1e-12 to 1e-10 of the scale at n = 1-20, within
// Newton's tolerance (1e-9), so the guess is taken with no iteration and no Jacobian, where the
// first mesh's coarser steps cost one iteration.
constexpr int kGuessHalvings = 2;

// Whether `answer`, a converged solve on the mesh of `fine` (h halvings) whose unknowns x met
// Newton's tolerance there, is the refinement's answer: one shot of x on the next coarser mesh
// (no Newton step) gives the Richardson estimates of mesh h's integration error, of the tip,
// |tip_h - tip_coarse| / (r^4 - 1), and of the residual, |F_h - F_coarse| / (r^4 - 1) (bounded by
// the two norms' sum). The residual's must leave x within Newton's tolerance of the continuous
// equations' answer (|F_h| + its estimate), as a converged solve's unknowns are on its own mesh,
// and the tip's within tip_tolerance. On success the answer's summary carries the estimate.
bool accept_by_coarser_shot(const StaticModel& model, const ShotOnMesh& shoot, const SolverOptions& fine, int h,
                            Solution& answer) {
  if (h < 1 || answer.unknowns.size() == 0 || answer.disk_frames.empty()) return false;
  SolverOptions coarse = fine;
  coarse.rk4_steps = fine.rk4_steps / 2;
  coarse.rk4_max_step = 2.0 * fine.rk4_max_step;
  double coarse_norm = INFINITY;
  Frame tip;
  if (!shoot(coarse, answer.unknowns, coarse_norm, tip)) return false;
  const double r4 = std::pow(refinement_ratio(model.robot(), coarse.rk4_steps, coarse.rk4_max_step, 2), 4);
  const double fine_norm = answer.summary.residual_norm;
  const double residual_estimate = (fine_norm + coarse_norm) / (r4 - 1.0);
  const double tip_estimate = (answer.tip().p - tip.p).norm() / (r4 - 1.0);
  if (!(fine_norm + residual_estimate <= fine.function_tolerance) || !(tip_estimate <= fine.tip_tolerance))
    return false;
  SolverSummary& sum = answer.summary;
  sum.residual_evaluations += 1;
  sum.tip_error_estimate = tip_estimate;
  sum.tip_error_estimate_age = 0;
  sum.rk4_refinements = 1;
  sum.rk4_halvings = h;
  return true;
}
static_assert((SolverOptions::kFirstMeshRk4Steps << kPathHalvings) == SolverOptions::kCoarsePathRk4Steps);

}  // namespace

// Solve on the first mesh, then on finer meshes, each warm-started from the last, until the
// Richardson estimate of the tip error is within the tolerance. RK4's error goes like h^4, so
// the finer answer's error is about |tip_fine - tip_coarse| / (r^4 - 1) for a step ratio r. The
// first refinement halves the steps; later ones jump by as many halvings as the last estimate
// says are needed (its error / 16 per halving), so that a tight tolerance does not solve every
// mesh on the way. A warm-started solve solves on the mesh its warm start's estimate predicts
// (below), and falls back to this refinement from one halving below the warm start's mesh.
// Its answer's stability is not tested here: `test` says whether the rule asks for it (decided by
// the first solve's path: the refined answers are direct warm solves), `last` gives the options
// of the solve that returned it.
// `path`: a cold tension solve whose cold rule follows the loading path from rest.
Solution solve_refined(const StaticModel& model, ModelWorkspace& workspace, const ModelInput& input,
                       const SolverOptions& options, const Solution* warm_start, bool path, bool guess_is_answer,
                       const KeepHistory& keep_history, const ShotOnMesh& shoot, SolverOptions& last_options,
                       bool& test) {
  const auto t0 = std::chrono::steady_clock::now();
  const double tol = options.tip_tolerance;
  SolverOptions o = options;
  o.integrator = IntegratorKind::FixedStepRK4;
  o.stability = StabilityCheck::Never;
  test = false;
  const auto set_mesh = [&](SolverOptions& opt, int h) {
    opt.rk4_steps = SolverOptions::kFirstMeshRk4Steps << h;
    opt.rk4_max_step = SolverOptions::kFirstMeshRk4MaxStep / (1 << h);
  };
  SolverSummary spent;  // work of solves whose answers are not the refinement's
  // The refinement's last converged answer and the number of halvings of its mesh.
  std::optional<Solution> last;
  int halvings = 0, next = 1;
  // A warm start with a measured or predicted estimate (a trajectory's last step): solve on the
  // coarsest mesh its estimate predicts within a share of the tolerance (RK4's error scales with
  // the fourth power of the step), from the warm start (its Jacobian and the secant predictor fit
  // a neighbouring mesh as well). The prediction is the answer's estimate while it is fresh
  // enough (SolverOptions::kMaxEstimateAge solves, a tip move below kMaxPredictedTipMove of the
  // length per solve); otherwise the estimate is measured: one Newton step from the answer on the
  // neighbouring mesh (the coarser one; from the first mesh the finer one), Newton's tolerance
  // ten times looser there and the workspace's warm-start history left as the solve on the
  // answer's mesh made it. Above the tolerance, the refinement goes on from the answer.
  const SolverSummary* from = warm_start ? &warm_start->summary : nullptr;
  if (from && from->integrator == "rk4" && std::isfinite(from->tip_error_estimate) &&
      !warm_start->disk_frames.empty()) {
    const int hw = std::clamp(from->rk4_halvings, 0, SolverOptions::kMaxRk4Halvings);
    const double share = SolverOptions::kPredictedToleranceShare * tol;
    const auto predicted = [&](int h) {
      return from->tip_error_estimate * std::pow(coarsening_ratio(model.robot(), h, hw), 4);
    };
    int h = hw;
    while (h > 0 && predicted(h - 1) <= share) --h;
    set_mesh(o, h);
    Solution answer = tdcr::solve(model, workspace, input, o, warm_start);
    test = answer.converged() && wants_stability(options.stability, input, reached_by_path(answer), false);
    last_options = o;
    if (answer.converged() && answer.summary.integrator == "rk4" && !answer.disk_frames.empty()) {
      SolverSummary& sum = answer.summary;
      sum.rk4_halvings = h;
      const auto finish = [&]() {
        sum.solve_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        return answer;
      };
      const int age = from->tip_error_estimate_age + 1;
      const double moved = (answer.tip().p - warm_start->tip().p).norm();
      if (predicted(h) <= share && age <= SolverOptions::kMaxEstimateAge &&
          moved <= SolverOptions::kMaxPredictedTipMove * model.robot().total_length()) {
        sum.tip_error_estimate = predicted(h);
        sum.tip_error_estimate_age = age;
        return finish();
      }
      const bool finer = h == 0;
      SolverOptions oc = o;
      set_mesh(oc, finer ? 1 : h - 1);
      oc.function_tolerance = std::min(10.0 * o.function_tolerance, SolverOptions::kMaxFunctionTolerance);
      oc.stability = StabilityCheck::Never;
      oc.differential_kinematics = false;
      // One Newton step from the answer: the meshes' answers differ by the discretisation
      // error, so the step lands on the other mesh's answer up to the square of it.
      oc.max_iterations = 1;
      oc.continuation = false;
      const double r = finer ? refinement_ratio(model.robot(), o.rk4_steps, o.rk4_max_step, 2)
                             : refinement_ratio(model.robot(), oc.rk4_steps, oc.rk4_max_step, 2);
      const Solution c = keep_history([&]() { return tdcr::solve(model, workspace, input, oc, &answer); });
      const bool stepped = c.converged() || (c.summary.termination == TerminationType::MaxIterations &&
                                             !c.disk_frames.empty() && c.tip().p.allFinite());
      if (stepped) {
        add_work(c.summary, sum);
        // Richardson: the finer answer's error is d / (r^4 - 1), the coarser one's r^4 times that.
        const double r4 = std::pow(r, 4);
        const double d = (answer.tip().p - c.tip().p).norm();
        sum.tip_error_estimate = finer ? d * r4 / (r4 - 1.0) : d / (r4 - 1.0);
        sum.tip_error_estimate_age = 0;
        sum.rk4_refinements = 1;
        if (sum.tip_error_estimate <= tol) return finish();
        if (h >= SolverOptions::kMaxRk4Halvings) {
          sum.termination = TerminationType::NoConvergence;
          sum.message = "accuracy-driven RK4: tip error estimate " + format_value(sum.tip_error_estimate) +
                        " m above solver.tip_tolerance " + format_value(tol) + " m on the finest mesh allowed";
          return finish();
        }
        halvings = h;
        next = static_cast<int>(std::ceil(std::log(sum.tip_error_estimate / tol) / std::log(16.0)));
        next = std::clamp(next, 1, SolverOptions::kMaxRk4Halvings - halvings);
        last = std::move(answer);
      } else {
        add_work(answer.summary, spent);
        add_work(c.summary, spent);
      }
    } else {
      add_work(answer.summary, spent);
    }
    // Otherwise the refinement from one halving below the warm start's mesh, as from a cold start.
  }
  if (!last) {
    // The first solve's mesh, as halvings of the first mesh's steps.
    halvings = path ? kPathHalvings : 0;
    if (warm_start && warm_start->summary.rk4_halvings > 0)
      halvings = std::min(warm_start->summary.rk4_halvings - 1, SolverOptions::kMaxRk4Halvings - 1);
    const bool check_guess = guess_is_answer && !warm_start && !path;
    if (check_guess) {
      // Newton's test of a first guess is 100 times stricter than its tolerance (KINSOL's); here
      // the tolerance itself is checked below, with the mesh's own error added.
      halvings = kGuessHalvings;
      o.function_tolerance = std::min(100.0 * options.function_tolerance, SolverOptions::kMaxFunctionTolerance);
    }
    set_mesh(o, halvings);
    Solution first_answer = tdcr::solve(model, workspace, input, o, warm_start);
    o.function_tolerance = options.function_tolerance;
    last_options = o;
    add_work(spent, first_answer.summary);
    if (check_guess && first_answer.converged() && first_answer.summary.iterations == 0 &&
        first_answer.summary.integrator == "rk4" &&
        accept_by_coarser_shot(model, shoot, o, halvings, first_answer)) {
      test = wants_stability(options.stability, input, reached_by_path(first_answer), false);
      first_answer.summary.function_tolerance = options.function_tolerance;
      first_answer.summary.solve_time_s =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      return first_answer;
    }
    if (check_guess && !first_answer.converged()) {  // the refinement's own start instead
      const SolverSummary checked = first_answer.summary;
      halvings = 0;
      set_mesh(o, halvings);
      first_answer = tdcr::solve(model, workspace, input, o, nullptr);
      add_work(checked, first_answer.summary);
    }
    if (path && !first_answer.converged()) {
      // As the fixed mesh's cold rule does: the whole path again on the fine mesh.
      const SolverSummary first = first_answer.summary;
      halvings = kFinePathHalvings;
      set_mesh(o, halvings);
      o.coarse_loading_path = false;
      first_answer = tdcr::solve(model, workspace, input, o, nullptr);
      o.coarse_loading_path = options.coarse_loading_path;
      add_work(first, first_answer.summary);
      first_answer.summary.message += " (followed on a finer mesh, " + std::to_string(o.rk4_steps) +
                                      " steps per disk interval at least, h <= " + format_value(o.rk4_max_step) +
                                      " m, because on the coarse one: " + first.message + ")";
    }
    // (VC and VCref only: their tests count under loads alone.)
    test = first_answer.converged() &&
           wants_stability(options.stability, input, reached_by_path(first_answer), false);
    if (!first_answer.converged() || first_answer.summary.integrator != "rk4" || first_answer.disk_frames.empty())
      return first_answer;
    last = std::move(first_answer);
  }
  Solution coarse = std::move(*last);
  SolverSummary work = coarse.summary;
  const std::vector<PathEvent> events = coarse.path_events;
  int solves = coarse.summary.rk4_refinements;
  for (;;) {
    const int factor = 1 << next;
    const double r = refinement_ratio(model.robot(), o.rk4_steps, o.rk4_max_step, factor);
    o.rk4_steps *= factor;
    o.rk4_max_step /= factor;
    halvings += next;
    ++solves;
    Solution fine = tdcr::solve(model, workspace, input, o, &coarse);
    last_options = o;
    add_work(fine.summary, work);
    SolverSummary& sum = fine.summary;
    sum.iterations = work.iterations;
    sum.residual_evaluations = work.residual_evaluations;
    sum.jacobian_evaluations = work.jacobian_evaluations;
    sum.continuation_steps = work.continuation_steps;
    sum.rk4_refinements = solves;
    sum.rk4_halvings = halvings;
    if (fine.path_events.empty()) fine.path_events = events;
    const auto finish = [&]() {
      sum.solve_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      return fine;
    };
    const std::string mesh = std::to_string(o.rk4_steps) + " steps per interval at least, h <= " +
                             format_value(o.rk4_max_step) + " m";
    if (!fine.converged()) {
      sum.message = "accuracy-driven RK4: the solve on the refined mesh (" + mesh + ") failed: " + sum.message;
      return finish();
    }
    sum.tip_error_estimate = (fine.tip().p - coarse.tip().p).norm() / (std::pow(r, 4) - 1.0);
    if (sum.tip_error_estimate <= tol) return finish();
    if (halvings >= SolverOptions::kMaxRk4Halvings) {
      sum.termination = TerminationType::NoConvergence;
      sum.message = "accuracy-driven RK4: tip error estimate " + format_value(sum.tip_error_estimate) +
                    " m above solver.tip_tolerance " + format_value(tol) + " m on the finest mesh allowed (" +
                    mesh + ", " + std::to_string(1 << halvings) + " times the first)";
      return finish();
    }
    next = static_cast<int>(std::ceil(std::log(sum.tip_error_estimate / tol) / std::log(16.0)));
    next = std::clamp(next, 1, SolverOptions::kMaxRk4Halvings - halvings);
    coarse = std::move(fine);
  }
}

// --- Coarse loading paths (SolverOptions::coarse_loading_path; what each does: rk4_refinement.hpp). ---

bool wants_coarse_path(const StaticModel& model, const SolverOptions& options, const Solution* warm_start,
                       const std::string& reason) {
  return options.coarse_loading_path && !warm_start && options.continuation && !reason.empty() &&
         options.integrator == IntegratorKind::FixedStepRK4 &&
         model.capabilities().rk4_mesh &&
         (options.rk4_steps > SolverOptions::kCoarsePathRk4Steps ||
          options.rk4_max_step < SolverOptions::kCoarsePathRk4MaxStep);
}

Solution solve_with_coarse_path(const StaticModel& model, ModelWorkspace& workspace, const ModelInput& input,
                                const SolverOptions& options, std::string& failure) {
  // The coarse mesh, never finer than the requested one in either of its two settings.
  SolverOptions coarse_options = options;
  coarse_options.rk4_steps = std::min(options.rk4_steps, SolverOptions::kCoarsePathRk4Steps);
  coarse_options.rk4_max_step = std::max(options.rk4_max_step, SolverOptions::kCoarsePathRk4MaxStep);
  coarse_options.coarse_loading_path = false;
  coarse_options.stability = StabilityCheck::Never;
  coarse_options.differential_kinematics = false;
  const Solution coarse = tdcr::solve(model, workspace, input, coarse_options, nullptr);
  if (!coarse.converged()) {
    failure = "the loading path on the coarse mesh failed: " + coarse.summary.message;
    return coarse;
  }
  SolverOptions fine_options = options;
  fine_options.coarse_loading_path = false;
  // The answer is the coarse path's: the warm solve from it tests it by the path's rule.
  // (VC and VCref only: their tests count under loads alone.)
  fine_options.stability = resolved_stability(options.stability, input, reached_by_path(coarse), true);
  Solution fine = tdcr::solve(model, workspace, input, fine_options, &coarse);
  if (!fine.converged()) {
    failure = "the solve on the requested mesh from the coarse path's answer failed: " + fine.summary.message;
    add_work(coarse.summary, fine.summary);
    return fine;
  }
  add_work(coarse.summary, fine.summary);
  fine.path_events = coarse.path_events;
  fine.summary.message = "loading path on a coarse RK4 mesh (" + std::to_string(coarse_options.rk4_steps) +
                         " per disk interval at least, h <= " + format_value(coarse_options.rk4_max_step) +
                         " m): " + coarse.summary.message + "; then on the requested mesh: " + fine.summary.message;
  return fine;
}

}  // namespace tdcr::detail
