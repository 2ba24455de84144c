// The lumped models' own Jacobian (LumpedProblem::jacobian, recursive form): forward differences
// that re-evaluate only from the perturbed subsegment on must give exactly the numbers of plain
// forward differences of the whole residual (bvp::finite_difference_jacobian: same steps, same
// operations), for CCsub and PRB, with tendons alone, a tip wrench, gravity with disk masses and
// only the first segment loaded, at the solution and off it. Exact equality: the reused frames and
// disk loads must be bit-identical to recomputed ones, or the optimisation changed the physics.
#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/lumped_problem.hpp"
#include "tdcr/bvp/residual_system.hpp"
#include "tdcr/core/paper_robot.hpp"
#include "tdcr/models/ccsub.hpp"
#include "tdcr/models/prb.hpp"

using namespace tdcr;

namespace {

struct Case {
  std::string name;
  Scene scene;
};

std::vector<Case> cases(int n) {
  std::vector<Case> c;
  Scene tendons = paper::scene(n, 5, "ccsub");  // (0, 0, T_M, 0): every subsegment loaded
  c.push_back({"tendons", tendons});
  Scene tip = tendons;
  tip.loads.tip_force = Vec3(0.3, -0.2, 0.1);
  tip.loads.tip_moment = Vec3(0.002, 0.0, -0.001);
  c.push_back({"tip wrench", tip});
  Scene g = paper::scene(n, 2, "ccsub");  // (T_M, 0, 0, 0): segment 1 loaded by its tendon
  g.loads.gravity = Vec3(0.0, -9.81, 0.0);
  for (Segment& seg : g.robot.segments) seg.disk_mass = 2e-4;
  c.push_back({"gravity, disk masses", g});
  return c;
}

template <typename Model>
void check(const Case& c) {
  const Model model(c.scene.robot, c.scene.effects, LumpedFormulation::Recursive);
  auto ws = model.make_workspace();
  const Solution sol = solve(model, *ws, c.scene.input(), c.scene.solver);
  ASSERT_TRUE(sol.converged()) << sol.summary.message;
  detail::LumpedProblem& P = *static_cast<detail::LumpedWorkspace&>(*ws).problem;
  P.bind(c.scene.input());
  P.set_parameter(1.0);
  ASSERT_TRUE(P.has_jacobian());
  ASSERT_TRUE(P.jacobian_is_forward_difference());
  const int n = P.size();
  ASSERT_GT(n, 0);
  for (double offset : {0.0, 0.03, -0.1}) {
    SCOPED_TRACE(offset);
    Eigen::VectorXd x = sol.unknowns.head(n);
    for (int i = 0; i < n; ++i) x[i] += offset * (i % 2 ? -1.0 : 1.0) * (1.0 + 0.1 * (i % 7));
    Eigen::VectorXd f(n);
    ASSERT_TRUE(P.residual(x, f));
    Eigen::MatrixXd own(n, n), plain(n, n);
    ASSERT_TRUE(P.jacobian(x, f, own));
    ASSERT_TRUE(bvp::finite_difference_jacobian(P, x, f, plain));
    EXPECT_EQ((own - plain).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_GT(plain.cwiseAbs().maxCoeff(), 0.0);
  }
}

}  // namespace

TEST(LumpedJacobian, CcsubStructuredDifferencesEqualPlainDifferences) {
  for (int n : {1, 3, 10})
    for (const Case& c : cases(n)) {
      SCOPED_TRACE(c.name + ", n = " + std::to_string(n));
      check<CcsubModel>(c);
    }
}

TEST(LumpedJacobian, PrbStructuredDifferencesEqualPlainDifferences) {
  for (int n : {1, 3, 10})
    for (const Case& c : cases(n)) {
      SCOPED_TRACE(c.name + ", n = " + std::to_string(n));
      check<PrbModel>(c);
    }
}

// The reduced Newton steps colour the banded Jacobian's columns periodically instead of by the
// greedy search: valid (no two columns of a group share a row) for every J, and no more groups
// than the greedy colouring needs.
TEST(LumpedJacobian, BandedColouringIsValidAndAsSmallAsGreedy) {
  for (int n : {1, 2, 3, 5, 50}) {  // up to 100 nodes, past the period search from 9 on
    Scene s = paper::scene(n, 5, "ccsub");
    s.loads.tip_force = Vec3(0.1, 0.0, 0.0);
    for (bool prb : {false, true}) {
      SCOPED_TRACE(std::string(prb ? "prb" : "ccsub") + ", n = " + std::to_string(n));
      std::unique_ptr<StaticModel> model;
      if (prb) model = std::make_unique<PrbModel>(s.robot, s.effects, LumpedFormulation::Banded);
      else model = std::make_unique<CcsubModel>(s.robot, s.effects, LumpedFormulation::Banded);
      auto ws = model->make_workspace();
      detail::LumpedProblem& P = *static_cast<detail::LumpedWorkspace&>(*ws).problem;
      P.bind(s.input());
      const bvp::SparsityPattern& p = P.banded_pattern();
      const std::vector<int>& g = P.banded_groups();
      ASSERT_EQ(static_cast<int>(g.size()), p.cols);
      EXPECT_TRUE(bvp::valid_column_groups(p, g));
      int greedy = 0;
      bvp::column_groups(p, &greedy);
      EXPECT_LE(*std::max_element(g.begin(), g.end()) + 1, greedy);
      // Colourings that join two columns sharing a row are caught: two unknowns of one
      // subsegment (its constitutive rows), and the disk positions of nodes 1 and 2 (the
      // balance rows of disk 1 read the tendon chords to disks 0, 1 and 2).
      const int m = prb ? 5 : 3, K = m + 12;
      std::vector<int> bad = g;
      bad[1] = bad[0];
      EXPECT_FALSE(bvp::valid_column_groups(p, bad));
      if (p.cols > K + m) {
        bad = g;
        bad[K + m] = bad[m];
        EXPECT_FALSE(bvp::valid_column_groups(p, bad));
      }
    }
  }
}
