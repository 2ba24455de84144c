/// @file newton_solver.cpp
/// @brief KINSOL driver: workspace lifetime, callbacks, and one solve. The translation of
/// KINSOL's return flags is in newton_flags.cpp, the exact-then-frozen policy of
/// NewtonOptions::freeze_jacobian_below in newton_frozen_jacobian.cpp.
#include "tdcr/bvp/newton_solver.hpp"

#include <kinsol/kinsol.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <stdexcept>
#include <utility>

#include "dense_linear_solver.hpp"
#include "klu_linear_solver.hpp"
#include "newton_flags.hpp"
#include "newton_frozen_jacobian.hpp"
#include "tdcr/bvp/sparse_lu.hpp"
#include "tdcr/core/error.hpp"

namespace tdcr::bvp {

using detail::EvalFailure;
using detail::kinsol_flag_name;

struct NewtonSolver::Impl {
  // SUNDIALS objects, destroyed in reverse order of creation.
  SUNContext ctx = nullptr;
  N_Vector u = nullptr, uscale = nullptr, fscale = nullptr;
  SUNMatrix J = nullptr;
  SUNLinearSolver LS = nullptr;
  void* kin = nullptr;

  // What the objects were built for.
  int n = -1;
  bool sparse = false;
  bool stepper = false;  // the system's own Newton steps (ResidualSystem::has_newton_step)
  SparsityPattern pattern;     // copy of the system's pattern (empty if dense system)
  bool has_pattern = false;
  bool dense_fallback = false;  // pattern is SparsityPattern::dense(n): KLU without a pattern
  int rebuilds = 0;
  // KLU factorisations owned here, not by the SUNDIALS linear solver, so that they (their
  // analyses, LU memory and pivot orders) survive rebuilds for another system size.
  SparseLu lu;          // the KINSOL linear solver's
  SparseLu tangent_lu;  // NewtonSolver::tangent_lu()

  // Per-solve state, reached from the C callbacks through user_data.
  ResidualSystem* system = nullptr;
  FiniteDifferenceWorkspace fd;
  bool fd_groups = false;       // fd holds the column groups of pattern (computed on first use)
  std::vector<double> values;  // sparse Jacobian values when the linear solver is dense
  // The residual of KINSOL's last residual call and its point (x_last): where no Jacobian or
  // Newton-step call came after it (f_last_valid) and the returned point is x_last, that is the
  // residual at the returned point, and the system's state is the one a new evaluation there
  // would leave: the judgement after KINSOL takes it instead of evaluating it again.
  Eigen::VectorXd f_final, x_last;
  bool f_last_valid = false;
  int nfe = 0, nje = 0;
  // The system whose Jacobian the linear solver holds factored (NewtonOptions::reuse_jacobian).
  const ResidualSystem* factored = nullptr;
  EvalFailure last_failure = EvalFailure::None;
  EvalFailure jac_failure = EvalFailure::None;
  std::string kinsol_message;
  std::exception_ptr exception;

  Impl() {
    if (SUNContext_Create(nullptr, &ctx) != 0 || !ctx)
      throw std::runtime_error("NewtonSolver: SUNContext_Create failed");
  }
  ~Impl() {
    destroy();
    if (ctx) SUNContext_Free(&ctx);
  }

  void destroy() {
    if (kin) KINFree(&kin);
    if (LS) SUNLinSolFree(LS);
    if (J) SUNMatDestroy(J);
    if (fscale) N_VDestroy(fscale);
    if (uscale) N_VDestroy(uscale);
    if (u) N_VDestroy(u);
    kin = nullptr;
    LS = nullptr;
    J = nullptr;
    u = uscale = fscale = nullptr;
    n = -1;
  }

  SparseLuStatistics lu_statistics() const { return lu.statistics(); }

  /// Adopt a new Jacobian structure (nullptr: none) without rebuilding the SUNDIALS objects.
  void set_pattern(const SparsityPattern* p, bool dense) {
    factored = nullptr;
    has_pattern = p != nullptr;
    pattern = p ? *p : SparsityPattern();
    dense_fallback = dense;
    fd = FiniteDifferenceWorkspace();
    fd_groups = false;
  }

