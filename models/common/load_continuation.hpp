// Private to models/: the load continuation every static model falls back on when its direct
// solve fails (scene.solver.continuation). One mechanism, bvp::continuation(); this only maps
// its result into the model's SolverSummary.
#pragma once

#include <Eigen/Core>

#include "tdcr/bvp/continuation.hpp"
#include "tdcr/bvp/newton_solver.hpp"
#include "tdcr/core/solution.hpp"
#include "tdcr/core/solver_options.hpp"

namespace tdcr::detail {

/// @brief Load continuation after a failed direct solve: the system's parameter is the load
/// factor (every tension, the tip wrench and gravity scale with it), raised from 0 to 1.
///
/// @param x In: the exact solution of the unloaded system (load factor 0). Out: the solution at
///        the load factor reached (1 on success).
/// @param sum The summary of the failed direct solve. Work counters are added to it,
///        continuation_steps is set; on success the termination, flag and residual of the final
///        Newton solve are copied and the message says that continuation was used; on failure
///        the termination is that of the last failed step and the message gives the load
///        fraction reached (the returned shape is the equilibrium at that fraction) and the
///        direct solve's message. Never converged unless the full load converged.
bvp::ContinuationResult continue_loads(bvp::NewtonSolver& newton, bvp::ParameterizedSystem& system,
                                       Eigen::VectorXd& x, const bvp::NewtonOptions& newton_options,
                                       const SolverOptions& options, SolverSummary& sum);

}  // namespace tdcr::detail
