// Private to models/: the load continuation every static model falls back on when its direct
// solve fails (scene.solver.continuation). One mechanism, bvp::continuation(); this only maps
// its result into the model's SolverSummary.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "tdcr/bvp/arclength.hpp"
#include "tdcr/bvp/continuation.hpp"
#include "tdcr/bvp/newton_solver.hpp"
#include "tdcr/core/solution.hpp"
#include "tdcr/core/solver_options.hpp"

namespace tdcr::detail {

/// @brief Load continuation: the system's parameter is the load factor (every tension, the tip
/// wrench and gravity scale with it), raised from 0 to 1 by bvp::continuation().
///
/// Used after a failed direct solve, and by models that load a robot from rest on purpose (VC's
/// multiple shooting under large loads follows the branch connected to the unloaded robot).
///
/// @param x In: the exact solution of the unloaded system (load factor 0). Out: the solution at
///        the load factor reached (1 on success).
/// @param sum The summary so far. Work counters are added to it, continuation_steps too; on
///        success the termination, flag and residual of the final Newton solve are copied and the
///        message says that continuation was used and why; on failure the termination is that of
///        the last failed step and the message gives the load fraction reached (the returned shape
///        is the equilibrium at that fraction). Never converged unless the full load converged.
/// @param first_step First load step (0: SolverOptions' default).
/// @param purpose Why continuation runs, for the message; empty: "direct solve failed: <the
///        message in sum>".
bvp::ContinuationResult continue_loads(bvp::NewtonSolver& newton, bvp::ParameterizedSystem& system,
                                       Eigen::VectorXd& x, const bvp::NewtonOptions& newton_options,
                                       const SolverOptions& options, SolverSummary& sum, double first_step = 0.0,
                                       const std::string& purpose = "");

class ModelProblem;

/// @brief The answer to a loaded scene (docs/models.md): follow the loading path from the
/// unloaded straight robot (load factor 0) to the full input (1) by pseudo-arclength
/// continuation (bvp::arclength_continuation, FoldAction::Snap). Where the path meets a fold
/// before full load the robot snaps: the solver lands on the branch beyond and goes on.
///
/// @param x Out: the solution at the load factor reached (1 on success); starts from
///        P.rest_state().
/// @param sum Work counters and continuation_steps are added; termination and message set as
///        by continue_loads() (the message names the snaps, with load fraction and tip jump).
/// @param events Out: the folds, bifurcations and snaps of the path (tip jump from the tip
///        positions of ModelProblem::tip_position()).
/// @param first_step First step (0: the arclength default), in scaled arclength.
/// @param purpose Why the path is followed, for the message.
bvp::ArclengthResult follow_loading_path(ModelProblem& P, bvp::ParameterizedSystem& system, Eigen::VectorXd& x,
                                         const bvp::NewtonOptions& newton_options, const SolverOptions& options,
                                         SolverSummary& sum, std::vector<PathEvent>& events, double first_step,
                                         const std::string& purpose);

}  // namespace tdcr::detail
