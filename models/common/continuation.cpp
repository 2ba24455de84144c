#include <algorithm>
#include <cstdio>

#include "common/load_continuation.hpp"

namespace tdcr::detail {

bvp::ContinuationResult continue_loads(bvp::NewtonSolver& newton, bvp::ParameterizedSystem& system,
                                       Eigen::VectorXd& x, const bvp::NewtonOptions& newton_options,
                                       const SolverOptions& options, SolverSummary& sum, double first_step,
                                       const std::string& purpose) {
  const std::string why = purpose.empty() ? "direct solve failed: " + sum.message : purpose;
  bvp::ContinuationOptions copt = bvp::ContinuationOptions::from(options);
  if (first_step > 0.0) copt.initial_step = std::clamp(first_step, copt.min_step, copt.initial_step);
  const bvp::ContinuationResult c = bvp::continuation(newton, system, x, newton_options, copt);
  sum.iterations += c.iterations;
  sum.residual_evaluations += c.residual_evaluations;
  sum.jacobian_evaluations += c.jacobian_evaluations;
  sum.continuation_steps += c.steps;
  const bvp::NewtonResult& r = c.last;
  if (c.steps > 0) {
    sum.solver_flag = r.flag;
    sum.residual_norm = r.residual_norm;
    sum.physical_residual = r.physical_residual;
    if (!r.linear_solver.empty()) sum.linear_solver = r.linear_solver;
  }
  char buf[160];
  if (c.converged()) {
    sum.termination = TerminationType::Converged;
    std::snprintf(buf, sizeof buf, " (by load continuation: %d steps, %d converged; ", c.steps, c.accepted_steps);
    sum.message = r.message + buf + why + ")";
  } else {
    sum.termination = r.converged() || c.steps == 0 ? TerminationType::NoConvergence : r.termination;
    std::snprintf(buf, sizeof buf,
                  "load continuation stopped at %.1f %% of the load (returned shape: the equilibrium there): ",
                  100.0 * c.fraction);
    sum.message = buf + c.message + "; " + why;
  }
  return c;
}

}  // namespace tdcr::detail