  void build(int size, bool use_klu, bool own_step, const SparsityPattern* p) {
    destroy();
    factored = nullptr;
    ++rebuilds;
    u = N_VNew_Serial(size, ctx);
    uscale = N_VNew_Serial(size, ctx);
    fscale = N_VNew_Serial(size, ctx);
    if (!u || !uscale || !fscale) throw std::runtime_error("NewtonSolver: N_VNew_Serial failed");
    if (own_step) {
      J = SUNDenseMatrix(1, 1, ctx);  // placeholder: no Jacobian is formed
      if (J) LS = detail::make_system_step_solver(ctx, &Impl::step_fn, this);
    } else if (use_klu) {
      J = SUNSparseMatrix(size, size, p->nnz(), CSC_MAT, ctx);
      if (J) LS = detail::make_klu_linear_solver(ctx, lu);
    } else {
      J = SUNDenseMatrix(size, size, ctx);
      if (J) LS = detail::make_dense_linear_solver(ctx);
    }
    if (!J || !LS) throw std::runtime_error("NewtonSolver: cannot create the linear solver");
    kin = KINCreate(ctx);
    if (!kin) throw std::runtime_error("NewtonSolver: KINCreate failed");
    int ret = KINSetErrHandlerFn(kin, &Impl::on_error, this);
    if (ret == KIN_SUCCESS) ret = KINSetInfoHandlerFn(kin, &Impl::on_info, this);
    if (ret == KIN_SUCCESS) ret = KINSetPrintLevel(kin, 0);
    if (ret == KIN_SUCCESS) ret = KINInit(kin, &Impl::residual_fn, u);
    if (ret == KIN_SUCCESS) ret = KINSetUserData(kin, this);
    if (ret == KIN_SUCCESS) ret = KINSetLinearSolver(kin, LS, J);
    if (ret == KIN_SUCCESS) ret = KINSetJacFn(kin, &Impl::jacobian_fn);
    if (ret != KIN_SUCCESS)
      throw std::runtime_error(std::string("NewtonSolver: KINSOL setup failed: ") +
                               kinsol_flag_name(ret) + " " + kinsol_message);
    n = size;
    sparse = use_klu;
    stepper = own_step;
  }

  // ---- C callbacks. They never let an exception cross KINSOL's C frames. ----

  static void on_error(int code, const char* module, const char* function, char* msg,
                       void* user) {
    auto* self = static_cast<Impl*>(user);
    std::string text = std::string(module ? module : "KINSOL") + "/" +
                       (function ? function : "?") + ": " + (msg ? msg : "");
    (void)code;
    // Keep the latest message only: KINSOL reports the final, most specific error last.
    self->kinsol_message = std::move(text);
  }

  static void on_info(const char*, const char*, char*, void*) {}

  static int residual_fn(N_Vector uu, N_Vector fval, void* user) {
    auto* self = static_cast<Impl*>(user);
    try {
      Eigen::Map<const Eigen::VectorXd> x(N_VGetArrayPointer(uu), self->n);
      Eigen::Map<Eigen::VectorXd> f(N_VGetArrayPointer(fval), self->n);
      ++self->nfe;
      self->f_last_valid = false;
      if (!self->system->residual(x, f)) {
        self->last_failure = EvalFailure::NotEvaluated;
        return 1;  // recoverable: KINSOL shortens the step
      }
      if (!f.allFinite()) {
        self->last_failure = EvalFailure::NonFinite;
        return 1;
      }
      self->x_last = x;  // sized at solve(): no allocation
      self->f_final = f;
      self->f_last_valid = true;
      return 0;
    } catch (...) {
      self->exception = std::current_exception();
      return -1;
    }
  }

  static int jacobian_fn(N_Vector uu, N_Vector fu, SUNMatrix Jm, void* user, N_Vector,
                         N_Vector) {
    auto* self = static_cast<Impl*>(user);
    try {
      ++self->nje;
      self->f_last_valid = false;  // finite differences or a setup may leave another state
      const EvalFailure r = self->fill_jacobian(uu, fu, Jm);
      if (r != EvalFailure::None) {
        self->jac_failure = r;
        return 1;
      }
      return 0;
    } catch (...) {
      self->exception = std::current_exception();
      return -1;
    }
  }

