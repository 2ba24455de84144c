// Private to models/: the loading path from rest every static model follows where a direct
// solve is not the answer or fails (scene.solver.continuation): bvp::arclength_continuation()
// with snaps, its result mapped into the model's SolverSummary and path events.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "tdcr/bvp/arclength.hpp"
#include "tdcr/bvp/newton_solver.hpp"
#include "tdcr/core/scene.hpp"
#include "tdcr/core/solution.hpp"
#include "tdcr/core/solver_options.hpp"

#include "solve/rebind.hpp"
#include "tdcr/models/model_problem.hpp"

namespace tdcr::detail {

/// @brief The answer to a loaded scene (docs/models.md): follow the loading path from the
/// unloaded straight robot (load factor 0) to the full input (1) by pseudo-arclength
/// continuation (bvp::arclength_continuation, FoldAction::Snap). Where the path meets a fold
/// before full load the robot snaps: the solver lands on the branch beyond and goes on.
///
/// @param x Out: the solution at the load factor reached (1 on success); starts from
///        P.rest_state().
/// @param sum Work counters and continuation_steps are added; termination and message set (on
///        failure: the load fraction reached; on success: the snaps, with load fraction and tip
///        jump). Never converged unless the full load converged.
/// @param events Out: the folds, bifurcations and snaps of the path (tip jump from the tip
///        positions of ModelProblem::tip_position()).
/// @param first_step First step (0: the arclength default), in scaled arclength.
/// @param purpose Why the path is followed, for the message.
/// @param routing The robot's tendons: a fold where a tensioned tendon is at its geometric limit
///        (curvature x offset >= physics::kTendonLimitWarn) is not snapped; the path stops there
///        and the driver names the actuation infeasible.
bvp::ArclengthResult follow_loading_path(ModelProblem& P, const TendonRouting& routing,
                                         bvp::ParameterizedSystem& system, Eigen::VectorXd& x,
                                         const bvp::NewtonOptions& newton_options, const SolverOptions& options,
                                         SolverSummary& sum, std::vector<PathEvent>& events, double first_step,
                                         const std::string& purpose);

/// @brief A warm start's path (docs/models.md): from the input of the previous Solution
/// (`from`: its tensions and loads) to `to` in steps of the input fraction t (inputs
/// interpolated linearly), each a warm direct solve from the last equilibrium; a failed step is
/// halved, down to 1/64 of the way. On return the problem is bound to `to` again.
///
/// @param x In: the warm guess at `to` (the previous Solution's unknowns); out: the solution at
///        `to` on success (else unchanged).
/// @return True if every step converged; sum gets the work counters and the message (on
///         failure: the fraction of the path reached and the last Newton message).
bool follow_input_path(const Rebind& rebind, const ModelInput& from, const ModelInput& to, const Solution& previous,
                       const bvp::NewtonOptions& newton_options, Eigen::VectorXd& x, SolverSummary& sum);

}  // namespace tdcr::detail
