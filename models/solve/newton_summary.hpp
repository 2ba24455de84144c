// Private to models/: a solve's summary kept in one place each: a bvp::NewtonResult copied into
// it, and the work of another solve added to it.
#pragma once

#include "tdcr/bvp/newton_solver.hpp"
#include "tdcr/core/solution.hpp"

namespace tdcr::detail {

inline void copy_newton_result(const bvp::NewtonResult& r, SolverSummary& s) {
  s.termination = r.termination;
  s.message = r.message;
  s.solver_flag = r.flag;
  s.iterations += r.iterations;
  s.residual_evaluations += r.residual_evaluations;
  s.jacobian_evaluations += r.jacobian_evaluations;
  s.residual_norm = r.residual_norm;
  s.physical_residual = r.physical_residual;
  s.linear_solver = r.linear_solver;
}

// The work counts of `from` (another solve on the way to the same answer) added to `to`.
inline void add_work(const SolverSummary& from, SolverSummary& to) {
  to.iterations += from.iterations;
  to.residual_evaluations += from.residual_evaluations;
  to.jacobian_evaluations += from.jacobian_evaluations;
  to.continuation_steps += from.continuation_steps;
}

}  // namespace tdcr::detail
