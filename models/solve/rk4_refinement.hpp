// Private to models/solve: the mesh policies of the solve driver (solve_driver.cpp) for the
// models on an RK4 mesh (ModelCapabilities::rk4_mesh, VC and VCref): accuracy-driven RK4 and
// coarse loading paths (rk4_refinement.cpp).
#pragma once

#include <functional>
#include <string>

#include "tdcr/core/scene.hpp"
#include "tdcr/core/solution.hpp"
#include "tdcr/models/static_model.hpp"

namespace tdcr::detail {

// Runs a solve and leaves the workspace's warm-start history as it was before it.
using KeepHistory = std::function<Solution(const std::function<Solution()>&)>;

// One shot of unknowns x on the mesh of `options` at the bound input, no Newton step: false if it
// cannot be evaluated, else the scaled residual's max norm and the tip frame.
using ShotOnMesh =
    std::function<bool(const SolverOptions& options, const Eigen::VectorXd& x, double& scaled_residual, Frame& tip)>;

// The answer of accuracy-driven RK4 (IntegratorKind::AccuracyDrivenRK4) on the mesh whose
// Richardson estimate of the tip error meets options.tip_tolerance. `path`: a cold tension solve
// whose cold rule follows the loading path from rest; `guess_is_answer`: a cold solve whose
// guess solves the continuous equations (ColdStart::guess_is_answer); `last_options`: the options
// of the solve that returned the answer; `test`: whether the stability rule asks for the answer's
// test (not done here).
Solution solve_refined(const StaticModel& model, ModelWorkspace& workspace, const ModelInput& input,
                       const SolverOptions& options, const Solution* warm_start, bool path, bool guess_is_answer,
                       const KeepHistory& keep_history, const ShotOnMesh& shoot, SolverOptions& last_options,
                       bool& test);

// Whether a cold solve of VC or VCref on RK4 should follow its loading path on the coarse mesh:
// the path is the model's cold rule here (reason non-empty) and the requested mesh is finer.
bool wants_coarse_path(const StaticModel& model, const SolverOptions& options, const Solution* warm_start,
                       const std::string& reason);

// The loading path on the coarse mesh, then Newton on the requested mesh from its answer (a warm
// start at the same input: a direct solve). If either fails the result is not converged, with
// the reason in `failure`; the caller then follows the path on the requested mesh. Work counts
// are those of both solves, path events the coarse path's.
Solution solve_with_coarse_path(const StaticModel& model, ModelWorkspace& workspace, const ModelInput& input,
                                const SolverOptions& options, std::string& failure);

}  // namespace tdcr::detail
