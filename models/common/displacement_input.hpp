// Private to models/: displacement input for the static models (CCsub, PRB, VC, VCref) by an
// outer semismooth Newton over the tensions of the displacement-driven tendons, each residual
// evaluation a warm-started tension solve (docs/models.md, "Displacement input").
#pragma once

#include "tdcr/core/scene.hpp"
#include "tdcr/core/solution.hpp"
#include "tdcr/core/solver_options.hpp"

namespace tdcr {
class StaticModel;
class ModelWorkspace;
}  // namespace tdcr

namespace tdcr::detail {

/// True if `model` solves `input` with the outer solve: some tendon is given by displacement
/// and the model has statics (ModelCapabilities::displacement_statics; CC maps displacements
/// kinematically instead).
bool needs_displacement_solve(const StaticModel& model, const ModelInput& input);

/// The answer to `input` with the tensions of its displacement-driven tendons as unknowns:
/// phi_k = min(T_k / T_s, (d_k(T) + T_k / c_k - delta_k) / r_k) = 0, d_k the pull of the
/// tendon's path, c_k = EA_k / L_k of an elastic tendon (TendonSpec::stiffness; infinite:
/// inextensible). A tendon cannot push: slack (T_k = 0) when its path at T_k = 0 pulls more than
/// commanded; an elastic tendon's T_k = c_k max(0, delta_k - d_k) in complementarity form.
/// Converged only if the last tension solve converged and max |phi_k| <=
/// options.function_tolerance. A warm start's tensions start the iteration.
Solution solve_displacement_input(const StaticModel& model, ModelWorkspace& workspace, const ModelInput& input,
                                  const SolverOptions& options, const Solution* warm_start);

}  // namespace tdcr::detail