  static int step_fn(double* b, double* x, void* user) {
    auto* self = static_cast<Impl*>(user);
    self->f_last_valid = false;
    try {
      Eigen::Map<Eigen::VectorXd> d(x, self->n);
      d = Eigen::Map<const Eigen::VectorXd>(b, self->n);
      return self->system->solve_newton_step(d) && d.allFinite() ? 0 : 1;
    } catch (...) {
      self->exception = std::current_exception();
      return -1;
    }
  }

  EvalFailure fill_jacobian(N_Vector uu, N_Vector fu, SUNMatrix Jm) {
    Eigen::Map<const Eigen::VectorXd> x(N_VGetArrayPointer(uu), n);
    Eigen::Map<const Eigen::VectorXd> f(N_VGetArrayPointer(fu), n);
    ResidualSystem& sys = *system;
    if (stepper) return sys.setup_newton_step(x, f) ? EvalFailure::None : EvalFailure::NotEvaluated;
    const bool analytic = sys.has_jacobian();
    bool ok = false;
    if (sparse) {
      // KINSOL zeroes the matrix before this call, and SUNMatZero on a sparse matrix wipes the
      // index arrays too: restore the structure every time.
      sunindextype* colptr = SM_INDEXPTRS_S(Jm);
      sunindextype* rowval = SM_INDEXVALS_S(Jm);
      for (int j = 0; j <= n; ++j) colptr[j] = pattern.col_ptr[j];
      const int nnz = pattern.nnz();
      for (int k = 0; k < nnz; ++k) rowval[k] = pattern.row_idx[k];
      double* vals = SM_DATA_S(Jm);
      if (!analytic) prepare_fd_groups();
      ok = analytic ? sys.sparse_jacobian(x, f, vals)
                    : finite_difference_sparse_jacobian(sys, x, f, pattern, vals, &fd);
      if (ok)
        for (int k = 0; k < nnz; ++k)
          if (!std::isfinite(vals[k])) return EvalFailure::NonFinite;
    } else {
      // SUNDIALS' dense matrix is column-major and contiguous, like Eigen's default.
      Eigen::Map<Eigen::MatrixXd> Jd(SM_DATA_D(Jm), n, n);
      if (has_pattern) {
        // Structured system on a dense solver: still use grouped differences, then scatter.
        if (!analytic) prepare_fd_groups();
        ok = analytic ? sys.sparse_jacobian(x, f, values.data())
                      : finite_difference_sparse_jacobian(sys, x, f, pattern, values.data(), &fd);
        if (ok) {
          Jd.setZero();
          for (int j = 0; j < n; ++j)
            for (int k = pattern.col_ptr[j]; k < pattern.col_ptr[j + 1]; ++k)
              Jd(pattern.row_idx[k], j) = values[k];
        }
      } else {
        ok = analytic ? sys.jacobian(x, f, Jd) : finite_difference_jacobian(sys, x, f, Jd, &fd);
      }
      if (ok && !Jd.allFinite()) return EvalFailure::NonFinite;
    }
    // A finite-difference failure is a failed residual evaluation; treat an analytic one alike.
    if (!ok) return EvalFailure::NotEvaluated;
    return EvalFailure::None;
  }

