/// @file dense_linear_solver.cpp
/// @brief The SUNLinearSolvers of dense_linear_solver.hpp.
#include "dense_linear_solver.hpp"

#include <nvector/nvector_serial.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <Eigen/LU>
#include <memory>
#include <new>
#include <utility>

namespace tdcr::bvp::detail {

namespace {

// Up to this size the LU is factored unblocked in place (the lumped models' cold solves at a few
// subsegments, single shooting): Eigen's blocked LU (from 17 on) spends more in its blocking and
// matrix-product set-up than in the arithmetic there. Same operations as Eigen's unblocked LU
// (which Eigen itself uses up to 16: identical factors there).
constexpr Eigen::Index kUnblockedUpTo = 48;

struct DenseSolver {
  Eigen::PartialPivLU<Eigen::MatrixXd> lu;
  Eigen::MatrixXd small;             // unblocked factors (n <= kUnblockedUpTo)
  Eigen::VectorXi small_pivot;       // row exchanged with row k at step k
  Eigen::Index n = 0;
  bool factored = false;
  int last_flag = SUNLS_SUCCESS;

  int setup(SUNMatrix A) {
    factored = false;
    if (SUNMatGetID(A) != SUNMATRIX_DENSE || SM_ROWS_D(A) != SM_COLUMNS_D(A)) return SUNLS_ILL_INPUT;
    n = SM_COLUMNS_D(A);
    try {
      // Column-major and contiguous like Eigen's default; the LU memory is reused for equal n.
      const Eigen::Map<const Eigen::MatrixXd> M(SM_DATA_D(A), n, n);
      if (n <= kUnblockedUpTo) return factor_small(M);
      lu.compute(M);
    } catch (const std::bad_alloc&) {
      return SUNLS_MEM_FAIL;
    }
    const auto& U = lu.matrixLU();
    for (Eigen::Index k = 0; k < n; ++k)
      if (U(k, k) == 0.0) return static_cast<int>(k + 1);
    factored = true;
    return SUNLS_SUCCESS;
  }

  // Partial pivoting, right-looking, as Eigen's partial_lu_impl::unblocked_lu.
  int factor_small(const Eigen::Map<const Eigen::MatrixXd>& M) {
    small = M;
    small_pivot.resize(n);
    for (Eigen::Index k = 0; k < n; ++k) {
      const Eigen::Index rrows = n - k - 1;
      Eigen::Index p;
      small.col(k).tail(n - k).cwiseAbs().maxCoeff(&p);
      p += k;
      small_pivot[k] = static_cast<int>(p);
      if (small(p, k) == 0.0) return static_cast<int>(k + 1);
      if (p != k) small.row(k).swap(small.row(p));
      if (rrows > 0) {
        small.col(k).tail(rrows) /= small(k, k);
        small.bottomRightCorner(rrows, rrows).noalias() -= small.col(k).tail(rrows) * small.row(k).tail(rrows);
      }
    }
    factored = true;
    return SUNLS_SUCCESS;
  }

  int solve(double* b, double* x) {
    if (!factored) return SUNLS_MEM_NULL;
    Eigen::Map<Eigen::VectorXd> xv(x, n);
    if (n > kUnblockedUpTo) {
      xv = lu.solve(Eigen::Map<const Eigen::VectorXd>(b, n));
      return SUNLS_SUCCESS;
    }
    if (x != b) xv = Eigen::Map<const Eigen::VectorXd>(b, n);
    for (Eigen::Index k = 0; k < n; ++k)
      if (small_pivot[k] != k) std::swap(xv[k], xv[small_pivot[k]]);
    small.triangularView<Eigen::UnitLower>().solveInPlace(xv);
    small.triangularView<Eigen::Upper>().solveInPlace(xv);
    return SUNLS_SUCCESS;
  }
};

struct StepSolver {
  int (*step)(double*, double*, void*);
  void* data;
  int last_flag = SUNLS_SUCCESS;

  int setup(SUNMatrix) { return SUNLS_SUCCESS; }
  int solve(double* b, double* x) { return step(b, x, data) == 0 ? SUNLS_SUCCESS : SUNLS_PACKAGE_FAIL_REC; }
};

// The generic SUNDIALS operations over a content object C with setup(A), solve(b, x), last_flag.
template <class C>
C& content(SUNLinearSolver S) {
  return *static_cast<C*>(S->content);
}

template <class C>
SUNLinearSolver make_solver(SUNContext ctx, std::unique_ptr<C> c) {
  SUNLinearSolver S = SUNLinSolNewEmpty(ctx);
  if (!S) throw std::bad_alloc();
  S->content = c.release();
  S->ops->gettype = [](SUNLinearSolver) { return SUNLINEARSOLVER_DIRECT; };
  S->ops->getid = [](SUNLinearSolver) { return SUNLINEARSOLVER_CUSTOM; };
  S->ops->initialize = [](SUNLinearSolver) { return static_cast<int>(SUNLS_SUCCESS); };
  S->ops->setup = [](SUNLinearSolver s, SUNMatrix A) { return content<C>(s).last_flag = content<C>(s).setup(A); };
  S->ops->solve = [](SUNLinearSolver s, SUNMatrix, N_Vector x, N_Vector b, realtype) {
    return content<C>(s).last_flag = content<C>(s).solve(N_VGetArrayPointer(b), N_VGetArrayPointer(x));
  };
  S->ops->lastflag = [](SUNLinearSolver s) { return static_cast<sunindextype>(content<C>(s).last_flag); };
  S->ops->free = [](SUNLinearSolver s) {
    if (!s) return static_cast<int>(SUNLS_SUCCESS);
    delete static_cast<C*>(s->content);
    s->content = nullptr;
    SUNLinSolFreeEmpty(s);
    return static_cast<int>(SUNLS_SUCCESS);
  };
  return S;
}

}  // namespace

SUNLinearSolver make_dense_linear_solver(SUNContext ctx) {
  return make_solver(ctx, std::make_unique<DenseSolver>());
}

SUNLinearSolver make_system_step_solver(SUNContext ctx, int (*solve)(double*, double*, void*), void* data) {
  return make_solver(ctx, std::make_unique<StepSolver>(StepSolver{solve, data}));
}

}  // namespace tdcr::bvp::detail
