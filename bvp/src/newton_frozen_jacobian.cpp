/// @file newton_frozen_jacobian.cpp
/// @brief Exact Newton to the freezing threshold, then modified Newton from its last Jacobian
/// (newton_frozen_jacobian.hpp).
#include "newton_frozen_jacobian.hpp"

#include <algorithm>
#include <cmath>
#include <string>

namespace tdcr::bvp::detail {

NewtonResult solve_exact_then_frozen(NewtonSolver& solver, ResidualSystem& system, Eigen::VectorXd& x,
                                     const NewtonOptions& options) {
  // Exact Newton to the freezing threshold, then modified Newton from its last Jacobian.
  NewtonOptions exact = options;
  exact.freeze_jacobian_below = 0.0;
  exact.function_tolerance = options.freeze_jacobian_below;
  exact.max_setup_calls = 1;
  NewtonResult first = solver.solve(system, x, exact);
  // Done if it met the full tolerance as KINSOL judges it: after an iteration, or at the
  // initial guess with KINSOL's margin of 0.01.
  const double done = first.iterations > 0 ? options.function_tolerance : 0.01 * options.function_tolerance;
  if (!first.converged() || first.residual_norm <= done) return first;
  if (first.iterations >= options.max_iterations) {
    // Converged only to the freezing threshold when the budget ran out: not the solve's
    // tolerance (a cold CCsub attempt capped at 30 iterations was returned as converged at
    // |F| = 5e-4, and its caller never tried the loading path).
    first.termination = TerminationType::MaxIterations;
    first.message += " (the iteration budget ended at the Jacobian-freezing threshold, above function_tolerance)";
    return first;
  }
  // Modified Newton converges linearly and stops just below its tolerance, where exact
  // Newton's last step lands far below it: ask it for kFrozenTighter times more, and accept
  // function_tolerance if round-off stops it first.
  constexpr double kFrozenTighter = 1e-2;
  constexpr int kFrozenMaxIterations = 30;
  NewtonOptions frozen = options;
  frozen.freeze_jacobian_below = 0.0;
  frozen.reuse_jacobian = true;
  frozen.max_setup_calls = 10;
  frozen.function_tolerance = options.function_tolerance * kFrozenTighter;
  frozen.max_iterations = std::min(kFrozenMaxIterations, options.max_iterations - first.iterations);
  const Eigen::VectorXd x_first = x;
  NewtonResult r = solver.solve(system, x, frozen);
  const auto add = [](NewtonResult& to, const NewtonResult& from) {
    to.iterations += from.iterations;
    to.residual_evaluations += from.residual_evaluations;
    to.jacobian_evaluations += from.jacobian_evaluations;
    to.fd_residual_evaluations += from.fd_residual_evaluations;
  };
  add(r, first);
  if (r.converged()) return r;
  if (std::isfinite(r.residual_norm) && r.residual_norm <= options.function_tolerance && x.allFinite()) {
    r.termination = TerminationType::Converged;
    r.message += " (within function_tolerance; the tighter target of the modified Newton iterations was not reached)";
    return r;
  }
  // The frozen Jacobian contracted too slowly: exact Newton finishes, from the better point.
  if (!(std::isfinite(r.residual_norm) && r.residual_norm <= first.residual_norm && x.allFinite())) x = x_first;
  NewtonOptions rest = exact;
  rest.function_tolerance = options.function_tolerance;
  rest.max_iterations = std::max(1, options.max_iterations - r.iterations);
  NewtonResult last = solver.solve(system, x, rest);
  add(last, r);
  last.message += " (exact Newton after " + std::to_string(frozen.max_iterations) +
                  " modified Newton iterations did not converge)";
  return last;
}

}  // namespace tdcr::bvp::detail
