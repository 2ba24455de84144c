/// @file newton_frozen_jacobian.hpp
/// @brief Private to bvp: NewtonOptions::freeze_jacobian_below, exact Newton down to the
/// freezing threshold and modified Newton from its last Jacobian below it.
#pragma once

#include <Eigen/Core>

#include "tdcr/bvp/newton_solver.hpp"

namespace tdcr::bvp::detail {

/// Solves system(x) = 0 as NewtonSolver::solve() does with options.freeze_jacobian_below > 0
/// and reuse_jacobian false: a sequence of plain solves (freeze_jacobian_below 0) on `solver`,
/// their work summed into the result.
NewtonResult solve_exact_then_frozen(NewtonSolver& solver, ResidualSystem& system, Eigen::VectorXd& x,
                                     const NewtonOptions& options);

}  // namespace tdcr::bvp::detail
