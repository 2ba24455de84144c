// Private to models/: a solve's SolverOptions (core, the scene file's `solver`) as the settings of
// the numerics under it (bvp). bvp knows nothing of scenes or models, so the models layer decides
// which of its options each bvp component sees; every call into bvp takes its settings from here.
#pragma once

#include "tdcr/bvp/arclength.hpp"
#include "tdcr/bvp/continuation.hpp"
#include "tdcr/bvp/integrator.hpp"
#include "tdcr/bvp/newton_solver.hpp"
#include "tdcr/core/solver_options.hpp"

namespace tdcr::detail {

/// The linear solver inside Newton, as bvp names it.
bvp::LinearSolverKind linear_solver_kind(LinearSolverKind kind);

/// Newton's settings: function_tolerance, step_tolerance, max_iterations and linear_solver; the
/// KINSOL details keep bvp's defaults (the problems adjust them, ModelProblem::adjust).
bvp::NewtonOptions newton_options(const SolverOptions& options);

/// Natural-parameter continuation: bvp's step control, at most max_continuation_steps solves.
bvp::ContinuationOptions continuation_options(const SolverOptions& options);

/// A loading path: bvp's step control and events, at most max_continuation_steps corrector
/// solves; without reuse_jacobian the correctors never freeze their Jacobian (no Jacobian
/// history may shape the answer).
bvp::ArclengthOptions arclength_options(const SolverOptions& options);

/// The Cosserat rod integrator: CVODE with its tolerances, or RK4 on the mesh of rk4_steps and
/// rk4_max_step for both RK4 integrators (the accuracy-driven one hands each of its solves a
/// fixed mesh through these two settings).
bvp::IntegratorOptions integrator_options(const SolverOptions& options);

}  // namespace tdcr::detail