  // Column grouping costs more than a small solve: only systems without an analytic Jacobian
  // need it, once per pattern.
  void prepare_fd_groups() {
    if (!fd_groups) fd.prepare(pattern);
    fd_groups = true;
  }
};

NewtonSolver::NewtonSolver() : impl_(std::make_unique<Impl>()) {}
NewtonSolver::~NewtonSolver() = default;
NewtonSolver::NewtonSolver(NewtonSolver&&) noexcept = default;
NewtonSolver& NewtonSolver::operator=(NewtonSolver&&) noexcept = default;

int NewtonSolver::rebuilds() const { return impl_->rebuilds; }

void NewtonSolver::forget_jacobian() { impl_->factored = nullptr; }

SparseLuStatistics NewtonSolver::sparse_lu_statistics() const { return impl_->lu_statistics(); }

SparseLu& NewtonSolver::tangent_lu() { return impl_->tangent_lu; }

NewtonResult NewtonSolver::solve(ResidualSystem& system, Eigen::VectorXd& x,
                                 const NewtonOptions& options) {
  options.validate();
  if (options.freeze_jacobian_below > 0.0 && !options.reuse_jacobian)
    return detail::solve_exact_then_frozen(*this, system, x, options);
  Impl& s = *impl_;
  const int n = system.size();
  if (n < 0) throw std::invalid_argument("NewtonSolver::solve: negative system size");
  if (x.size() != n)
    throw std::invalid_argument("NewtonSolver::solve: initial guess has size " +
                                std::to_string(x.size()) + ", system has " + std::to_string(n));
  const SparsityPattern* p = system.sparsity();
  // The pattern the solver holds was validated when it was taken: a repeated solve of the same
  // structure (a trajectory's warm steps) compares it instead of walking it again (5 % of a
  // VCref warm step).
  const bool known_pattern = p && impl_->has_pattern && *p == impl_->pattern;
  if (p && (p->rows != n || p->cols != n || (!known_pattern && !p->valid())))
    throw std::invalid_argument("NewtonSolver::solve: sparsity pattern is not a valid " +
                                std::to_string(n) + "x" + std::to_string(n) + " pattern");

  NewtonResult result;
  if (n == 0) {
    result.termination = TerminationType::Converged;
    result.message = "KIN_SUCCESS: empty system";
    result.linear_solver = "none";
    return result;
  }

  // Linear solver choice. KLU without a declared pattern uses a dense pattern: correct, just
  // not sparse.
  bool use_klu = false;
  const bool own_step = system.has_newton_step();
  if (!own_step) switch (options.linear_solver) {
    case LinearSolverKind::Dense: use_klu = false; break;
    case LinearSolverKind::SparseKLU: use_klu = true; break;
    case LinearSolverKind::Automatic: use_klu = p && n > options.dense_size_limit; break;
  }
  const bool dense_fallback = use_klu && !p;
  const bool same_size = s.n == n && s.sparse == use_klu && s.stepper == own_step;
  const bool reuse_dense = dense_fallback && same_size && s.dense_fallback;
  const SparsityPattern dense_pattern =
      dense_fallback && !reuse_dense ? SparsityPattern::dense(n) : SparsityPattern();
  const SparsityPattern* eff = reuse_dense ? &s.pattern : dense_fallback ? &dense_pattern : p;

  // Rebuild only on a change of size or solver kind; a new structure re-sizes the sparse
  // matrix (the KLU solver notices the new pattern and re-analyses it).
  const bool pattern_changed =
      (eff != nullptr) != s.has_pattern || (eff && eff != &s.pattern && *eff != s.pattern);
  if (!same_size) {
    s.set_pattern(eff, dense_fallback);
    s.build(n, use_klu, own_step, eff);
  } else if (pattern_changed) {
    s.set_pattern(eff, dense_fallback);
    if (use_klu && SUNSparseMatrix_Reallocate(s.J, eff->nnz()) != 0)
      throw std::runtime_error("NewtonSolver: cannot re-size the sparse Jacobian");
  }
  s.fd.prepare(n);
  if (s.has_pattern && !use_klu) s.values.resize(static_cast<size_t>(s.pattern.nnz()));
  if (s.f_final.size() != n) s.f_final.resize(n);
  if (s.x_last.size() != n) s.x_last.resize(n);
  s.f_last_valid = false;

  // Scaling.
  Eigen::Map<Eigen::VectorXd> us(N_VGetArrayPointer(s.uscale), n);
  Eigen::Map<Eigen::VectorXd> fs(N_VGetArrayPointer(s.fscale), n);
  system.unknown_scale(us);
  system.residual_scale(fs);
  if (!(us.array() > 0.0).all() || !us.allFinite())
    throw std::invalid_argument("NewtonSolver::solve: unknown_scale must be positive and finite");
  if (!(fs.array() > 0.0).all() || !fs.allFinite())
    throw std::invalid_argument("NewtonSolver::solve: residual_scale must be positive and finite");

  Eigen::Map<Eigen::VectorXd> u(N_VGetArrayPointer(s.u), n);
  u = x;

  double mxnewt = options.max_newton_step;
  if (mxnewt == 0.0)
    mxnewt = 1000.0 * std::max(us.cwiseProduct(x).norm(), std::sqrt(static_cast<double>(n)));

  // Per-solve state.
  s.system = &system;
  s.nfe = s.nje = 0;
  const int fd_before = s.fd.evaluations;
  s.last_failure = s.jac_failure = EvalFailure::None;
  s.kinsol_message.clear();
  s.exception = nullptr;

  int ret = KINSetFuncNormTol(s.kin, options.function_tolerance);
  if (ret == KIN_SUCCESS) ret = KINSetScaledStepTol(s.kin, options.step_tolerance);
  if (ret == KIN_SUCCESS) ret = KINSetNumMaxIters(s.kin, options.max_iterations);
  if (ret == KIN_SUCCESS) ret = KINSetMaxSetupCalls(s.kin, options.max_setup_calls);
  if (ret == KIN_SUCCESS) ret = KINSetMaxNewtonStep(s.kin, mxnewt);
  const bool reuse = options.reuse_jacobian && s.factored == &system;
  if (ret == KIN_SUCCESS) ret = KINSetNoInitSetup(s.kin, reuse ? SUNTRUE : SUNFALSE);
  int flag = ret;
  if (ret == KIN_SUCCESS)
    flag = KINSol(s.kin, s.u, options.line_search ? KIN_LINESEARCH : KIN_NONE, s.uscale,
                  s.fscale);
  s.system = nullptr;

  if (s.exception) {
    std::exception_ptr e = s.exception;
    s.exception = nullptr;
    // KINSOL's memory may be mid-iteration; rebuild it on the next solve to be safe.
    s.destroy();
    std::rethrow_exception(e);
  }

  long nni = 0;
  KINGetNumNonlinSolvIters(s.kin, &nni);
  s.factored = s.jac_failure == EvalFailure::None && (s.nje > 0 || reuse) ? &system : nullptr;
  result.flag = flag;
  result.iterations = static_cast<int>(nni);
  result.jacobian_evaluations = s.nje;
  result.fd_residual_evaluations = s.fd.evaluations - fd_before;
  result.linear_solver = own_step ? "system" : use_klu ? "klu" : "dense";
  x = u;

  // Judge the returned point ourselves: KINSOL's flag alone is not a proof of convergence
  // (KIN_STEP_LT_STPTOL means "stuck" as often as "converged").
  EvalFailure final_failure = EvalFailure::None;
  // KINSOL's last residual call at the returned point is that evaluation (see f_last_valid).
  const bool known = s.f_last_valid && x == s.x_last;
  s.f_last_valid = false;
  if (!known) ++s.nfe;
  const bool eval_ok = known || system.residual(x, s.f_final);
  if (!eval_ok)
    final_failure = EvalFailure::NotEvaluated;
  else if (!s.f_final.allFinite())
    final_failure = EvalFailure::NonFinite;
  result.residual_evaluations = s.nfe;
  if (final_failure == EvalFailure::None) {
    result.residual_norm = s.f_final.cwiseProduct(fs).cwiseAbs().maxCoeff();
    result.physical_residual = s.f_final.norm();
  } else {
    result.residual_norm = std::numeric_limits<double>::infinity();
    result.physical_residual = std::numeric_limits<double>::infinity();
  }
  const bool small = final_failure == EvalFailure::None &&
                     result.residual_norm <= options.function_tolerance;

  const detail::Verdict verdict = detail::judge(flag, final_failure, small, s.jac_failure, s.last_failure);
  result.termination = verdict.termination;
  result.message = detail::newton_message(flag, result.iterations, result.residual_norm, verdict, s.kinsol_message);
  return result;
}

}  // namespace tdcr::bvp
