/// @file sparse_lu.hpp
/// @brief A sparse LU factorisation (KLU) that keeps its symbolic analysis and its LU memory
/// across factorisations of matrices with the same pattern, for Newton methods that factor a
/// Jacobian of fixed structure once per iteration.
///
/// KINSOL's KLU path uses it behind a SUNLinearSolver; a residual system that solves its own
/// Newton steps on a second, larger sparse linearisation (ResidualSystem::has_newton_step) can
/// hold one directly.
///
/// Policy (the reason this wraps KLU instead of calling it directly):
///  - a pattern is analysed (BTF + AMD ordering, symbolic factorisation) only when it differs
///    from the kPatternSlots patterns analysed last; each keeps its analysis and its last
///    factorisation (a Newton solver that alternates between two systems, e.g. a loading
///    path's bordered corrector and the natural solve at its end, re-analyses neither);
///  - a matrix with the analysed pattern is refactorised with the previous pivot order
///    (klu_refactor), which skips the pivot search and the memory allocation; the result is
///    kept only if the refactorisation succeeded and its reciprocal pivot growth is at least a
///    set ratio (default kRefactorGrowthRatio) times that of the pivoting factorisation whose
///    order it reuses;
///  - otherwise (first matrix, a zero pivot in the reused order, too much growth) the matrix is
///    factorised afresh with partial pivoting.
#pragma once

#include <memory>

#include "tdcr/bvp/newton_solver.hpp"
#include "tdcr/bvp/residual_system.hpp"

namespace tdcr::bvp {

/// A refactorisation whose reciprocal pivot growth falls below this fraction of the reference
/// one (the last pivoting factorisation's) is redone with pivoting: it may lose at most about
/// two more digits than a fresh factorisation.
constexpr double kRefactorGrowthRatio = 1e-2;

/// @brief Sparse LU of a square CSC matrix (KLU), reusing analysis, memory and pivot order
/// across matrices of one pattern. Move-only; not thread safe (one per workspace).
class SparseLu {
 public:
  /// Distinct patterns kept analysed (least recently used one replaced).
  static constexpr int kPatternSlots = 2;

  /// @param refactor_growth_ratio a refactorisation is kept if its reciprocal pivot growth is
  /// at least this times the reference one (> 0; smaller keeps more refactorisations, at up to
  /// log10(1 / ratio) digits of extra error in a solve).
  explicit SparseLu(double refactor_growth_ratio = kRefactorGrowthRatio);
  ~SparseLu();
  /// @brief Takes over the factorisation; the moved-from object may only be destroyed or
  /// assigned to.
  SparseLu(SparseLu&&) noexcept;
  /// @brief Takes over the factorisation (see the move constructor).
  SparseLu& operator=(SparseLu&&) noexcept;
  SparseLu(const SparseLu&) = delete;
  SparseLu& operator=(const SparseLu&) = delete;

  /// @brief Outcome of factorize().
  enum class Status {
    Success,   ///< Factorised; solve() may be called.
    Singular,  ///< A structurally or numerically zero pivot even with pivoting.
    Failed     ///< Invalid input (not square) or out of memory.
  };

  /// @brief Factorises the n x n matrix given in CSC form (64-bit indices, rows sorted and
  /// unique per column, SUNDIALS' CSC_MAT layout). The arrays are read, not kept.
  Status factorize(long n, const long* col_ptr, const long* row_idx, const double* values);
  /// @brief Factorises the matrix with pattern `pattern` (must be square) and values in the
  /// pattern's CSC order (pattern.nnz() of them).
  Status factorize(const SparsityPattern& pattern, const double* values);
  /// @brief Solves A x = b in place (b has n entries) with the last successful factorisation.
  /// False if there is none or KLU reports a failure.
  bool solve(double* b);
  /// @brief Sign and log|det| of the last successfully factorised matrix, from KLU's factors:
  /// det A = sign(P) sign(Q) prod(Rs) prod(diag U) (row scaling Rs > 0, BTF blocks upper
  /// triangular, L unit lower). sign is -1, 0 (a zero pivot) or +1; false if there is no
  /// factorisation. Allocates nothing after the first call for a given size.
  bool determinant(int& sign, double& log_abs);
  /// @brief True after a successful factorize() (until the next one fails).
  bool factorized() const;
  /// @brief Work counters since construction.
  const SparseLuStatistics& statistics() const;
  /// @brief Integer words held (the analysed patterns).
  long integer_words() const;
  /// @brief Real words of KLU's memory in use.
  long real_words() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tdcr::bvp
