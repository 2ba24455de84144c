/// @file continuation.hpp
/// @brief Load continuation: the fallback when a direct solve fails.
///
/// Hard cases (tip angles beyond 180 deg, soft backbones, strong transverse tip forces) defeat
/// Newton's method from the straight initial guess. Continuation scales the actuation and every
/// external load (tip force and moment, gravity) by a factor lambda and raises lambda from 0 to 1
/// in adaptive steps, each warm-started from the last converged step: the step grows after a
/// success and is halved after a failure. The total work is bounded by
/// SolverOptions::max_continuation_steps solves.
#pragma once

#include "tdcr/models/static_model.hpp"

namespace tdcr {

/// @brief The scene with its actuation values and external loads scaled by `lambda`.
Scene scale_loads(const Scene& scene, double lambda);

/// @brief Solve `model`; if the direct solve fails and the scene's solver options enable
/// continuation, solve again by load continuation. The returned summary counts the iterations of
/// every step and sets continuation_steps (0 when the direct solve succeeded); a continuation
/// that cannot reach full load returns the failure, with the load fraction it reached.
Solution solve_with_continuation(const StaticModel& model, ModelWorkspace& workspace,
                                 const Solution* warm_start = nullptr);

}  // namespace tdcr
