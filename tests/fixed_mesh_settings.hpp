// The solver settings the older suites' tolerances and iteration counts were measured with: RK4
// on the fixed mesh (8 steps per disk interval, h <= 1 mm) and Newton's residual tolerance 1e-10,
// the defaults before the accuracy-driven mesh and the tip tolerance (1e-8 m on the paper robot)
// became them. Tests that assert agreement to 1e-9 m or below, warm-start iteration counts, or a
// path's events on a given mesh ask for these; tests of the defaults do not.
#pragma once

#include "tdcr/core/solver_options.hpp"

namespace tdcr::test {

inline SolverOptions fixed_mesh_settings(SolverOptions o = SolverOptions()) {
  if (o.integrator == IntegratorKind::AccuracyDrivenRK4) o.integrator = IntegratorKind::FixedStepRK4;
  if (o.function_tolerance == 0.0) o.function_tolerance = 1e-10;
  return o;
}

}  // namespace tdcr::test
