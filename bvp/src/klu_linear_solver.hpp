/// @file klu_linear_solver.hpp
/// @brief (private) A SUNDIALS linear solver on KLU that keeps its symbolic analysis and LU
/// memory across KINSol() calls and refactorises with the previous pivot order when safe.
///
/// Why not SUNLinSol_KLU: its initialize() (which KINSOL calls at the start of every KINSol())
/// forces the next setup to free and redo the symbolic analysis and a pivoting factorisation,
/// so every Newton solve re-analysed an unchanged pattern and re-allocated the LU memory. Its
/// refactor check (crude rcond only) also turns a zero pivot in the reused order into a fatal
/// setup failure instead of a fresh factorisation. This solver is bvp::SparseLu (sparse_lu.hpp:
/// analysis once per pattern (the last two kept), refactorisation with a pivot-growth check) behind the
/// SUNLinearSolver interface.
#pragma once

#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>
#include <sundials/sundials_matrix.h>

#include "tdcr/bvp/newton_solver.hpp"
#include "tdcr/bvp/sparse_lu.hpp"

namespace tdcr::bvp::detail {

/// @brief Creates the solver for CSC SUNSparseMatrix systems on `lu`, which it borrows: `lu`
/// must outlive it, and keeps its analysed patterns after it is freed (SUNLinSolFree), so a
/// Newton workspace that rebuilds its SUNDIALS objects for another system size re-analyses
/// nothing it has seen recently. Throws std::bad_alloc.
SUNLinearSolver make_klu_linear_solver(SUNContext ctx, SparseLu& lu);

}  // namespace tdcr::bvp::detail
