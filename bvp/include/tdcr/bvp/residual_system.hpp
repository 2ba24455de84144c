/// @file residual_system.hpp
/// @brief A nonlinear system F(x) = 0 as the Newton solver sees it (a small, Ceres-like
/// interface), its Jacobian sparsity, and finite-difference Jacobians that exploit it.
///
/// Everything here is numerics only: x and F are plain vectors, their meaning (and units) is the
/// business of whoever implements ResidualSystem.
#pragma once

#include <limits>
#include <utility>
#include <vector>

#include <Eigen/Core>

namespace tdcr::bvp {

/// @brief Structure (not values) of a sparse Jacobian, in compressed sparse column (CSC) form.
///
/// Column j owns the entries col_ptr[j] .. col_ptr[j+1]-1; row_idx holds their row indices,
/// sorted ascending and unique within every column. This is exactly the layout of SUNDIALS'
/// CSC_MAT sparse matrix, so values computed in this order can be copied into KLU's matrix as is.
struct SparsityPattern {
  int rows = 0;              ///< Number of rows (residuals).
  int cols = 0;              ///< Number of columns (unknowns).
  std::vector<int> col_ptr;  ///< Size cols+1; col_ptr[0] = 0, col_ptr[cols] = nnz().
  std::vector<int> row_idx;  ///< Size nnz(); row of every stored entry, sorted per column.

  /// @brief A fully dense n x n pattern (every entry structurally nonzero). Lets a system with
  /// no known structure still use the sparse code paths (e.g. KLU on request).
  static SparsityPattern dense(int n);
  /// @brief Build a pattern from (row, col) pairs in any order; duplicates are merged.
  /// Throws std::invalid_argument on an index outside [0, rows) x [0, cols).
  static SparsityPattern from_triplets(int rows, int cols,
                                       const std::vector<std::pair<int, int>>& entries);
  /// @brief Number of structurally nonzero entries.
  int nnz() const { return col_ptr.empty() ? 0 : col_ptr.back(); }
  /// @brief Position in the CSC value array of entry (row, col), or -1 if it is structurally
  /// zero. Binary search in the column: O(log nnz(col)). Convenient when filling analytic
  /// sparse Jacobians; precompute the positions if this sits in a hot loop.
  int index_of(int row, int col) const;
  /// @brief True if the sizes are consistent, col_ptr is non-decreasing and row indices are in
  /// range, sorted and unique per column.
  bool valid() const;
  /// @brief Structural equality (same sizes and entries).
  bool operator==(const SparsityPattern& o) const {
    return rows == o.rows && cols == o.cols && col_ptr == o.col_ptr && row_idx == o.row_idx;
  }
  /// @brief Structural inequality.
  bool operator!=(const SparsityPattern& o) const { return !(*this == o); }
};

/// @brief Greedy column colouring for grouped finite differences (Curtis-Powell-Reid).
///
/// Two columns receive different groups if they have a nonzero in a common row, so all columns
/// of one group can be perturbed together and their Jacobian columns still be told apart: a
/// finite-difference Jacobian then costs one residual evaluation per group instead of one per
/// unknown. A tridiagonal pattern needs 3 groups whatever its size; a block-banded multiple
/// shooting Jacobian needs about (bandwidth) groups, independent of the number of intervals.
///
/// @param pattern The Jacobian structure.
/// @param num_groups If not null, receives the number of groups (max group id + 1).
/// @return The group id (0-based) of every column.
std::vector<int> column_groups(const SparsityPattern& pattern, int* num_groups = nullptr);

/// @brief A square nonlinear system F(x) = 0, the unit of work of NewtonSolver.
///
/// Only size() and residual() are required. The rest lets a system tell the solver what it
/// knows: Jacobian structure (for KLU and grouped finite differences), an analytic Jacobian, and
/// typical magnitudes of residuals and unknowns (scaling). Implementations must not allocate in
/// residual() if they are used in hot loops; the solver never does.
class ResidualSystem {
 public:
  virtual ~ResidualSystem() = default;

  /// @brief Number of unknowns, which is also the number of residuals.
  virtual int size() const = 0;

  /// @brief Evaluate F(x) into f (both of length size()).
  /// @return false if F cannot be evaluated at x (e.g. the ODE integrator failed). The Newton
  /// solver treats this as recoverable: it shortens the step and tries again.
  virtual bool residual(const Eigen::Ref<const Eigen::VectorXd>& x,
                        Eigen::Ref<Eigen::VectorXd> f) = 0;

  /// @brief Jacobian structure, or nullptr for a dense Jacobian. The pointer must stay valid
  /// and unchanged for the duration of a solve; returning the same pattern across solves lets
  /// NewtonSolver reuse its sparse matrix and KLU symbolic analysis.
  virtual const SparsityPattern* sparsity() const { return nullptr; }

