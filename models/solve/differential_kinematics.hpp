// Private to models/: differential kinematics of a converged answer by the implicit function
// theorem (docs/models.md, "Differential kinematics").
#pragma once

#include "solve/rebind.hpp"

namespace tdcr::detail {

/// Fills solution.tip_jacobian (6 x m, d tip pose / d Actuation::values) and
/// solution.tip_compliance (6 x 6, d tip pose / d tip wrench) at the converged unknowns x of the
/// problem bound to `input` (system parameter 1). For a system F(x; v) = 0:
/// dx/dv = -F_x^{-1} F_v, F_x analytic or by finite differences, F_v by central differences of
/// the residual at x with the input perturbed; then the tip's total derivative is a central
/// difference of tip_pose() along (dx/dv, 1). No full solve. A closed-form model (no system)
/// gets central differences of its answer with respect to the actuation values only. A
/// perturbation that adds unknowns (CCsub, PRB: a load on unloaded distal subsegments) is
/// linearised in the larger system, at the answer mapped there by ModelProblem::warm_guess
/// (checked to solve it to 10 `tolerance`). Leaves both empty if an evaluation fails; rebinds
/// `input` before returning.
void differential_kinematics(const Rebind& rebind, const ModelInput& input, double force_scale,
                             double moment_scale, double tolerance, const Eigen::VectorXd& x, Solution& solution);

}  // namespace tdcr::detail
