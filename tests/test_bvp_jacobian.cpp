// Sparsity patterns, column groups, finite-difference Jacobians and check_jacobian.
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "bvp_test_systems.hpp"
#include "tdcr/bvp/residual_system.hpp"

using tdcr::bvp::SparsityPattern;

namespace {



using bvp_test::Bratu;
using bvp_test::tridiagonal;

// A dense 3x3 system with an analytic Jacobian, optionally with one wrong entry.
class Dense3 : public tdcr::bvp::ResidualSystem {
 public:
  explicit Dense3(bool wrong = false) : wrong_(wrong) {}
  int size() const override { return 3; }
  bool residual(const Eigen::Ref<const Eigen::VectorXd>& x,
                Eigen::Ref<Eigen::VectorXd> f) override {
    f[0] = 3.0 * x[0] + x[1] * x[2] - 9.0;
    f[1] = x[0] * x[0] + 2.0 * x[1] - x[2] - 2.0;
    f[2] = std::exp(x[0] - 1.0) + x[1] + x[2] * x[2] - 12.0;
    return true;
  }
  bool has_jacobian() const override { return true; }
  bool jacobian(const Eigen::Ref<const Eigen::VectorXd>& x, const Eigen::Ref<const Eigen::VectorXd>&,
                Eigen::Ref<Eigen::MatrixXd> J) override {
    J << 3.0, x[2], x[1],  //
        2.0 * x[0], 2.0, -1.0,  //
        std::exp(x[0] - 1.0), 1.0, 2.0 * x[2];
    if (wrong_) J(1, 2) = -1.1;  // a 10% error in one entry
    return true;
  }

 private:
  bool wrong_;
};

}  // namespace

TEST(BvpSparsity, FromTripletsSortsMergesAndIndexes) {
  const auto p = SparsityPattern::from_triplets(3, 3, {{2, 0}, {0, 0}, {2, 0}, {1, 2}, {0, 2}});
  EXPECT_TRUE(p.valid());
  EXPECT_EQ(p.nnz(), 4);
  EXPECT_EQ(p.col_ptr, (std::vector<int>{0, 2, 2, 4}));
  EXPECT_EQ(p.row_idx, (std::vector<int>{0, 2, 0, 1}));
  EXPECT_EQ(p.index_of(2, 0), 1);
  EXPECT_EQ(p.index_of(1, 2), 3);
  EXPECT_EQ(p.index_of(1, 0), -1);
  EXPECT_THROW(SparsityPattern::from_triplets(2, 2, {{2, 0}}), std::invalid_argument);
}

TEST(BvpSparsity, DensePatternIsFull) {
  const auto p = SparsityPattern::dense(4);
  EXPECT_TRUE(p.valid());
  EXPECT_EQ(p.nnz(), 16);
  EXPECT_EQ(p.index_of(3, 2), 11);
}

TEST(BvpSparsity, ColumnGroupsOfTridiagonalAreThree) {
  const auto p = tridiagonal(500);
  int groups = 0;
  const auto g = tdcr::bvp::column_groups(p, &groups);
  EXPECT_EQ(groups, 3);
  ASSERT_EQ(g.size(), 500u);
  // Columns in one group must share no row.
  for (int r = 0; r < 500; ++r) {
    std::set<int> seen;
    for (int j = std::max(0, r - 1); j <= std::min(499, r + 1); ++j)
      EXPECT_TRUE(seen.insert(g[j]).second) << "row " << r;
  }
}

TEST(BvpSparsity, ColumnGroupsOfDiagonalAndDense) {
  std::vector<std::pair<int, int>> d;
  for (int i = 0; i < 10; ++i) d.emplace_back(i, i);
  int groups = 0;
  tdcr::bvp::column_groups(SparsityPattern::from_triplets(10, 10, d), &groups);
  EXPECT_EQ(groups, 1);
  tdcr::bvp::column_groups(SparsityPattern::dense(7), &groups);
  EXPECT_EQ(groups, 7);
}

TEST(BvpJacobian, DenseForwardDifferenceMatchesAnalytic) {
  Dense3 sys;
  Eigen::VectorXd x(3), f(3);
  x << 0.7, -1.3, 2.1;
  sys.residual(x, f);
  Eigen::MatrixXd Jfd(3, 3), Ja(3, 3);
  ASSERT_TRUE(tdcr::bvp::finite_difference_jacobian(sys, x, f, Jfd));
  ASSERT_TRUE(sys.jacobian(x, f, Ja));
  // Forward differences: error ~ sqrt(eps) * |F''| ~ 1e-8 relative.
  EXPECT_LT((Jfd - Ja).cwiseAbs().maxCoeff(), 1e-6);
}

TEST(BvpJacobian, GroupedDifferencesCostThreeEvaluationsAndMatchAnalytic) {
  const int n = 500;
  Bratu sys(n, 1.0, true);
  Eigen::VectorXd u(n), f(n);
  for (int i = 0; i < n; ++i) u[i] = 0.1 * std::sin(0.01 * i);
  sys.residual(u, f);
  const SparsityPattern& p = *sys.sparsity();
  std::vector<double> fd(p.nnz()), an(p.nnz());
  tdcr::bvp::FiniteDifferenceWorkspace ws;
  ws.prepare(p);
  sys.evaluations = 0;
  ASSERT_TRUE(tdcr::bvp::finite_difference_sparse_jacobian(sys, u, f, p, fd.data(), &ws));
  EXPECT_EQ(sys.evaluations, 3);  // one per column group, not n
  EXPECT_EQ(ws.evaluations, 3);
  ASSERT_TRUE(sys.sparse_jacobian(u, f, an.data()));
  double err = 0.0;
  for (int k = 0; k < p.nnz(); ++k) err = std::max(err, std::abs(fd[k] - an[k]));
  EXPECT_LT(err, 1e-7);
}

TEST(BvpJacobian, CheckJacobianAcceptsCorrectAndFlagsWrongEntry) {
  Eigen::VectorXd x(3);
  x << 0.7, -1.3, 2.1;
  Dense3 good;
  const auto ok = tdcr::bvp::check_jacobian(good, x);
  EXPECT_TRUE(ok.evaluated);
  EXPECT_LT(ok.max_relative_error, 1e-8);
  EXPECT_TRUE(ok.ok(1e-6));

  Dense3 bad(true);
  const auto ko = tdcr::bvp::check_jacobian(bad, x);
  EXPECT_TRUE(ko.evaluated);
  EXPECT_NEAR(ko.max_relative_error, 0.1 / 1.1, 1e-6);  // |-1.1 - (-1)| / 1.1
  EXPECT_EQ(ko.worst_row, 1);
  EXPECT_EQ(ko.worst_col, 2);
  EXPECT_FALSE(ko.ok(1e-6));
}

TEST(BvpJacobian, CheckJacobianOnSparseSystem) {
  Bratu sys(20, 2.0, true);
  Eigen::VectorXd u = Eigen::VectorXd::Constant(20, 0.3);
  const auto r = tdcr::bvp::check_jacobian(sys, u);
  EXPECT_TRUE(r.evaluated);
  EXPECT_LT(r.max_relative_error, 1e-8);
}
