/// @file newton_solver.hpp
/// @brief Globalised Newton's method (SUNDIALS KINSOL with line search) on a ResidualSystem,
/// with a dense or sparse (KLU) linear solver, behind a reusable workspace.
#pragma once

#include <memory>
#include <string>

#include <Eigen/Core>

#include "tdcr/bvp/residual_system.hpp"
#include "tdcr/core/solution.hpp"

namespace tdcr::bvp {

class SparseLu;

/// @brief Linear solver inside KINSOL's Newton iteration (NewtonOptions::linear_solver).
enum class LinearSolverKind {
  /// Dense LU up to NewtonOptions::dense_size_limit unknowns; above it KLU if the system declares
  /// a sparsity pattern (ResidualSystem::sparsity), dense LU otherwise.
  Automatic,
  Dense,     ///< SUNDIALS dense LU.
  SparseKLU  ///< SUNDIALS KLU on a compressed-sparse-column Jacobian (a dense pattern if the
             ///< system declares none).
};

/// @brief Settings of one Newton solve (NewtonSolver::solve). Plain numbers: the models layer
/// fills the tolerances, iteration limit and linear solver from its own options; the rest are
/// KINSOL details that the models adjust per problem. Residual norms are scaled max-norms,
/// max_i |s_i F_i| with s = ResidualSystem::residual_scale, so tolerances are dimensionless.
struct NewtonOptions {
  /// Residual tolerance (dimensionless, scaled max-norm; KINSOL fnormtol): the solve has
  /// converged when max_i |s_i F_i| <= this. Default 1e-10.
  double function_tolerance = 1e-10;
  /// Scaled step tolerance (dimensionless; KINSOL scsteptol): KINSOL stops when the scaled Newton
  /// step is below this. Such a stop is reported as converged only if function_tolerance also
  /// holds. Default 1e-14.
  double step_tolerance = 1e-14;
  /// Most Newton iterations per solve (count, >= 1). Default 200.
  int max_iterations = 200;
  /// Longest scaled Newton step (dimensionless, KINSOL mxnewtstep; >= 0). 0 (default):
  /// automatic, 1000 * max(|D_u x0|_2, sqrt(n)) with D_u = ResidualSystem::unknown_scale.
  /// KINSOL's own default, 1000 |D_u x0|_2, is zero for a zero initial guess and would stall the
  /// very first step.
  double max_newton_step = 0.0;
  /// Newton iterations between Jacobian evaluations (count, >= 1). Default 1: exact Newton
  /// (KINSOL's default of 10 trades robustness for Jacobian cost, a bad deal when Jacobians are
  /// cheap finite differences or analytic).
  int max_setup_calls = 1;
  /// Start from the Jacobian of this solver's previous solve, if it had one of the same system
  /// (KINSOL's KINSetNoInitSetup): for a sequence of nearby solves such as a warm-started
  /// trajectory. KINSOL evaluates a fresh Jacobian after max_setup_calls iterations, when the
  /// residual stops decreasing fast enough with the old one, or when a line search fails with it.
  /// Default false.
  bool reuse_jacobian = false;
  /// Scaled residual (dimensionless) below which the Jacobian is frozen: exact Newton down to
  /// this, then modified Newton from the last Jacobian (reuse_jacobian, max_setup_calls 10) down
  /// to function_tolerance. The iterates far from the solution, which decide the branch it lands
  /// on, are exact Newton's; the last ones cost a residual each instead of a Jacobian. 0
  /// (default): off; also off when reuse_jacobian is set. Must be 0 or above
  /// function_tolerance.
  double freeze_jacobian_below = 0.0;
  /// Backtracking line search (KIN_LINESEARCH); false: full Newton steps (KIN_NONE). Default
  /// true.
  bool line_search = true;
  /// Linear solver inside Newton. Default LinearSolverKind::Automatic.
  LinearSolverKind linear_solver = LinearSolverKind::Automatic;
  /// LinearSolverKind::Automatic: dense LU up to this many unknowns (count, >= 0), KLU above if
  /// the system declares a sparsity pattern (KLU's overhead does not pay off on small systems).
  /// Default 200.
  int dense_size_limit = 200;

