// bvp::SparseLu: solves against dense LU, keeps its analysis and pivot order across matrices of
// one pattern, re-pivots when the reused order meets a zero pivot or too much growth, and says
// Singular for a singular matrix.
#include <gtest/gtest.h>

#include <random>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "tdcr/bvp/sparse_lu.hpp"

using tdcr::bvp::SparseLu;
using tdcr::bvp::SparsityPattern;

namespace {

// A block-banded pattern like the lumped models' (blocks of k unknowns, rows of block i
// coupled to blocks i-2 .. i+1), every entry of the pattern set.
SparsityPattern block_band(int blocks, int k) {
  std::vector<std::pair<int, int>> e;
  for (int i = 0; i < blocks; ++i)
    for (int j = std::max(0, i - 2); j <= std::min(blocks - 1, i + 1); ++j)
      for (int r = 0; r < k; ++r)
        for (int c = 0; c < k; ++c) e.emplace_back(k * i + r, k * j + c);
  return SparsityPattern::from_triplets(blocks * k, blocks * k, e);
}

// Values of a random, diagonally weighted matrix on the pattern (well conditioned).
std::vector<double> random_values(const SparsityPattern& p, unsigned seed, double diagonal = 10.0) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> v(p.nnz());
  for (int c = 0; c < p.cols; ++c)
    for (int q = p.col_ptr[c]; q < p.col_ptr[c + 1]; ++q) v[q] = u(rng) + (p.row_idx[q] == c ? diagonal : 0.0);
  return v;
}

Eigen::MatrixXd dense(const SparsityPattern& p, const std::vector<double>& v) {
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(p.rows, p.cols);
  for (int c = 0; c < p.cols; ++c)
    for (int q = p.col_ptr[c]; q < p.col_ptr[c + 1]; ++q) A(p.row_idx[q], c) = v[q];
  return A;
}

double solve_error(SparseLu& lu, const SparsityPattern& p, const std::vector<double>& v, unsigned seed) {
  const Eigen::MatrixXd A = dense(p, v);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::VectorXd b(p.rows);
  for (int i = 0; i < p.rows; ++i) b[i] = u(rng);
  Eigen::VectorXd x = b;
  EXPECT_TRUE(lu.solve(x.data()));
  return (x - A.partialPivLu().solve(b)).cwiseAbs().maxCoeff();
}

}  // namespace

TEST(BvpSparseLu, SolvesLikeDenseLuAndRefactorsMatricesOfOnePattern) {
  const SparsityPattern p = block_band(20, 5);
  SparseLu lu;
  for (unsigned k = 0; k < 4; ++k) {
    const std::vector<double> v = random_values(p, 10 + k);
    ASSERT_EQ(lu.factorize(p, v.data()), SparseLu::Status::Success);
    EXPECT_LE(solve_error(lu, p, v, 100 + k), 1e-12) << "matrix " << k;
  }
  EXPECT_TRUE(lu.factorized());
  EXPECT_EQ(lu.statistics().symbolic_analyses, 1);
  EXPECT_EQ(lu.statistics().factorizations, 1);
  EXPECT_EQ(lu.statistics().refactorizations, 3);
  EXPECT_GT(lu.integer_words(), 0);
  EXPECT_GT(lu.real_words(), 0);

  // Another pattern: analysed afresh, factorised with pivoting.
  const SparsityPattern q = block_band(12, 4);
  const std::vector<double> w = random_values(q, 7);
  ASSERT_EQ(lu.factorize(q, w.data()), SparseLu::Status::Success);
  EXPECT_LE(solve_error(lu, q, w, 8), 1e-12);
  EXPECT_EQ(lu.statistics().symbolic_analyses, 2);
  EXPECT_EQ(lu.statistics().factorizations, 2);
}

TEST(BvpSparseLu, RepivotsWhenTheReusedOrderMeetsAZeroPivot) {
  // [[1, 1], [1, 0]] first (pivot order: diagonal 1 first), then [[0, 1], [1, 0]] whose (0, 0)
  // pivot in the reused order is zero: the refactorisation fails and a pivoting one succeeds.
  const SparsityPattern p = SparsityPattern::from_triplets(2, 2, {{0, 0}, {0, 1}, {1, 0}, {1, 1}});
  SparseLu lu;
  std::vector<double> a{1.0, 1.0, 1.0, 0.0};  // CSC: (0,0), (1,0), (0,1), (1,1)
  ASSERT_EQ(lu.factorize(p, a.data()), SparseLu::Status::Success);
  std::vector<double> b{0.0, 1.0, 1.0, 0.0};
  ASSERT_EQ(lu.factorize(p, b.data()), SparseLu::Status::Success);
  EXPECT_EQ(lu.statistics().rejected_refactorizations, 1);
  EXPECT_EQ(lu.statistics().factorizations, 2);
  double x[2] = {2.0, 3.0};  // [[0, 1], [1, 0]] x = (2, 3)  ->  x = (3, 2)
  ASSERT_TRUE(lu.solve(x));
  EXPECT_DOUBLE_EQ(x[0], 3.0);
  EXPECT_DOUBLE_EQ(x[1], 2.0);
}

TEST(BvpSparseLu, GrowthRatioDecidesWhetherARefactorisationIsKept) {
  // The first matrix fixes the pivot order with a large first pivot; the second puts a tiny
  // value there, so reusing the order grows the pivots by ~1e6. The default ratio (1e-2)
  // re-pivots; a ratio of 1e-9 keeps the refactorisation, and both solve to rounding.
  const SparsityPattern p = SparsityPattern::from_triplets(2, 2, {{0, 0}, {0, 1}, {1, 0}, {1, 1}});
  const std::vector<double> a{4.0, 1.0, 1.0, 3.0};
  const std::vector<double> b{1e-6, 1.0, 1.0, 3.0};
  for (double ratio : {tdcr::bvp::kRefactorGrowthRatio, 1e-9}) {
    SparseLu lu(ratio);
    ASSERT_EQ(lu.factorize(p, a.data()), SparseLu::Status::Success);
    ASSERT_EQ(lu.factorize(p, b.data()), SparseLu::Status::Success);
    const bool kept = ratio < 1e-6;
    EXPECT_EQ(lu.statistics().refactorizations, kept ? 1 : 0) << ratio;
    EXPECT_EQ(lu.statistics().rejected_refactorizations, kept ? 0 : 1) << ratio;
    EXPECT_LE(solve_error(lu, p, b, 3), 1e-9) << ratio;
  }
}

TEST(BvpSparseLu, SingularAndInvalidInputAreReported) {
  const SparsityPattern p = SparsityPattern::from_triplets(2, 2, {{0, 0}, {0, 1}, {1, 0}, {1, 1}});
  SparseLu lu;
  const std::vector<double> singular{1.0, 2.0, 2.0, 4.0};
  EXPECT_EQ(lu.factorize(p, singular.data()), SparseLu::Status::Singular);
  EXPECT_FALSE(lu.factorized());
  double x[2] = {1.0, 1.0};
  EXPECT_FALSE(lu.solve(x));
  const SparsityPattern rect = SparsityPattern::from_triplets(2, 3, {{0, 0}, {1, 1}});
  const std::vector<double> v{1.0, 1.0};
  EXPECT_EQ(lu.factorize(rect, v.data()), SparseLu::Status::Failed);
}
