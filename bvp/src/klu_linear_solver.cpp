/// @file klu_linear_solver.cpp
/// @brief The KLU SUNLinearSolver of klu_linear_solver.hpp: the generic SUNDIALS operations
/// over a C++ content object.
#include "klu_linear_solver.hpp"

#include <klu.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <algorithm>
#include <new>
#include <type_traits>
#include <vector>

namespace tdcr::bvp::detail {

namespace {

static_assert(std::is_same<sunindextype, SuiteSparse_long>::value,
              "SUNDIALS' index type must be KLU's long index type (klu_l_*)");

class KluSolver {
 public:
  KluSolver() {
    klu_l_defaults(&common_);
    // Fill-reducing ordering of each BTF block: AMD on A + A^T (KLU's default). It also gives
    // KLU a fill estimate to size the LU memory by; COLAMD (SUNLinSol_KLU's choice) does not, and
    // KLU then reserves 10 nnz(A), several times what the shooting Jacobians need.
    common_.ordering = 0;
  }
  ~KluSolver() {
    if (numeric_) klu_l_free_numeric(&numeric_, &common_);
    if (symbolic_) klu_l_free_symbolic(&symbolic_, &common_);
  }
  KluSolver(const KluSolver&) = delete;
  KluSolver& operator=(const KluSolver&) = delete;

  int setup(SUNMatrix A) {
    if (SUNMatGetID(A) != SUNMATRIX_SPARSE || SM_SPARSETYPE_S(A) != CSC_MAT ||
        SM_ROWS_S(A) != SM_COLUMNS_S(A))
      return last_flag_ = SUNLS_ILL_INPUT;
    const sunindextype n = SM_COLUMNS_S(A);
    sunindextype* colptr = SM_INDEXPTRS_S(A);
    sunindextype* rowval = SM_INDEXVALS_S(A);
    double* values = SM_DATA_S(A);

    if (!symbolic_ || !same_pattern(n, colptr, rowval)) {
      if (numeric_) klu_l_free_numeric(&numeric_, &common_);
      if (symbolic_) klu_l_free_symbolic(&symbolic_, &common_);
      colptr_.assign(colptr, colptr + n + 1);
      rowval_.assign(rowval, rowval + colptr[n]);
      symbolic_ = klu_l_analyze(n, colptr, rowval, &common_);
      if (!symbolic_) {
        colptr_.clear();
        return last_flag_ = SUNLS_PACKAGE_FAIL_UNREC;
      }
      ++stats_.symbolic_analyses;
    }

    if (numeric_) {
      if (klu_l_refactor(colptr, rowval, values, symbolic_, numeric_, &common_) &&
          klu_l_rgrowth(colptr, rowval, values, symbolic_, numeric_, &common_) &&
          common_.rgrowth >= kRefactorGrowthRatio * reference_rgrowth_) {
        ++stats_.refactorizations;
        return last_flag_ = SUNLS_SUCCESS;
      }
      // Failed (e.g. a zero pivot in the reused order) or too much growth: pivot afresh.
      ++stats_.rejected_refactorizations;
      klu_l_free_numeric(&numeric_, &common_);
    }
    numeric_ = klu_l_factor(colptr, rowval, values, symbolic_, &common_);
    if (!numeric_)
      return last_flag_ = common_.status == KLU_SINGULAR ? SUNLS_LUFACT_FAIL
                                                         : SUNLS_PACKAGE_FAIL_UNREC;
    ++stats_.factorizations;
    reference_rgrowth_ = klu_l_rgrowth(colptr, rowval, values, symbolic_, numeric_, &common_)
                             ? common_.rgrowth
                             : 0.0;
    return last_flag_ = SUNLS_SUCCESS;
  }

  int solve(N_Vector x, N_Vector b) {
    if (!numeric_) return last_flag_ = SUNLS_MEM_NULL;
    N_VScale(1.0, b, x);
    if (!klu_l_solve(symbolic_, numeric_, symbolic_->n, 1, N_VGetArrayPointer(x), &common_))
      return last_flag_ = SUNLS_PACKAGE_FAIL_REC;
    return last_flag_ = SUNLS_SUCCESS;
  }

  int last_flag() const { return last_flag_; }
  const SparseLuStatistics& statistics() const { return stats_; }
  long integer_words() const { return static_cast<long>(colptr_.size() + rowval_.size()); }
  long real_words() const { return static_cast<long>(common_.memusage / sizeof(double)); }

 private:
  bool same_pattern(sunindextype n, const sunindextype* colptr,
                    const sunindextype* rowval) const {
    return static_cast<sunindextype>(colptr_.size()) == n + 1 &&
           std::equal(colptr_.begin(), colptr_.end(), colptr) &&
           std::equal(rowval_.begin(), rowval_.end(), rowval);
  }

  klu_l_common common_{};
  klu_l_symbolic* symbolic_ = nullptr;
  klu_l_numeric* numeric_ = nullptr;
  std::vector<sunindextype> colptr_, rowval_;  // the analysed pattern
  double reference_rgrowth_ = 0.0;             // of the last pivoting factorisation
  int last_flag_ = SUNLS_SUCCESS;
  SparseLuStatistics stats_;
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

SUNLinearSolver make_klu_linear_solver(SUNContext ctx) {
  SUNLinearSolver S = SUNLinSolNewEmpty(ctx);
  if (!S) throw std::bad_alloc();
  try {
    S->content = new KluSolver();
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

void add_klu_statistics(SUNLinearSolver solver, SparseLuStatistics& total) {
  const SparseLuStatistics& s = content(solver).statistics();
  total.symbolic_analyses += s.symbolic_analyses;
  total.factorizations += s.factorizations;
  total.refactorizations += s.refactorizations;
  total.rejected_refactorizations += s.rejected_refactorizations;
}

}  // namespace tdcr::bvp::detail
