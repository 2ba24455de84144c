/// @file dense_linear_solver.hpp
/// @brief (private) A SUNDIALS linear solver for SUNDenseMatrix systems on Eigen's blocked
/// PartialPivLU.
///
/// Why not SUNLinSol_Dense: its LU (SUNDlsMat_denseGETRF) is unblocked and not vectorised, and
/// dominates the solve of every dense model from about 50 unknowns on (41 % of a CCsub solve
/// with 60 unknowns). Same contract: partial pivoting, an exactly zero pivot is a recoverable
/// setup failure (the 1-based column, as SUNLinSol_Dense reports it), LU memory kept across
/// KINSol() calls.
#pragma once

#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>

namespace tdcr::bvp::detail {

/// @brief Creates the solver (throws std::bad_alloc). Free it with SUNLinSolFree.
SUNLinearSolver make_dense_linear_solver(SUNContext ctx);

/// @brief A solver for systems that compute their Newton steps themselves
/// (ResidualSystem::has_newton_step): the Jacobian callback linearises, setup does nothing and
/// solve calls `solve(b, x, data)` (returns 0, or a positive value for a recoverable failure).
/// The matrix it is used with is a placeholder. Throws std::bad_alloc.
SUNLinearSolver make_system_step_solver(SUNContext ctx, int (*solve)(double* b, double* x, void* data), void* data);

}  // namespace tdcr::bvp::detail