  /// @brief Throws InputError (field `newton.<name>`) on a non-positive tolerance, iteration
  /// limit, setup interval or a negative size limit, a negative max_newton_step, or a
  /// freeze_jacobian_below that is neither 0 nor above function_tolerance.
  void validate() const;
};

/// @brief Outcome of NewtonSolver::solve(). A failed solve is never reported as converged.
struct NewtonResult {
  TerminationType termination = TerminationType::NotSolved;  ///< Why the solve ended.
  int flag = 0;                 ///< KINSOL's return flag (e.g. -6 = KIN_MAXITER_REACHED).
  /// "<KINSOL flag name>: <iterations> iterations, |F|=<residual_norm>", followed by KINSOL's
  /// own error text if it produced one.
  std::string message;
  int iterations = 0;            ///< Newton iterations.
  int residual_evaluations = 0;  ///< Residual evaluations by KINSOL and the final check.
  int jacobian_evaluations = 0;  ///< Jacobian evaluations (analytic or finite differences).
  int fd_residual_evaluations = 0;  ///< Residual evaluations spent in FD Jacobians.
  double residual_norm = 0.0;   ///< max_i |s_i F_i(x)| at the returned x (dimensionless).
  double physical_residual = 0.0;  ///< |F(x)|_2 at the returned x, unscaled (system units).
  std::string linear_solver;    ///< "dense", "klu" or "system" (ResidualSystem::has_newton_step).

  /// @brief True if the residual at the returned x satisfies the tolerance.
  bool converged() const { return termination == TerminationType::Converged; }
};

/// @brief Work done by the sparse LU (KLU) of a NewtonSolver over its lifetime.
struct SparseLuStatistics {
  int symbolic_analyses = 0;  ///< Orderings and symbolic analyses: one per sparsity pattern.
  int factorizations = 0;     ///< Numeric factorisations with partial pivoting.
  int refactorizations = 0;   ///< Accepted refactorisations reusing the previous pivot order.
  /// Refactorisations that failed or grew the pivots too much, redone with pivoting (each
  /// is also counted in factorizations).
  int rejected_refactorizations = 0;
};

/// @brief Newton solver workspace: owns the SUNDIALS context, vectors, Jacobian matrix, linear
/// solver and KINSOL memory, and keeps them across solves.
///
/// They are rebuilt only when the system size or the linear solver kind changes; a new sparsity
/// pattern only re-sizes the sparse matrix. Otherwise a solve reuses everything (vectors,
/// matrix, KINSOL memory, and KLU's symbolic analysis, pivot order and LU memory: later
/// Jacobians are refactorised in the previous pivot order while that stays numerically safe),
/// so warm-started repeated solves (continuation, trajectories, benchmarks) pay no setup cost.
/// Not thread-safe: use one NewtonSolver per thread. Movable, not copyable.
class NewtonSolver {
 public:
  /// @brief Creates the SUNDIALS context (throws std::runtime_error if that fails); vectors,
  /// matrix, linear solver and KINSOL memory are built by the first solve().
  NewtonSolver();
  ~NewtonSolver();
  /// @brief Takes over another solver's SUNDIALS objects. The moved-from solver may only be
  /// destroyed or assigned to.
  NewtonSolver(NewtonSolver&&) noexcept;
  /// @brief Takes over another solver's SUNDIALS objects (this one's are freed). The moved-from
  /// solver may only be destroyed or assigned to.
  NewtonSolver& operator=(NewtonSolver&&) noexcept;
  NewtonSolver(const NewtonSolver&) = delete;
  NewtonSolver& operator=(const NewtonSolver&) = delete;

  /// @brief Solve system(x) = 0.
  /// @param system The residual system (its sparsity(), scales and Jacobian are used if given).
  /// @param x In: initial guess (size system.size()). Out: the last iterate, whatever the
  /// outcome (check the result before using it).
  /// @param options Validated here (throws InputError on bad values).
  /// Exceptions thrown by the system's callbacks propagate after KINSOL has been unwound
  /// cleanly. Never writes to stdout or stderr.
  NewtonResult solve(ResidualSystem& system, Eigen::VectorXd& x,
                     const NewtonOptions& options = NewtonOptions());

  /// @brief Forget the factored Jacobian: the next solve with NewtonOptions::reuse_jacobian
  /// starts with a fresh one (e.g. after the system re-parameterised its unknowns).
  void forget_jacobian();

  /// @brief Number of times the SUNDIALS objects were (re)built; lets tests and benchmarks
  /// verify that repeated solves reuse the workspace.
  int rebuilds() const;

  /// @brief KLU work over this solver's lifetime (all zero if KLU was never used); lets tests
  /// and benchmarks verify that repeated solves keep the symbolic analysis.
  SparseLuStatistics sparse_lu_statistics() const;

  /// @brief A second KLU factorisation kept with this workspace for callers that factor their
  /// own matrices between Newton solves (the arclength tangents of arclength_continuation), so
  /// that its analysis and LU memory serve every path solved with this workspace. Not used by
  /// solve(); not counted in sparse_lu_statistics().
  SparseLu& tangent_lu();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tdcr::bvp
