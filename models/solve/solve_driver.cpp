// The one solve driver: every model is solved through tdcr::solve(model, workspace, input,
// options, warm_start). It owns the policy; the model's ModelProblem owns the physics.
#include <algorithm>
#include <chrono>
#include <functional>
#include <cstdio>
#include <cmath>
#include <limits>
#include <optional>

#include "solve/bvp_options.hpp"
#include "solve/differential_kinematics.hpp"
#include "solve/displacement_input.hpp"
#include "solve/load_continuation.hpp"
#include "tdcr/models/model_problem.hpp"
#include "solve/newton_summary.hpp"
#include "physics/geometry_check.hpp"
#include "physics/load_case.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/models/static_model.hpp"
#include "tdcr/models/tendon_physics.hpp"

namespace tdcr {

namespace {

void check_warm_start(const StaticModel& model, const Solution& warm) {
  if (warm.model != model.name())
    throw InputError("warm_start", "a Solution of model \"" + warm.model + "\"",
                     "a warm start must come from the same model (" + model.name() + ")");
  if (warm.model_fingerprint != model.fingerprint())
    throw InputError("warm_start", "a Solution of another robot or other effects",
                     "a warm start must come from the same model of the same robot (StaticModel::fingerprint)");
}

// --- Which answers get their stability tested (SolverOptions::stability). ---

// External loads: a tip force or moment, or gravity.
bool externally_loaded(const Loads& loads) {
  return !loads.tip_force.isZero(0.0) || !loads.tip_moment.isZero(0.0) || !loads.gravity.isZero(0.0);
}

// Whether an answer reached by a loading path or not (`by_path`) is tested: the automatic rule
// tests the answers of loading paths (from rest, snaps, a warm start's input path) and, where
// the model's test is cheap (`loads_count`: ModelProblem::automatic_stability_under_loads, for a
// cold solve), of loaded scenes; not plain unloaded direct solves nor warm steps.
bool wants_stability(StabilityCheck check, const ModelInput& input, bool by_path, bool loads_count) {
  switch (check) {
    case StabilityCheck::Always: return true;
    case StabilityCheck::Never: return false;
    default: return by_path || (loads_count && externally_loaded(input.loads));
  }
}

// Whether a Solution's answer was reached along a path: continuation steps (the loading path
// from rest, a warm start's input path) or path events (folds, snaps).
bool reached_by_path(const Solution& sol) {
  return sol.summary.continuation_steps > 0 || !sol.path_events.empty();
}

// The rule resolved for a solve whose answer another solve's path reached (`by_path`): Always or
// Never, so that the solve from that answer (a direct warm solve) keeps the verdict's rule.
StabilityCheck resolved_stability(StabilityCheck check, const ModelInput& input, bool by_path, bool loads_count) {
  return wants_stability(check, input, by_path, loads_count) ? StabilityCheck::Always : StabilityCheck::Never;
}

// Direct Newton solve from x, with one retry from the problem's alternative cold guess. A cold
// solve freezes the Jacobian near the solution where the problem allows it (and the options
// allow Jacobian reuse at all). attempt_cap > 0 bounds the Newton iterations of each attempt
// (within the options' total).
void direct_solve(detail::ModelProblem& P, bvp::ParameterizedSystem& sys, const bvp::NewtonOptions& options,
                  bool warm, bool allow_reuse, Eigen::VectorXd& x, SolverSummary& sum, int attempt_cap = 0) {
  bvp::NewtonOptions nopt = options;
  const double freeze = P.cold_freeze_jacobian_below();
  if (!warm && allow_reuse && freeze > nopt.function_tolerance) nopt.freeze_jacobian_below = freeze;
  const int budget = nopt.max_iterations;
  if (attempt_cap > 0) nopt.max_iterations = std::min(budget, attempt_cap);
  bvp::NewtonResult res = P.newton().solve(sys, x, nopt);
  detail::copy_newton_result(res, sum);
  if (res.converged() || warm || budget <= sum.iterations) return;
  Eigen::VectorXd xr;
  if (!P.alternative_guess(xr)) return;
  bvp::NewtonOptions ropt = nopt;
  ropt.max_iterations = budget - sum.iterations;
  if (attempt_cap > 0) ropt.max_iterations = std::min(ropt.max_iterations, attempt_cap);
  const std::string first = sum.message;
  res = P.newton().solve(sys, xr, ropt);
  detail::copy_newton_result(res, sum);
  if (res.converged()) {
    x = xr;
    sum.message += " (retry from the other initial guess; first attempt: " + first + ")";
  } else {
    sum.message += "; first attempt: " + first;
  }
}

// The converged flag must describe the returned unknowns: evaluate the residual at full load.
// After a stopped loading path x is the equilibrium at load factor `reached`: evaluated there.
bool final_check(detail::ModelProblem& P, bvp::ParameterizedSystem& sys, const Eigen::VectorXd& x, double reached,
                 double tolerance, SolverSummary& sum) {
  sys.set_parameter(reached);
  Eigen::VectorXd f(sys.size()), scale(sys.size());
  const bool evaluated = P.final_residual(x, f);
  if (!sum.converged()) return evaluated;
  sys.residual_scale(scale);
  const double scaled =
      evaluated && sys.size() > 0 ? f.cwiseProduct(scale).cwiseAbs().maxCoeff() : (evaluated ? 0.0 : INFINITY);
  if (!(scaled <= tolerance)) {
    sum.termination = evaluated ? TerminationType::NoConvergence : TerminationType::IntegrationFailed;
    sum.message += evaluated ? "; final residual " + format_value(scaled) + " above tolerance"
                             : "; the residual at the solution could not be evaluated";
    sum.residual_norm = scaled;
  }
  return evaluated;
}

// A loading path stopped at load factor `reached` < 1: if a tendon is at its geometric limit
// there (the model's own test, else the disk frames), the actuation is infeasible.
void name_infeasibility(detail::ModelProblem& P, const TendonRouting& routing, const Eigen::VectorXd& x,
                        double reached, Solution& sol) {
  std::string why;
  if (!P.infeasibility(x, physics::kTendonLimitNear, why) &&
      !physics::tendon_limit(routing, sol, physics::kTendonLimitNear, why))
    return;
  char buf[64];
  std::snprintf(buf, sizeof buf, ", reached at %.1f %% of the load; ", 100.0 * reached);
  sol.summary.termination = TerminationType::Infeasible;
  sol.summary.message = why + buf + sol.summary.message;
}

// --- The answer to a loaded scene (docs/models.md): the loading path from rest. ---

// Load parameters up to which a cold direct solve is taken as the answer: below them the
// external loads only perturb the tendon-bent shape the cold guesses start from, and the direct
// solve lands on the branch connected to rest (VCref's measured thresholds, docs/models.md).
constexpr double kDirectLoadParameter = 2.0;
// Newton iterations a cold direct solve may take before the loading path takes over. Direct
// solves that land take at most 13 on the loaded cases of bench_loaded (28 with accuracy-driven
// RK4, over its refinement solves; docs/models.md); VCref's on the antagonistic scene of
// tests/data/antagonistic_tip_force.json spent 86 before failing.
constexpr int kColdDirectIterations = 30;
constexpr double kDirectCompressionParameter = 2.0;

// Why a cold solve must follow the loading path instead of a direct solve ("" if it need not).
std::string path_reason(const StaticModel& model, const ModelInput& input, const detail::ColdStart& cold) {
  if (cold.from_rest) return cold.reason;
  physics::LoadCase load;
  load.bind(model.robot(), model.routing(), input);
  if (load.load_parameter() <= kDirectLoadParameter && load.compression_parameter() <= kDirectCompressionParameter)
    return "";
  char why[200];
  std::snprintf(why, sizeof why,
                "loaded from rest: L^2 (|W| + |F_tip|) / EI = %.3g, compression parameter %.3g (direct solve up to %g, %g)",
                load.load_parameter(), load.compression_parameter(), kDirectLoadParameter,
                kDirectCompressionParameter);
  return why;
}

// --- Warm starts: the path from the previous answer (docs/models.md). ---

// Whether an input path can start at a previous Solution's input (its tensions and loads):
// tension input with the same tendon count.
bool has_previous_input(const Solution& previous, const ModelInput& input) {
  return input.actuation.kind == Actuation::Kind::Tensions && previous.tensions.size() == input.actuation.values.size();
}

// The input of a previous Solution, for the input path (built only when the path is walked).
ModelInput previous_input(const Solution& previous, const ModelInput& input) {
  ModelInput from = input;
  from.actuation.values = previous.tensions;
  from.loads = previous.loads;
  return from;
}

// A warm start whose tip force changes this much (L^2 |dF| / EI, the load parameter of the
// change) follows the input path instead of a direct solve, which could jump to another branch.
bool large_change(const StaticModel& model, const Loads& from, const Loads& to) {
  const Robot& robot = model.robot();
  const double L = robot.total_length();
  return L * L * (to.tip_force - from.tip_force).norm() / robot.backbone.effective_stiffness().EI >
         kDirectLoadParameter;
}

// Cold or warm solve of a system: the direct solve where it lands on the loading branch, else
// (or when it fails) the loading path: from rest for a cold solve, from the previous answer's
// input for a warm one (then from rest if that fails too). Returns the load factor reached (1:
// the input).
double solve_on_loading_path(const StaticModel& model, const ModelInput& input, detail::ModelProblem& P,
                             bvp::ParameterizedSystem& sys, const bvp::NewtonOptions& nopt, const SolverOptions& options,
                             const Solution* warm_start, const detail::Rebind& rebind, Eigen::VectorXd& x,
                             const Eigen::VectorXd* unpredicted, Solution& sol) {
  SolverSummary& sum = sol.summary;
  const bool warm = warm_start != nullptr;
  const detail::ColdStart cold = P.cold_start();
  const std::string reason = warm ? "" : path_reason(model, input, cold);
  if (!reason.empty() && options.continuation)
    return detail::follow_loading_path(P, model.routing(), sys, x, nopt, options, sum, sol.path_events, cold.first_step, reason)
        .parameter;
  const bool input_path = warm && options.continuation && has_previous_input(*warm_start, input);
  if (!warm) P.cold_guess(x);
  const bool skip_direct = input_path && large_change(model, warm_start->loads, input.loads);
  if (skip_direct && unpredicted) x = *unpredicted;
  if (!skip_direct) {
    // A cold direct solve is only the fast path to the loading path's answer: when an attempt
    // has not converged within kColdDirectIterations, the next guess or the loading path from
    // rest takes over.
    const int cap = !warm && options.continuation ? kColdDirectIterations : 0;
    direct_solve(P, sys, nopt, warm, options.reuse_jacobian, x, sum, cap);
    if (!sum.converged() && unpredicted) {  // the secant prediction failed: from the last answer
      const std::string first = sum.message;
      x = *unpredicted;
      direct_solve(P, sys, nopt, warm, options.reuse_jacobian, x, sum);
      sum.message += " (retry from the previous answer; from the secant prediction: " + first + ")";
    }
    if (sum.converged() || !options.continuation) return 1.0;
  }
  std::string why = skip_direct ? "the warm start's tip force differs by L^2 |dF| / EI > " + format_value(kDirectLoadParameter)
                                : (warm ? "warm-started direct solve failed: " : "direct solve failed: ") + sum.message;
  if (input_path) {
    const Eigen::VectorXd guess = x;
    if (detail::follow_input_path(rebind, previous_input(*warm_start, input), input, *warm_start, nopt, x, sum)) {
      const std::string path = sum.message;
      direct_solve(P, sys, nopt, true, options.reuse_jacobian, x, sum);  // at the path's end: converged in 0-1 iterations
      if (sum.converged()) {
        sum.message = path + "; " + sum.message;
        return 1.0;
      }
    }
    x = guess;
    why += "; then the input path from the warm start failed: " + sum.message;
  }
  return detail::follow_loading_path(P, model.routing(), sys, x, nopt, options, sum, sol.path_events, cold.first_step, why).parameter;
}

// --- The secant predictor of warm starts (SolverOptions::extrapolate_warm_starts). ---

// An input as one vector: actuation values, tip force, tip moment, gravity.
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
bool extrapolate(const detail::SolveHistory& h, const Eigen::VectorXd& from, const Eigen::VectorXd& u,
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

// Solution::tip_jacobian and tip_compliance of a converged answer at unknowns x.
void add_differential_kinematics(const StaticModel& model, const detail::Rebind& rebind, const ModelInput& input,
                                 double tolerance, const Eigen::VectorXd& x, Solution& sol) {
  physics::LoadCase load;
  load.bind(model.robot(), model.routing(), input);
  detail::differential_kinematics(rebind, input, load.force_scale(), load.moment_scale(), tolerance, x, sol);
}

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

void add_work(const SolverSummary& from, SolverSummary& to) {
  to.iterations += from.iterations;
  to.residual_evaluations += from.residual_evaluations;
  to.jacobian_evaluations += from.jacobian_evaluations;
  to.continuation_steps += from.continuation_steps;
}

// Cold solves that follow their loading path from rest follow it on the mesh of the fixed mesh's
// coarse loading path (2 steps per disk interval, h <= 4 mm: one halving of the first mesh), and
// if that fails on the fixed mesh's default (8 steps, h <= 1 mm: three halvings), as the fixed
// mesh's cold rule does: on the first mesh, 1 step and 8 mm, curvature near a tendon's limit is
// judged too coarsely (VC called a feasible loaded scene infeasible at 99 % of its load).
constexpr int kPathHalvings = 1;
constexpr int kFinePathHalvings = 3;
static_assert((SolverOptions::kFirstMeshRk4Steps << kPathHalvings) == SolverOptions::kCoarsePathRk4Steps);

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
// Runs a solve and leaves the workspace's warm-start history as it was before it.
using KeepHistory = std::function<Solution(const std::function<Solution()>&)>;

// `path`: a cold tension solve whose cold rule follows the loading path from rest.
Solution solve_refined(const StaticModel& model, ModelWorkspace& workspace, const ModelInput& input,
                       const SolverOptions& options, const Solution* warm_start, bool path,
                       const KeepHistory& keep_history, SolverOptions& last_options, bool& test) {
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
    set_mesh(o, halvings);
    Solution first_answer = tdcr::solve(model, workspace, input, o, warm_start);
    last_options = o;
    add_work(spent, first_answer.summary);
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

// --- Coarse loading paths (SolverOptions::coarse_loading_path). ---

// Whether a cold solve of VC or VCref on RK4 should follow its loading path on the coarse mesh:
// the path is the model's cold rule here (reason non-empty) and the requested mesh is finer.
bool wants_coarse_path(const StaticModel& model, const SolverOptions& options, const Solution* warm_start,
                       const std::string& reason) {
  return options.coarse_loading_path && !warm_start && options.continuation && !reason.empty() &&
         options.integrator == IntegratorKind::FixedStepRK4 &&
         model.capabilities().rk4_mesh &&
         (options.rk4_steps > SolverOptions::kCoarsePathRk4Steps ||
          options.rk4_max_step < SolverOptions::kCoarsePathRk4MaxStep);
}

// The loading path on the coarse mesh, then Newton on the requested mesh from its answer (a warm
// start at the same input: a direct solve). If either fails the result is not converged, with
// the reason in `failure`; the caller then follows the path on the requested mesh. Work counts
// are those of both solves, path events the coarse path's.
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

}  // namespace

Solution solve(const StaticModel& model, ModelWorkspace& workspace, const ModelInput& input,
               const SolverOptions& requested, const Solution* warm_start) {
  const auto t0 = std::chrono::steady_clock::now();
  requested.validate();
  // The tip tolerance and the Newton tolerance tied to it, for this robot.
  const SolverOptions options = requested.resolved(model.robot().total_length());
  input.validate(model.robot());
  model.check_input(input);
  if (!workspace.belongs_to(model))
    throw InputError("workspace", "a workspace of another model",
                     "use the workspace made by this model's make_workspace() (" + model.name() + ")");
  if (warm_start) check_warm_start(model, *warm_start);
  if (options.integrator == IntegratorKind::AccuracyDrivenRK4 && model.capabilities().rk4_mesh) {
    bool path = false;
    // Whether the automatic rule tests a direct answer under these loads (as the model says),
    // asked before the refinement binds its own solves. Models whose problems always say no are
    // not asked (ModelCapabilities::stability_under_loads, VC): a bind just to ask changed the state a workspace's next cold solve starts from (a sweep's
    // rows then depended on which samples a thread had solved before,
    // SweepRun.MergedShardsEqualOneRun under load).
    bool under_loads = false;
    const bool displacement = detail::needs_displacement_solve(model, input);
    // Cold solves only: a trajectory's warm step from a tested answer is not tested again (VCref's
    // test would add 92 % to a loaded trajectory's step); it is when its input path snaps.
    const bool ask = options.stability == StabilityCheck::Automatic && externally_loaded(input.loads) &&
                     !displacement && model.capabilities().stability_under_loads && !warm_start;
    if ((!warm_start && options.continuation && !displacement) || ask) {
      SolverOptions first = options;
      first.integrator = IntegratorKind::FixedStepRK4;
      first.rk4_steps = SolverOptions::kFirstMeshRk4Steps;
      first.rk4_max_step = SolverOptions::kFirstMeshRk4MaxStep;
      detail::ModelProblem& P = model.bind(workspace, input, first);
      under_loads = ask && P.automatic_stability_under_loads();
      if (!warm_start && options.continuation && !displacement)
        path = P.system() && !path_reason(model, input, P.cold_start()).empty();
    }
    const KeepHistory keep_history = [&workspace](const std::function<Solution()>& run) {
      detail::SolveHistory saved = workspace.history_;
      Solution s = run();
      workspace.history_ = std::move(saved);
      return s;
    };
    SolverOptions last;
    bool test = false;
    Solution sol = solve_refined(model, workspace, input, options, warm_start, path, keep_history, last, test);
    // solve_refined decides by the path alone. A direct answer under loads the model tests
    // (VCref): the problem bound with the options of the solve that returned it (its mesh, not
    // the estimate's) and tested at the answer's unknowns as a warm start gives them (VCref: its
    // chart references at the answer's disks, as a solve from it sets them), without the solve
    // from it below (which costs VCref 13 % of its median loaded solve, bench_loaded).
    if (sol.converged() && !test && under_loads) {
      detail::ModelProblem& P = model.bind(workspace, input, last);
      Eigen::VectorXd x;
      if (P.system() && P.warm_guess(sol, x) && x.size() == P.system()->size()) {
        P.system()->set_parameter(1.0);
        sol.stability = P.direct_stability(x, 1.0);
        sol.summary.solve_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      } else {
        test = true;
      }
    }
    if (sol.converged() && test) {
      // The last answer tested: a solve on its mesh from it (no Newton iteration where it already
      // meets the tolerance there) with the test forced on, so that the test reads the answer's
      // own evaluation, not the estimate's on another mesh; the warm-start history is left as
      // the refinement made it.
      SolverOptions check = last;
      check.stability = StabilityCheck::Always;
      const Solution checked = keep_history([&]() { return tdcr::solve(model, workspace, input, check, &sol); });
      if (checked.converged()) sol.stability = checked.stability;
      sol.summary.solve_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    }
    return sol;
  }
  // Displacement input: the driven tendons' tensions join the model's unknowns. A cold solve
  // starts from the tension solve at the tensions linear beam theory gives its pulls (that solve
  // by its own rule: direct, or along its loading path from rest): the commanded pulls are then
  // brought on from that equilibrium's pulls (DisplacementProblem::start_from, a direct solve
  // first); where that fails, the solve is done again from rest (the first attempt's work
  // counted).
  const bool displacement = detail::needs_displacement_solve(model, input);
  Solution start;
  const Solution* tension_start = nullptr;
  std::string start_failure;
  SolverSummary start_work;
  if (displacement && !warm_start && options.continuation) {
    if (detail::tension_start(model, workspace, input, options, start)) tension_start = &start;
    else start_failure = "the tension solve at the linear guess's tensions failed: " + start.summary.message;
    start_work = start.summary;
  }
  // One solve of the bound problem; `from_tensions`: the displacement solve's tension start, if any.
  const auto solve_from = [&](const Solution* from_tensions) -> Solution {
    const auto bind_problem = [&]() -> detail::ModelProblem& {
      return displacement ? detail::bind_displacement_problem(model, workspace, input, options, warm_start, from_tensions)
                          : model.bind(workspace, input, options);
    };
    detail::ModelProblem* bound = &bind_problem();
    std::string coarse_failure;  // why a coarse loading path was not the answer ("" if none was tried)
    SolverSummary coarse_work;   // the work it took (counted in this solve's summary)
    if (bound->system() &&
        wants_coarse_path(model, options, warm_start, path_reason(model, input, bound->cold_start()))) {
      Solution answer = solve_with_coarse_path(model, workspace, input, options, coarse_failure);
      workspace.history_.valid = false;  // a cold solve leaves no warm-start history
      if (answer.converged()) {
        answer.summary.solve_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        return answer;
      }
      coarse_work = answer.summary;
      bound = &bind_problem();  // back to the requested mesh: the whole path there
    }
    detail::ModelProblem& P = *bound;
    Solution sol;
    sol.model = model.name();
    sol.model_fingerprint = model.fingerprint();
    SolverSummary& sum = sol.summary;
    sum.integrator = P.integrator_name();

    bvp::ParameterizedSystem* sys = P.system();
    double reached = 1.0;  // load factor of the answer (< 1: loading from rest stopped there)
    Eigen::VectorXd x;     // the system's unknowns (none for a closed form)
    std::string impossible;
    if (sys && P.impossible_input(impossible)) {
      // The robot at rest, named infeasible: nothing to solve.
      sys->set_parameter(0.0);
      P.rest_state(x);
      reached = 0.0;
      sum.unknowns = sys->size();
      sum.termination = TerminationType::Infeasible;
      sum.message = impossible + " (the robot at rest returned, nothing solved)";
      sol.stability.method = kStabilityNotChecked;
      Eigen::VectorXd f(sys->size());
      sol.unknowns = x;
      P.extract(x, P.final_residual(x, f), sol);
      sys->set_parameter(1.0);
    } else if (!sys) {
      // Closed form: the problem computes the answer and its summary.
      sum.linear_solver = "none";
      P.extract(Eigen::VectorXd(), true, sol);
    } else {
      sum.unknowns = sys->size();
      bvp::NewtonOptions nopt = detail::newton_options(options);
      P.adjust(nopt);
      sys->set_parameter(1.0);
      const bool warm = warm_start && P.warm_guess(*warm_start, x);
      // The secant predictor: this solve's input, its warm start's, and the model's warm guess.
      detail::SolveHistory& history = workspace.history_;
      Eigen::VectorXd u, from, unpredicted;
      bool predicted = false;
      if (warm) {
        input_vector(input.actuation.values, input.loads, u);
        input_vector(warm_start->tensions, warm_start->loads, from);
        if (options.reuse_jacobian) P.adjust_warm(nopt, from == u);
        unpredicted = x;
        if (options.extrapolate_warm_starts && !displacement) predicted = extrapolate(history, from, u, x);
      }
      if (sys->size() == 0) {
        x.resize(0);
        sum.termination = TerminationType::Converged;
        sum.message = "no unknowns: the answer follows from the input alone";
        sum.linear_solver = "none";
      } else {
        const detail::Rebind rebind = [&](const ModelInput& in) -> detail::ModelProblem& {
          return model.bind(workspace, in, options);
        };
        reached = solve_on_loading_path(model, input, P, *sys, nopt, options, warm ? warm_start : nullptr, rebind, x,
                                        predicted ? &unpredicted : nullptr, sol);
        // The problem's own completion (displacement input: compliance to zero, slack and taut
        // tendons); where it changed its equations and cannot solve them from the answer, the
        // solve again, cold.
        constexpr int kMaxFollowAgain = 3;
        for (int again = 0; sum.converged(); ++again) {
          if (P.complete(x, nopt, sum) == detail::ModelProblem::Completion::Done) break;
          if (again == kMaxFollowAgain) {
            sum.termination = TerminationType::NoConvergence;
            sum.message += "; the problem's equations changed " + std::to_string(kMaxFollowAgain + 1) +
                           " times after a converged solve";
            break;
          }
          sys->set_parameter(1.0);
          sol.path_events.clear();
          reached = solve_on_loading_path(model, input, P, *sys, nopt, options, nullptr, rebind, x, nullptr, sol);
        }
      }
      if (sum.converged()) reached = 1.0;
      const bool evaluated = final_check(P, *sys, x, reached, options.function_tolerance, sum);
      sol.unknowns = x;
      P.extract(x, evaluated, sol);
      // Remembered for the next solve's predictor: a converged warm solve (a cold one has no
      // warm guess to correct); anything else clears it.
      history.valid = warm && sum.converged() && x.size() > 0;
      if (history.valid) {
        history.from.swap(from);
        history.input.swap(u);
        history.guess.swap(unpredicted);
        history.unknowns = x;
      }
      // The answer reached along a path: this solve's (continuation steps, path events) or, for
      // displacement input, its tension start's.
      const bool by_path = reached_by_path(sol) || (from_tensions && reached_by_path(*from_tensions));
      if (sum.converged() &&
          wants_stability(options.stability, input, by_path, P.automatic_stability_under_loads() && !warm_start))
        // A direct answer tested for its loads alone: the model's cheaper test where it has one.
        sol.stability = options.stability == StabilityCheck::Automatic && !by_path ? P.direct_stability(x, 1.0)
                                                                                    : P.stability(x, 1.0);
      else sol.stability.method = kStabilityNotChecked;  // short: no allocation
    }
    if (sol.converged() && options.differential_kinematics && !displacement)
      add_differential_kinematics(
          model, [&](const ModelInput& in) -> detail::ModelProblem& { return model.bind(workspace, in, options); },
          input, options.function_tolerance, x, sol);
    if (sol.tensions.empty() && input.actuation.kind == Actuation::Kind::Tensions) sol.tensions = input.actuation.values;
    // The displacement a motor sets: the path's pull plus an elastic tendon's stretch.
    tendon::add_elastic_stretch(model.robot(), model.routing(), sol.tensions, sol.tendon_displacements);
    sol.loads = input.loads;
    if (!sum.converged() && reached < 1.0 && impossible.empty())
      name_infeasibility(P, model.routing(), sol.unknowns, reached, sol);
    physics::check_geometry(model.robot(), model.routing(), sol, P.max_curvature());
    if (!coarse_failure.empty()) {
      sum.message += " (followed on the requested mesh because " + coarse_failure + ")";
      add_work(coarse_work, sum);
    }
    return sol;
  };

  Solution sol = solve_from(tension_start);
  if (tension_start && !sol.converged()) {  // from rest instead
    start_failure = "from the tension solve at the linear guess's tensions: " + sol.summary.message;
    add_work(sol.summary, start_work);
    sol = solve_from(nullptr);
  }
  SolverSummary& sum = sol.summary;
  if (!start_failure.empty()) {
    sum.message += " (from rest because " + start_failure + ")";
    add_work(start_work, sum);
  } else if (displacement && start_work.termination != TerminationType::NotSolved) {
    add_work(start_work, sum);
    sum.message = "from the tension solve at the linear guess's tensions (" + start_work.brief_report() +
                  "): " + sum.message;
  }
  sum.function_tolerance = options.function_tolerance;
  sum.tip_tolerance = options.tip_tolerance;
  sum.solve_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return sol;
}

Solution warm_start_from_other_robot(const StaticModel& model, const Solution& previous) {
  if (previous.model != model.name())
    throw InputError("warm_start", "a Solution of model \"" + previous.model + "\"",
                     "a warm start must come from the same model (" + model.name() + ")");
  if (!previous.converged()) throw InputError("warm_start", "a Solution that did not converge", "a warm start must be converged");
  Solution s = previous;
  s.model_fingerprint = model.fingerprint();
  return s;
}

}  // namespace tdcr
