// A solve's SolverOptions as bvp's settings (bvp_options.hpp).
#include "solve/bvp_options.hpp"

namespace tdcr::detail {

bvp::LinearSolverKind linear_solver_kind(LinearSolverKind kind) {
  switch (kind) {
    case LinearSolverKind::Dense: return bvp::LinearSolverKind::Dense;
    case LinearSolverKind::SparseKLU: return bvp::LinearSolverKind::SparseKLU;
    case LinearSolverKind::Automatic: break;
  }
  return bvp::LinearSolverKind::Automatic;
}

bvp::NewtonOptions newton_options(const SolverOptions& options) {
  bvp::NewtonOptions o;
  o.function_tolerance = options.function_tolerance;
  o.step_tolerance = options.step_tolerance;
  o.max_iterations = options.max_iterations;
  o.linear_solver = linear_solver_kind(options.linear_solver);
  return o;
}

bvp::ContinuationOptions continuation_options(const SolverOptions& options) {
  bvp::ContinuationOptions c;
  c.max_steps = options.max_continuation_steps;
  return c;
}

bvp::ArclengthOptions arclength_options(const SolverOptions& options) {
  bvp::ArclengthOptions a;
  a.max_steps = options.max_continuation_steps;
  if (!options.reuse_jacobian) a.corrector_freeze_jacobian_below = 0.0;
  return a;
}

bvp::IntegratorOptions integrator_options(const SolverOptions& options) {
  bvp::IntegratorOptions o;
  o.method = is_rk4(options.integrator) ? bvp::IntegratorMethod::Rk4 : bvp::IntegratorMethod::Cvode;
  o.rk4_steps = options.rk4_steps;
  o.rk4_max_step = options.rk4_max_step;
  o.cvode_rtol = options.cvode_rtol;
  o.cvode_atol = options.cvode_atol;
  return o;
}

}  // namespace tdcr::detail