  /// @brief True if jacobian() (no sparsity) or sparse_jacobian() (with sparsity) is
  /// implemented by the system: analytically, or by differences that exploit its structure (see
  /// jacobian_is_forward_difference); otherwise the solver uses finite differences.
  virtual bool has_jacobian() const { return false; }
  /// @brief True if jacobian() is a forward-difference approximation with the solver's own
  /// steps (finite_difference_step), only cheaper than finite_difference_jacobian: accurate to
  /// O(sqrt(eps)), enough for Newton. A consumer that needs more (central differences for
  /// differential kinematics) differences the residual itself.
  virtual bool jacobian_is_forward_difference() const { return false; }

  /// @brief Analytic dense Jacobian dF/dx at x, where f = F(x) is supplied for reuse. Override
  /// this when sparsity() returns nullptr.
  /// @param x Unknowns (length size()).
  /// @param f F(x), already evaluated (length size()).
  /// @param J Preallocated size() x size() matrix (column-major), to be overwritten.
  /// @return false if it cannot be evaluated (recoverable, like residual()).
  virtual bool jacobian(const Eigen::Ref<const Eigen::VectorXd>& x,
                        const Eigen::Ref<const Eigen::VectorXd>& f,
                        Eigen::Ref<Eigen::MatrixXd> J) {
    (void)x;
    (void)f;
    (void)J;
    return false;
  }

  /// @brief Analytic sparse Jacobian at x: write the nnz() values of dF/dx in the order of the
  /// sparsity() CSC arrays. Override this when sparsity() is not nullptr; the solver scatters
  /// the values itself when it uses a dense linear solver.
  virtual bool sparse_jacobian(const Eigen::Ref<const Eigen::VectorXd>& x,
                               const Eigen::Ref<const Eigen::VectorXd>& f, double* values) {
    (void)x;
    (void)f;
    (void)values;
    return false;
  }

  /// @brief True if the system computes its Newton steps itself (setup_newton_step,
  /// solve_newton_step), e.g. by eliminating auxiliary unknowns from a larger structured system;
  /// the solver then forms no Jacobian and takes linear_solver "system".
  virtual bool has_newton_step() const { return false; }
  /// @brief Linearise at x (f = F(x), already evaluated) for the following solve_newton_step
  /// calls; false if it cannot be evaluated (recoverable, like residual()).
  virtual bool setup_newton_step(const Eigen::Ref<const Eigen::VectorXd>& x,
                                 const Eigen::Ref<const Eigen::VectorXd>& f) {
    (void)x;
    (void)f;
    return false;
  }
  /// @brief Overwrite b with the solution d of J d = b, J = dF/dx at the last setup's x.
  virtual bool solve_newton_step(Eigen::Ref<Eigen::VectorXd> b) {
    (void)b;
    return false;
  }

  /// @brief Residual scale factors s (length size()): the solver drives s_i F_i to zero and
  /// tests max_i |s_i F_i| against its tolerance. Choose 1 / (typical magnitude of F_i) so
  /// every scaled residual is O(1): force balances (N) and moment balances (N m) of a
  /// millimetre-sized rod differ by orders of magnitude, and an unscaled norm would ignore
  /// the small ones. Default: all ones.
  virtual void residual_scale(Eigen::Ref<Eigen::VectorXd> s) const { s.setOnes(); }

  /// @brief Unknown scale factors (KINSOL's uscale): 1 / (typical magnitude of x_j). Used for
  /// the step tolerance, the maximum Newton step and the finite-difference increments.
  /// Default: all ones.
  virtual void unknown_scale(Eigen::Ref<Eigen::VectorXd> s) const { s.setOnes(); }

  /// @brief Relative accuracy of residual() (default: machine epsilon). A residual computed
  /// through an error-controlled integrator (CVODE) is only a smooth function of x up to about
  /// its tolerance, and a finite-difference increment of sqrt(eps) would then mostly
  /// differentiate noise; finite differences use sqrt(max(eps, relative_noise())) instead.
  virtual double relative_noise() const;
};

/// @brief Scratch memory for finite-difference Jacobians, so that repeated Jacobians (one per
/// Newton iteration) allocate nothing. Sized by prepare(); reused as long as the system size
/// and pattern do not change.
struct FiniteDifferenceWorkspace {
  Eigen::VectorXd x_pert;        ///< Perturbed unknowns.
  Eigen::VectorXd f_pert;        ///< Residual at the perturbed unknowns.
  Eigen::VectorXd uscale;        ///< Unknown scale of the system.
  Eigen::VectorXd step;          ///< Increment actually used per column.
  std::vector<int> group_ptr;    ///< Columns of group g: group_cols[group_ptr[g] .. [g+1]).
  std::vector<int> group_cols;   ///< Columns sorted by group.
  int num_groups = 0;            ///< Number of column groups (0 until prepared for a pattern).
  int evaluations = 0;           ///< Residual evaluations spent in finite differences (total).

