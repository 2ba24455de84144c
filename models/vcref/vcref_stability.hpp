// Private to models/vcref: the stability of a converged VCref equilibrium (vcref_stability.cpp).
#pragma once

#include "tdcr/bvp/integrator.hpp"
#include "tdcr/bvp/shooting.hpp"
#include "tdcr/core/solution.hpp"
#include "vcref/vcref_shooting.hpp"

namespace tdcr {

/// The reduced stiffness in the disk poses of the equilibrium whose interval starts are `nodes`
/// (the shooting trajectory at the solution, load factor 1); see vcref_stability.cpp.
Stability disk_pose_stability(const VcrefShooting& problem, bvp::Integrator& integrator,
                              const bvp::ShootingNodes& nodes);

}  // namespace tdcr
