// bvp::SparseLu: solves against dense LU, keeps its analysis and pivot order across matrices of
// one pattern (and the analyses of its last two patterns), re-pivots when the reused order meets
// a zero pivot or too much growth, says Singular for a singular matrix, and gives the sign and
// log|det| of the factored matrix as dense LU does.
#include <gtest/gtest.h>

#include <cmath>
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

// Three patterns p, q, r: p and q alternate without re-analysis; r replaces the least recently
// used one (q after p, q, p, q, p), so p stays kept and q is analysed again (replacing r). Every solve uses the
// factorisation of the matrix just factorised.
TEST(BvpSparseLu, KeepsTheAnalysesOfItsLastTwoPatterns) {
  const SparsityPattern p = block_band(10, 3), q = block_band(8, 4), r = block_band(6, 2);
  SparseLu lu;
  int expected = 0;
  unsigned seed = 1;
  for (const auto& [pattern, analysed] : std::vector<std::pair<const SparsityPattern*, bool>>{
           {&p, true}, {&q, true}, {&p, false}, {&q, false}, {&p, false}, {&r, true}, {&p, false},
           {&q, true}, {&p, false}}) {
    const std::vector<double> v = random_values(*pattern, ++seed);
    ASSERT_EQ(lu.factorize(*pattern, v.data()), SparseLu::Status::Success);
    EXPECT_LE(solve_error(lu, *pattern, v, seed), 1e-12) << "step " << seed;
    if (analysed) ++expected;
    EXPECT_EQ(lu.statistics().symbolic_analyses, expected) << "step " << seed;
  }
  EXPECT_EQ(lu.statistics().factorizations, 4);  // one per analysis: kept slots refactorise
}

// The determinant from KLU's factors (row and column permutations, row scaling, BTF blocks)
// against dense LU: random block-banded matrices, the same with two columns swapped (the sign
// flips), a block-diagonal matrix (several BTF blocks) and a refactorisation in a reused order.
TEST(BvpSparseLu, DeterminantMatchesDenseLu) {
  auto check = [](SparseLu& lu, const SparsityPattern& pat, const std::vector<double>& v, const char* what) {
    ASSERT_EQ(lu.factorize(pat, v.data()), SparseLu::Status::Success) << what;
    const Eigen::PartialPivLU<Eigen::MatrixXd> dense_lu(dense(pat, v));
    const Eigen::VectorXd d = dense_lu.matrixLU().diagonal();
    int sign = static_cast<int>(dense_lu.permutationP().determinant());
    double log_abs = 0.0;
    for (Eigen::Index i = 0; i < d.size(); ++i) {
      if (d[i] < 0.0) sign = -sign;
      log_abs += std::log(std::abs(d[i]));
    }
    int klu_sign = 0;
    double klu_log = 0.0;
    ASSERT_TRUE(lu.determinant(klu_sign, klu_log)) << what;
    EXPECT_EQ(klu_sign, sign) << what;
    EXPECT_NEAR(klu_log, log_abs, 1e-10 * std::max(1.0, std::abs(log_abs))) << what;
  };
  const SparsityPattern p = block_band(12, 3);
  SparseLu lu;
  int negative = 0;
  for (unsigned seed = 1; seed <= 12; ++seed) {
    // Weak diagonals: pivoting permutes rows, and about half the determinants are negative.
    const std::vector<double> v = random_values(p, seed, seed % 2 ? 0.2 : 10.0);
    check(lu, p, v, "block band");
    negative += std::signbit(dense(p, v).determinant());
  }
  EXPECT_GT(negative, 0);
  // Columns 0 and 1 swapped: same pattern (full blocks), the opposite sign.
  std::vector<double> v = random_values(p, 40, 0.5), w = v;
  const int len = p.col_ptr[1] - p.col_ptr[0];
  ASSERT_EQ(p.col_ptr[2] - p.col_ptr[1], len);
  std::swap_ranges(w.begin(), w.begin() + len, w.begin() + len);
  check(lu, p, v, "unswapped");
  check(lu, p, w, "swapped");
  int s1 = 0, s2 = 0;
  double l1 = 0.0, l2 = 0.0;
  lu.factorize(p, v.data());
  lu.determinant(s1, l1);
  lu.factorize(p, w.data());
  lu.determinant(s2, l2);
  EXPECT_EQ(s1, -s2);
  EXPECT_NEAR(l1, l2, 1e-10 * std::abs(l1));
  // Block diagonal: KLU's BTF splits it into blocks.
  std::vector<std::pair<int, int>> e;
  for (int b = 0; b < 4; ++b)
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) e.emplace_back(3 * b + i, 3 * b + j);
  const SparsityPattern blocks = SparsityPattern::from_triplets(12, 12, e);
  SparseLu lu2;
  check(lu2, blocks, random_values(blocks, 5, 0.1), "block diagonal");
  check(lu2, blocks, random_values(blocks, 6, 0.1), "block diagonal, refactorised");
  // Structurally zero diagonals: BTF's matching permutes columns (an odd Q for the swaps).
  for (const std::vector<std::pair<int, int>>& t :
       {std::vector<std::pair<int, int>>{{0, 1}, {1, 0}},
        std::vector<std::pair<int, int>>{{0, 1}, {1, 0}, {1, 2}, {2, 2}},
        std::vector<std::pair<int, int>>{{0, 3}, {1, 2}, {2, 1}, {3, 0}, {0, 0}, {3, 2}}}) {
    const int n = t.size() == 2 ? 2 : t.size() == 4 ? 3 : 4;
    const SparsityPattern anti = SparsityPattern::from_triplets(n, n, t);
    SparseLu lu3;
    check(lu3, anti, random_values(anti, 9, 0.0), "zero diagonal");
  }
  int sign = 1;
  double log_abs = 0.0;
  EXPECT_FALSE(SparseLu().determinant(sign, log_abs));  // nothing factorised
}
