// The one solve driver: every model is solved through tdcr::solve(model, workspace, input,
// options, warm_start). It owns the policy; the model's ModelProblem owns the physics.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <limits>

#include "common/load_continuation.hpp"
#include "common/model_problem.hpp"
#include "common/newton_summary.hpp"
#include "physics/geometry_check.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/models/static_model.hpp"

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

// Direct Newton solve from x, with one retry from the problem's alternative cold guess.
void direct_solve(detail::ModelProblem& P, bvp::ParameterizedSystem& sys, const bvp::NewtonOptions& nopt,
                  bool warm, Eigen::VectorXd& x, SolverSummary& sum) {
  bvp::NewtonResult res = P.newton().solve(sys, x, nopt);
  detail::copy_newton_result(res, sum);
  if (res.converged() || warm || nopt.max_iterations <= sum.iterations) return;
  Eigen::VectorXd xr;
  if (!P.alternative_guess(xr)) return;
  bvp::NewtonOptions ropt = nopt;
  ropt.max_iterations = nopt.max_iterations - sum.iterations;
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
  if (!P.infeasibility(x, why) && !physics::tendon_limit(routing, sol, why)) return;
  char buf[64];
  std::snprintf(buf, sizeof buf, ", reached at %.1f %% of the load; ", 100.0 * reached);
  sol.summary.termination = TerminationType::Infeasible;
  sol.summary.message = why + buf + sol.summary.message;
}

}  // namespace

Solution solve(const StaticModel& model, ModelWorkspace& workspace, const ModelInput& input,
               const SolverOptions& options, const Solution* warm_start) {
  const auto t0 = std::chrono::steady_clock::now();
  options.validate();
  input.validate(model.robot());
  model.check_input(input);
  if (!workspace.belongs_to(model))
    throw InputError("workspace", "a workspace of another model",
                     "use the workspace made by this model's make_workspace() (" + model.name() + ")");
  if (warm_start) check_warm_start(model, *warm_start);

  detail::ModelProblem& P = model.bind(workspace, input, options);
  Solution sol;
  sol.model = model.name();
  sol.model_fingerprint = model.fingerprint();
  SolverSummary& sum = sol.summary;
  sum.integrator = P.integrator_name();

  bvp::ParameterizedSystem* sys = P.system();
  double reached = 1.0;  // load factor of the answer (< 1: loading from rest stopped there)
  if (!sys) {
    // Closed form: the problem computes the answer and its summary.
    sum.linear_solver = "none";
    P.extract(Eigen::VectorXd(), true, sol);
  } else {
    sum.unknowns = sys->size();
    bvp::NewtonOptions nopt = bvp::NewtonOptions::from(options);
    P.adjust(nopt);
    Eigen::VectorXd x;
    sys->set_parameter(1.0);
    const bool warm = warm_start && P.warm_guess(*warm_start, x);
    const detail::ColdStart cold = warm ? detail::ColdStart{} : P.cold_start();
    if (sys->size() == 0) {
      x.resize(0);
      sum.termination = TerminationType::Converged;
      sum.message = "no unknowns: the answer follows from the input alone";
      sum.linear_solver = "none";
    } else if (cold.from_rest && options.continuation) {
      sys->set_parameter(0.0);
      P.rest_state(x);
      reached = detail::continue_loads(P.newton(), *sys, x, nopt, options, sum, cold.first_step, cold.reason)
                    .parameter;
    } else {
      if (!warm) P.cold_guess(x);
      direct_solve(P, *sys, nopt, warm, x, sum);
      if (!sum.converged() && options.continuation) {
        sys->set_parameter(0.0);
        P.rest_state(x);
        reached = detail::continue_loads(P.newton(), *sys, x, nopt, options, sum, P.cold_start().first_step)
                      .parameter;
      }
    }
    if (sum.converged()) reached = 1.0;
    const bool evaluated = final_check(P, *sys, x, reached, options.function_tolerance, sum);
    sol.unknowns = x;
    P.extract(x, evaluated, sol);
    if (sum.converged() && options.stability) sol.stability = P.stability(x);
  }
  if (sol.tensions.empty() && input.actuation.kind == Actuation::Kind::Tensions) sol.tensions = input.actuation.values;
  if (!sum.converged() && reached < 1.0) name_infeasibility(P, model.routing(), sol.unknowns, reached, sol);
  physics::check_geometry(model.robot(), model.routing(), sol);
  sol.model = model.name();
  sol.model_fingerprint = model.fingerprint();
  sum.solve_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return sol;
}

}  // namespace tdcr
