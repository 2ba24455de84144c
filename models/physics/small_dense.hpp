// Private to models/: linear systems of fixed small size (6, 12) solved in plain loops. Eigen's
// fixed-size PartialPivLU goes through its general blocked triangular solver for matrix
// right-hand sides and inverses, several times slower at these sizes (in VC's conjugate-point
// test the 6 x 6 inverses and the 12 x 12 solve per disk interval cost as much as its shots).
#pragma once

#include <cmath>
#include <utility>

#include <Eigen/Core>

namespace tdcr::physics {

/// A X = B for X, overwriting B: Gaussian elimination with partial pivoting (A is taken by value
/// and eliminated). False, B unspecified, where a pivot is zero or not finite.
template <int N, int M>
bool solve_small(Eigen::Matrix<double, N, N> A, Eigen::Matrix<double, N, M>& B) {
  for (int c = 0; c < N; ++c) {
    int p = c;
    double best = std::abs(A(c, c));
    for (int r = c + 1; r < N; ++r)
      if (std::abs(A(r, c)) > best) {
        best = std::abs(A(r, c));
        p = r;
      }
    if (!(best > 0.0) || !std::isfinite(best)) return false;
    if (p != c) {
      for (int j = c; j < N; ++j) std::swap(A(p, j), A(c, j));
      for (int j = 0; j < M; ++j) std::swap(B(p, j), B(c, j));
    }
    const double inv = 1.0 / A(c, c);
    for (int r = c + 1; r < N; ++r) {
      const double f = A(r, c) * inv;
      if (f == 0.0) continue;
      for (int j = c + 1; j < N; ++j) A(r, j) -= f * A(c, j);
      for (int j = 0; j < M; ++j) B(r, j) -= f * B(c, j);
    }
  }
  for (int c = N - 1; c >= 0; --c) {
    const double inv = 1.0 / A(c, c);
    for (int j = 0; j < M; ++j) {
      double s = B(c, j);
      for (int k = c + 1; k < N; ++k) s -= A(c, k) * B(k, j);
      B(c, j) = s * inv;
    }
  }
  return B.allFinite();
}

/// A^-1 into `inv` (solve_small with B = I). False where A is singular to working precision.
template <int N>
bool invert_small(const Eigen::Matrix<double, N, N>& A, Eigen::Matrix<double, N, N>& inv) {
  inv.setIdentity();
  return solve_small<N, N>(A, inv);
}

}  // namespace tdcr::physics
