// Private to models/: the RK4 mesh of VC's and VCref's stability tests. A verdict does not need
// the answer's accuracy: the tests' shots across each disk interval (VC 9, VCref 12) are taken on
// a coarse mesh, which makes them 4 to 8 times cheaper on the paper robot (docs/models.md,
// "Stability", measured there with the verdicts it keeps).
#pragma once

#include <algorithm>
#include <memory>

#include "tdcr/bvp/integrator.hpp"
#include "tdcr/core/solver_options.hpp"

namespace tdcr::detail {

/// Least RK4 steps per disk interval of a stability test.
constexpr int kStabilityRk4Steps = 1;
/// Longest RK4 step of a stability test (m).
constexpr double kStabilityRk4MaxStep = 8e-3;

/// The integrator of the stability test of a solve with `options`: with RK4 one on the coarser of
/// the solve's mesh and (kStabilityRk4Steps, kStabilityRk4MaxStep) in each setting (`integrator`
/// made, or its mesh set, only when it changes: no allocation once warm); with CVODE none (reset:
/// the test integrates with the solve's CVODE, the reference integrator).
inline void update_stability_integrator(const SolverOptions& options, std::unique_ptr<bvp::Rk4Integrator>& integrator) {
  if (options.integrator != IntegratorKind::FixedStepRK4) {
    integrator.reset();
    return;
  }
  const int steps = std::min(options.rk4_steps, kStabilityRk4Steps);
  const double max_step = std::max(options.rk4_max_step, kStabilityRk4MaxStep);
  if (!integrator)
    integrator = std::make_unique<bvp::Rk4Integrator>(steps, max_step);
  else if (integrator->steps() != steps || integrator->max_step() != max_step)
    integrator->set_mesh(steps, max_step);
}

}  // namespace tdcr::detail
