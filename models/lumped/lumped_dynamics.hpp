// Private to models/: the equations of motion of the lumped models CCsub and PRB
// (lumped_dynamics.cpp, docs/dynamics.md). The unknowns q (x_j of every subsegment) are the
// generalized coordinates; bodies are the disks, each carrying its own mass and half of the
// backbone of the two subsegments beside it (mass and rotary inertia, lumped at the disk).
//
//   M(q) q'' = Q(q, t) - D q' - b(q, q')
//
// M = sum over bodies of (m J_v^T J_v + J_w^T I J_w) (composite inertias, O(N^2 m^2));
// Q = -S(q) r(q): the model's own static residual r mapped by S so that its spring part is
// exactly the gradient of the springs' energy (so Q = 0 is the model's statics, and without
// loads Q is conservative); D = tau_bt K (the springs' stiffness); b the velocity-product
// (Coriolis, centrifugal, gyroscopic) forces and the air drag. The right-hand side solves for
// q'' by the articulated-body algorithm (O(N), no M); so do CVODE's Newton systems under tension
// and load input (with K's diagonal blocks), while under displacement input M is formed for them.
#pragma once

#include <memory>

#include <Eigen/Core>

#include "tdcr/models/dynamics.hpp"
#include "tdcr/models/lumped_model.hpp"

namespace tdcr::detail {

class LumpedBody;

/// The integrator of a lumped model (CVODE BDF on (q, q')).
std::unique_ptr<DynamicsIntegrator> make_lumped_dynamics(const LumpedModel& model, const LumpedBody& body,
                                                         const DynamicsSettings& settings, double dt,
                                                         const SolverOptions& solver);

/// Undamped natural frequencies (Hz, ascending) of the lumped model linearised about the shape
/// x (all N subsegments) at rest under `input`: the generalized eigenvalues of (K, M), K = -dQ/dq.
/// For tests (the Euler-Bernoulli limit) and docs/dynamics.md.
Eigen::VectorXd lumped_natural_frequencies(const LumpedModel& model, const LumpedBody& body, const Eigen::VectorXd& x,
                                           const ModelInput& input);

}  // namespace tdcr::detail
