// Private to models/: copy a bvp::NewtonResult into a Solution's summary (one place for it).
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

}  // namespace tdcr::detail