  /// @brief Size the vectors for n unknowns (no-op if already sized).
  void prepare(int n);
  /// @brief Size the vectors and compute the column groups of a pattern (column_groups).
  void prepare(const SparsityPattern& pattern);
  /// @brief Size the vectors and take the column groups as given: groups[j] is the 0-based
  /// group of column j, and no two columns of one group may share a row of the pattern (not
  /// checked here; see valid_column_groups). A structured system knows such a colouring (e.g.
  /// by node index modulo the coupling width of a block-banded pattern) and saves the greedy
  /// search, which costs more than a Newton iteration of a large banded system.
  void prepare(const SparsityPattern& pattern, const std::vector<int>& groups);
};

/// @brief True if groups (one 0-based id per column of pattern) is a valid grouping for
/// finite_difference_sparse_jacobian: no two columns of a group share a row.
bool valid_column_groups(const SparsityPattern& pattern, const std::vector<int>& groups);

/// @brief The forward-difference increment used throughout bvp for an unknown of value x and
/// unknown scale uscale: sqrt(max(eps, relative_noise)) * max(|x|, 1/uscale), rounded so that
/// (x + h) - x == h exactly. Exposed for systems that difference their own sub-problems.
double finite_difference_step(double x, double uscale,
                              double relative_noise = std::numeric_limits<double>::epsilon());

/// @brief Forward-difference dense Jacobian: column j is (F(x + h_j e_j) - f) / h_j with
/// h_j = sqrt(eps) * max(|x_j|, 1 / uscale_j), the increment KINSOL itself uses (eps is
/// replaced by system.relative_noise() if that is larger).
///
/// Costs size() residual evaluations. Use finite_difference_sparse_jacobian when a sparsity
/// pattern is known.
/// @param system The system; its residual() is evaluated at the perturbed points.
/// @param x Unknowns at which to differentiate (length system.size()).
/// @param f F(x), already evaluated.
/// @param J Output, size() x size().
/// @param workspace Optional reusable scratch memory (allocated locally if null).
/// @return false if a perturbed residual could not be evaluated or was not finite.
bool finite_difference_jacobian(ResidualSystem& system, const Eigen::Ref<const Eigen::VectorXd>& x,
                                const Eigen::Ref<const Eigen::VectorXd>& f,
                                Eigen::Ref<Eigen::MatrixXd> J,
                                FiniteDifferenceWorkspace* workspace = nullptr);

/// @brief Forward-difference sparse Jacobian using column groups: every column of a group is
/// perturbed at once, so the cost is column_groups() residual evaluations, not size().
/// @param system The system; its residual() is evaluated at the perturbed points.
/// @param x Unknowns at which to differentiate (length system.size()).
/// @param f F(x), already evaluated.
/// @param pattern Jacobian structure (rows = cols = size()).
/// @param values Output, pattern.nnz() values in CSC order.
/// @param workspace Optional scratch memory; if given it must have been prepare()d with this
/// pattern (the groups are then not recomputed). Allocated locally if null.
/// @return false if a perturbed residual could not be evaluated or was not finite.
bool finite_difference_sparse_jacobian(ResidualSystem& system,
                                       const Eigen::Ref<const Eigen::VectorXd>& x,
                                       const Eigen::Ref<const Eigen::VectorXd>& f,
                                       const SparsityPattern& pattern, double* values,
                                       FiniteDifferenceWorkspace* workspace = nullptr);

/// @brief The analytic Jacobian of a system as a dense matrix, whichever form it implements
/// (jacobian() without sparsity, sparse_jacobian() scattered otherwise).
/// @return false if the system has no analytic Jacobian or it could not be evaluated.
bool analytic_jacobian_dense(ResidualSystem& system, const Eigen::Ref<const Eigen::VectorXd>& x,
                             const Eigen::Ref<const Eigen::VectorXd>& f,
                             Eigen::Ref<Eigen::MatrixXd> J);

/// @brief Outcome of check_jacobian().
struct JacobianCheck {
  bool evaluated = false;           ///< False if F or the analytic Jacobian failed at x.
  double max_relative_error = 0.0;  ///< max_ij |J_a - J_fd| / max(|J_a|, |J_fd|, floor).
  int worst_row = -1;               ///< Row of the entry attaining max_relative_error.
  int worst_col = -1;               ///< Column of that entry.
  Eigen::MatrixXd analytic;         ///< The analytic Jacobian (dense).
  Eigen::MatrixXd numeric;          ///< The central-difference Jacobian.
  /// @brief True if evaluated and max_relative_error <= tolerance.
  bool ok(double tolerance) const { return evaluated && max_relative_error <= tolerance; }
};

/// @brief Compare a system's analytic Jacobian with central differences at x (a test helper;
/// it allocates). For a sparse system the scattered analytic values are compared on the full
/// matrix, so an entry missing from sparsity() shows up as a relative error of 1.
///
/// Central differences with h_j = eps^(1/3) max(|x_j|, 1/uscale_j) (eps: the larger of machine
/// epsilon and system.relative_noise()) are accurate to about
/// 1e-10 relative for smooth F, so a correct Jacobian gives errors around 1e-8 or below.
/// Entries small against the largest entry of the matrix are compared on an absolute floor of
/// 1e-8 * max|J| to avoid dividing noise by zero.
JacobianCheck check_jacobian(ResidualSystem& system, const Eigen::Ref<const Eigen::VectorXd>& x);

}  // namespace tdcr::bvp
