// The one solve driver: every model is solved through tdcr::solve(model, workspace, input,
// options, warm_start). It owns the policy; the model's ModelProblem owns the physics.
#include <algorithm>
#include <chrono>
#include <functional>
#include <cstdio>
#include <cmath>
#include <limits>

#include "solve/bvp_options.hpp"
#include "solve/differential_kinematics.hpp"
#include "solve/rk4_refinement.hpp"
#include "solve/secant_predictor.hpp"
#include "solve/displacement_input.hpp"
#include "solve/load_continuation.hpp"
#include "tdcr/models/model_problem.hpp"
#include "solve/newton_summary.hpp"
#include "solve/stability_rule.hpp"
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

// Solution::tip_jacobian and tip_compliance of a converged answer at unknowns x.
void add_differential_kinematics(const StaticModel& model, const detail::Rebind& rebind, const ModelInput& input,
                                 double tolerance, const Eigen::VectorXd& x, Solution& sol) {
  physics::LoadCase load;
  load.bind(model.robot(), model.routing(), input);
  detail::differential_kinematics(rebind, input, load.force_scale(), load.moment_scale(), tolerance, x, sol);
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
    bool guess_is_answer = false;  // the cold guess is checked on a fine mesh first (ColdStart)
    const bool displacement = detail::needs_displacement_solve(model, input);
    // Cold solves only: a trajectory's warm step from a tested answer is not tested again (VCref's
    // test would add 92 % to a loaded trajectory's step); it is when its input path snaps.
    const bool ask = options.stability == StabilityCheck::Automatic && detail::externally_loaded(input.loads) &&
                     !displacement && model.capabilities().stability_under_loads && !warm_start;
    if ((!warm_start && options.continuation && !displacement) || ask) {
      SolverOptions first = options;
      first.integrator = IntegratorKind::FixedStepRK4;
      first.rk4_steps = SolverOptions::kFirstMeshRk4Steps;
      first.rk4_max_step = SolverOptions::kFirstMeshRk4MaxStep;
      detail::ModelProblem& P = model.bind(workspace, input, first);
      under_loads = ask && P.automatic_stability_under_loads();
      if (!warm_start && options.continuation && !displacement) {
        const detail::ColdStart cold = P.cold_start();
        path = P.system() && !path_reason(model, input, cold).empty();
        guess_is_answer = P.system() && !path && cold.guess_is_answer;
      }
    }
    const detail::KeepHistory keep_history = [&workspace](const std::function<Solution()>& run) {
      detail::SolveHistory saved = workspace.history_;
      Solution s = run();
      workspace.history_ = std::move(saved);
      return s;
    };
    const detail::ShotOnMesh shoot = [&](const SolverOptions& mesh, const Eigen::VectorXd& x, double& scaled,
                                         Frame& tip) {
      detail::ModelProblem& P = model.bind(workspace, input, mesh);
      bvp::ParameterizedSystem* sys = P.system();
      if (!sys || sys->size() != x.size()) return false;
      sys->set_parameter(1.0);
      Eigen::VectorXd f(sys->size()), scale(sys->size());
      if (!P.final_residual(x, f) || !f.allFinite()) return false;
      sys->residual_scale(scale);
      scaled = f.cwiseProduct(scale).cwiseAbs().maxCoeff();
      Solution shot;
      P.extract(x, true, shot);
      if (shot.disk_frames.empty() || !shot.tip().p.allFinite()) return false;
      tip = shot.tip();
      return true;
    };
    SolverOptions last;
    bool test = false;
    Solution sol = detail::solve_refined(model, workspace, input, options, warm_start, path, guess_is_answer,
                                                 keep_history, shoot, last, test);
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
        detail::wants_coarse_path(model, options, warm_start, path_reason(model, input, bound->cold_start()))) {
      Solution answer = detail::solve_with_coarse_path(model, workspace, input, options, coarse_failure);
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
        detail::input_vector(input.actuation.values, input.loads, u);
        detail::input_vector(warm_start->tensions, warm_start->loads, from);
        if (options.reuse_jacobian) P.adjust_warm(nopt, from == u);
        unpredicted = x;
        if (options.extrapolate_warm_starts && !displacement) predicted = detail::extrapolate(history, from, u, x);
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
      const bool by_path = detail::reached_by_path(sol) || (from_tensions && detail::reached_by_path(*from_tensions));
      if (sum.converged() &&
          detail::wants_stability(options.stability, input, by_path, P.automatic_stability_under_loads() && !warm_start))
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
      detail::add_work(coarse_work, sum);
    }
    return sol;
  };

  Solution sol = solve_from(tension_start);
  if (tension_start && !sol.converged()) {  // from rest instead
    start_failure = "from the tension solve at the linear guess's tensions: " + sol.summary.message;
    detail::add_work(sol.summary, start_work);
    sol = solve_from(nullptr);
  }
  SolverSummary& sum = sol.summary;
  if (!start_failure.empty()) {
    sum.message += " (from rest because " + start_failure + ")";
    detail::add_work(start_work, sum);
  } else if (displacement && start_work.termination != TerminationType::NotSolved) {
    detail::add_work(start_work, sum);
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
