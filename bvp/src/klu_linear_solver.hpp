/// @file klu_linear_solver.hpp
/// @brief (private) A SUNDIALS linear solver on KLU that keeps its symbolic analysis and LU
/// memory across KINSol() calls and refactorises with the previous pivot order when safe.
///
/// Why not SUNLinSol_KLU: its initialize() (which KINSOL calls at the start of every KINSol())
/// forces the next setup to free and redo the symbolic analysis and a pivoting factorisation,
/// so every Newton solve re-analysed an unchanged pattern and re-allocated the LU memory. Its
/// refactor check (crude rcond only) also turns a zero pivot in the reused order into a fatal
/// setup failure instead of a fresh factorisation. This solver:
///  - re-analyses only when the matrix's pattern differs from the analysed one;
///  - refactorises (klu_refactor) when a numeric factorisation exists, and accepts the result
///    only if it succeeded and its reciprocal pivot growth is at least kRefactorGrowthRatio
///    times that of the pivoting factorisation whose order it reuses; otherwise it factorises
///    afresh with partial pivoting (klu_factor).
#pragma once

#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>
#include <sundials/sundials_matrix.h>

#include "tdcr/bvp/newton_solver.hpp"

namespace tdcr::bvp::detail {

/// A refactorisation whose reciprocal pivot growth falls below this fraction of the reference
/// one (the last pivoting factorisation's) is redone with pivoting: it may lose at most about
/// two more digits than a fresh factorisation.
constexpr double kRefactorGrowthRatio = 1e-2;

/// @brief Creates the solver for CSC SUNSparseMatrix systems (throws std::bad_alloc).
/// Free it with SUNLinSolFree.
SUNLinearSolver make_klu_linear_solver(SUNContext ctx);

/// @brief Adds the work counters of a solver made by make_klu_linear_solver to total.
void add_klu_statistics(SUNLinearSolver solver, SparseLuStatistics& total);

}  // namespace tdcr::bvp::detail
