/// @file klu_linear_solver.cpp
/// @brief The KLU SUNLinearSolver of klu_linear_solver.hpp: the generic SUNDIALS operations
/// over a C++ content object.
#include "klu_linear_solver.hpp"

#include <sunmatrix/sunmatrix_sparse.h>

#include <new>
#include <type_traits>

namespace tdcr::bvp::detail {

namespace {

static_assert(std::is_same<sunindextype, long>::value,
              "SUNDIALS' index type must be SparseLu's (KLU's long index type)");

// The SUNDIALS adapter: SUNMatrix in, SparseLu does the work.
class KluSolver {
 public:
  explicit KluSolver(SparseLu& lu) : lu_(lu) {}
  int setup(SUNMatrix A) {
    if (SUNMatGetID(A) != SUNMATRIX_SPARSE || SM_SPARSETYPE_S(A) != CSC_MAT ||
        SM_ROWS_S(A) != SM_COLUMNS_S(A))
      return last_flag_ = SUNLS_ILL_INPUT;
    switch (lu_.factorize(SM_COLUMNS_S(A), SM_INDEXPTRS_S(A), SM_INDEXVALS_S(A), SM_DATA_S(A))) {
      case SparseLu::Status::Success: return last_flag_ = SUNLS_SUCCESS;
      case SparseLu::Status::Singular: return last_flag_ = SUNLS_LUFACT_FAIL;
      case SparseLu::Status::Failed: break;
    }
    return last_flag_ = SUNLS_PACKAGE_FAIL_UNREC;
  }

  int solve(N_Vector x, N_Vector b) {
    if (!lu_.factorized()) return last_flag_ = SUNLS_MEM_NULL;
    N_VScale(1.0, b, x);
    return last_flag_ = lu_.solve(N_VGetArrayPointer(x)) ? SUNLS_SUCCESS : SUNLS_PACKAGE_FAIL_REC;
  }

  int last_flag() const { return last_flag_; }
  long integer_words() const { return lu_.integer_words(); }
  long real_words() const { return lu_.real_words(); }

 private:
  SparseLu& lu_;  // the Newton workspace's: it outlives this solver and its analyses are kept
  int last_flag_ = SUNLS_SUCCESS;
};

KluSolver& content(SUNLinearSolver S) { return *static_cast<KluSolver*>(S->content); }

SUNLinearSolver_Type get_type(SUNLinearSolver) { return SUNLINEARSOLVER_DIRECT; }
SUNLinearSolver_ID get_id(SUNLinearSolver) { return SUNLINEARSOLVER_CUSTOM; }

// KINSOL calls this at the start of every KINSol(): nothing to reset, which is the point.
int initialize(SUNLinearSolver) { return SUNLS_SUCCESS; }

int setup(SUNLinearSolver S, SUNMatrix A) {
  try {
    return content(S).setup(A);
  } catch (const std::bad_alloc&) {  // the pattern copy
    return SUNLS_MEM_FAIL;
  }
}

int solve(SUNLinearSolver S, SUNMatrix, N_Vector x, N_Vector b, realtype) {
  return content(S).solve(x, b);
}

sunindextype last_flag(SUNLinearSolver S) { return content(S).last_flag(); }

int space(SUNLinearSolver S, long* lenrw, long* leniw) {
  *lenrw = content(S).real_words();
  *leniw = content(S).integer_words();
  return SUNLS_SUCCESS;
}

int free_solver(SUNLinearSolver S) {
  if (!S) return SUNLS_SUCCESS;
  delete static_cast<KluSolver*>(S->content);
  S->content = nullptr;
  SUNLinSolFreeEmpty(S);
  return SUNLS_SUCCESS;
}

}  // namespace

SUNLinearSolver make_klu_linear_solver(SUNContext ctx, SparseLu& lu) {
  SUNLinearSolver S = SUNLinSolNewEmpty(ctx);
  if (!S) throw std::bad_alloc();
  try {
    S->content = new KluSolver(lu);
  } catch (...) {
    SUNLinSolFreeEmpty(S);
    throw;
  }
  S->ops->gettype = get_type;
  S->ops->getid = get_id;
  S->ops->initialize = initialize;
  S->ops->setup = setup;
  S->ops->solve = solve;
  S->ops->lastflag = last_flag;
  S->ops->space = space;
  S->ops->free = free_solver;
  return S;
}

}  // namespace tdcr::bvp::detail
