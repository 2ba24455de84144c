#include "tdcr/core/solver_options.hpp"

#include <cmath>

#include "tdcr/core/error.hpp"

namespace tdcr {

void SolverOptions::validate() const {
  auto positive = [](const char* name, double v) {
    if (!(std::isfinite(v) && v > 0.0))
      throw InputError(std::string("solver.") + name, format_value(v), "must be a positive number");
  };
  positive("function_tolerance", function_tolerance);
  positive("step_tolerance", step_tolerance);
  positive("cvode_rtol", cvode_rtol);
  positive("cvode_atol", cvode_atol);
  if (!(rk4_max_step > 0.0))  // +infinity allowed: exactly rk4_steps steps per interval
    throw InputError("solver.rk4_max_step", format_value(rk4_max_step), "must be positive");
  if (!(std::isfinite(rk4_tip_tolerance) && rk4_tip_tolerance >= 0.0))
    throw InputError("solver.rk4_tip_tolerance", format_value(rk4_tip_tolerance),
                     "must be a non-negative number (0: fixed RK4 steps)");
  if (max_iterations < 1)
    throw InputError("solver.max_iterations", std::to_string(max_iterations), "must be at least 1");
  if (rk4_steps < 1) throw InputError("solver.rk4_steps", std::to_string(rk4_steps), "must be at least 1");
  if (max_continuation_steps < 1)
    throw InputError("solver.max_continuation_steps", std::to_string(max_continuation_steps),
                     "must be at least 1");
}

std::string to_string(IntegratorKind k) { return k == IntegratorKind::Cvode ? "cvode" : "rk4"; }

std::string to_string(LinearSolverKind k) {
  switch (k) {
    case LinearSolverKind::Dense: return "dense";
    case LinearSolverKind::SparseKLU: return "klu";
    default: return "auto";
  }
}

}  // namespace tdcr
