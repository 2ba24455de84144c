// The lumped models' own Jacobian (LumpedProblem::jacobian, recursive form): forward differences
// that move the frames distal of the perturbed subsegment rigidly, recompute the loads of two
// disks only and turn the external loads by the rigid motion must give the numbers of plain
// forward differences of the whole residual (bvp::finite_difference_jacobian: same steps) up to
// their own rounding, for CCsub and PRB, with tendons alone, a tip wrench, gravity with disk and
// backbone masses and only the first segment loaded, at the solution and off it. Both are also
// checked against central differences: both must be accurate to forward differences' own error
// (1e-6 of the largest entry, or twice the plain differences' error where PRB's central
// differences at h = 1e-5 are themselves only 1e-5 accurate). A wrong rigid-motion term (a sign,
// a missing shift) gives errors of 1e-3 .. 1 of the Jacobian's size.
#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "allocation_counter.hpp"

#include "lumped/lumped_problem.hpp"
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
  Scene all = tip;  // everything at once, with a heavy backbone
  all.loads.gravity = Vec3(3.0, 1.0, -9.0);
  for (Segment& seg : all.robot.segments) seg.disk_mass = 5e-4;
  all.robot.backbone.density = 8e4;
  c.push_back({"tip wrench, gravity, backbone weight", all});
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
    Eigen::MatrixXd own(n, n), plain(n, n), central(n, n);
    ASSERT_TRUE(P.jacobian(x, f, own));
    ASSERT_TRUE(bvp::finite_difference_jacobian(P, x, f, plain));
    Eigen::VectorXd xp = x, fp(n), fm(n);
    for (int c = 0; c < n; ++c) {
      const double h = 1e-5 * std::max(1.0, std::abs(x[c]));
      xp[c] = x[c] + h;
      ASSERT_TRUE(P.residual(xp, fp));
      xp[c] = x[c] - h;
      ASSERT_TRUE(P.residual(xp, fm));
      xp[c] = x[c];
      central.col(c) = (fp - fm) / (2.0 * h);
    }
    const double scale = plain.cwiseAbs().maxCoeff();
    ASSERT_GT(scale, 0.0);
    const double own_err = (own - central).cwiseAbs().maxCoeff() / scale;
    const double plain_err = (plain - central).cwiseAbs().maxCoeff() / scale;
    // Forward differences carry a relative error of about sqrt(eps) ~ 1e-8 (here 2e-8 .. 2e-7:
    // the structured one subtracts wrenches once more); a wrong rigid-motion term is 1e-3 .. 1.
    EXPECT_LT((own - plain).cwiseAbs().maxCoeff() / scale, std::max(1e-6, 2.0 * plain_err));
    EXPECT_LT(own_err, std::max(1e-6, 2.0 * plain_err)) << "plain differences: " << plain_err;
  }
}

}  // namespace

TEST(LumpedJacobian, CcsubStructuredDifferencesMatchPlainDifferences) {
  for (int n : {1, 3, 10})
    for (const Case& c : cases(n)) {
      SCOPED_TRACE(c.name + ", n = " + std::to_string(n));
      check<CcsubModel>(c);
    }
}

TEST(LumpedJacobian, PrbStructuredDifferencesMatchPlainDifferences) {
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

namespace {
// PRB or CCsub in the automatic formulation (structured Newton steps at every J).
std::unique_ptr<StaticModel> automatic_lumped(bool prb, const Scene& s) {
  if (prb) return std::make_unique<PrbModel>(s.robot, s.effects, LumpedFormulation::Automatic);
  return std::make_unique<CcsubModel>(s.robot, s.effects, LumpedFormulation::Automatic);
}
}  // namespace

// The structured Newton step (lumped_structured.cpp) solves J d = b with the factors of the
// recursive Jacobian: the same step as the dense Jacobian's LU, at few subsegments (J = 4) as at
// many (J = 40). Once its buffers are sized (first call per J), a Jacobian, a step setup and a
// step solve allocate nothing.
TEST(LumpedJacobian, StructuredStepSolvesTheDenseSystemAndAllocatesNothingOnceWarm) {
  for (int disks : {2, 20})
  for (bool prb : {false, true})
    for (bool tip : {false, true}) {
      SCOPED_TRACE(std::string(prb ? "prb" : "ccsub") + (tip ? ", tip wrench and gravity" : ", tendons") +
                   ", n = " + std::to_string(disks));
      Scene s = paper::scene(disks, 5, "ccsub");
      if (tip) {
        s.loads.tip_force = Vec3(0.2, -0.1, 0.05);
        s.loads.gravity = Vec3(0.0, -9.81, 0.0);
        s.robot.backbone.density = 8000.0;
      }
      const std::unique_ptr<StaticModel> model = automatic_lumped(prb, s);
      auto ws = model->make_workspace();
      const Solution sol = solve(*model, *ws, s.input(), s.solver);
      ASSERT_TRUE(sol.converged()) << sol.summary.message;
      EXPECT_EQ(sol.summary.linear_solver, "system");
      detail::LumpedProblem& P = *static_cast<detail::LumpedWorkspace&>(*ws).problem;
      P.bind(s.input());
      P.set_parameter(1.0);
      ASSERT_TRUE(P.has_newton_step());
      const int n = P.size();
      Eigen::VectorXd x = sol.unknowns.head(n);
      for (int i = 0; i < n; ++i) x[i] += 0.02 * (i % 3 ? -1.0 : 1.0);
      Eigen::VectorXd f(n), b(n), d(n);
      Eigen::MatrixXd J(n, n);
      for (int i = 0; i < n; ++i) b[i] = std::sin(1.0 + i);
      for (int round = 0; round < 2; ++round) {
        const long before = g_allocations.load();
        ASSERT_TRUE(P.residual(x, f));
        ASSERT_TRUE(P.jacobian(x, f, J));
        ASSERT_TRUE(P.setup_newton_step(x, f));
        d = b;
        ASSERT_TRUE(P.solve_newton_step(d));
        if (round == 1) {
          EXPECT_EQ(g_allocations.load() - before, 0);
        }
      }
      EXPECT_LT((J * d - b).norm(), 1e-9 * b.norm() * std::max(1.0, J.norm()));
    }
}

// Snap landings damp the recursive unknowns (set_damping: r + rate s (x - x_ref), s the unknowns'
// scales). In the reduced form (structured Newton steps, J = 40 here) the step must solve the
// damped Jacobian: the undamped one plus rate s on its diagonal. Before, the reduced form could
// not damp, and a snap of PRB or CCsub from 16 (30) loaded subsegments on had no damped landing.
TEST(LumpedJacobian, DampedStructuredStepSolvesTheDampedDenseSystem) {
  for (bool prb : {false, true}) {
    SCOPED_TRACE(prb ? "prb" : "ccsub");
    Scene s = paper::scene(20, 5, "ccsub");
    s.loads.tip_force = Vec3(0.2, -0.1, 0.05);
    const std::unique_ptr<StaticModel> model = automatic_lumped(prb, s);
    auto ws = model->make_workspace();
    const Solution sol = solve(*model, *ws, s.input(), s.solver);
    ASSERT_TRUE(sol.converged()) << sol.summary.message;
    detail::LumpedProblem& P = *static_cast<detail::LumpedWorkspace&>(*ws).problem;
    P.bind(s.input());
    P.set_parameter(1.0);
    ASSERT_TRUE(P.has_newton_step());
    const int n = P.size();
    const Eigen::VectorXd x_ref = sol.unknowns.head(n);
    Eigen::VectorXd x = x_ref;
    for (int i = 0; i < n; ++i) x[i] += 0.02 * (i % 3 ? -1.0 : 1.0);
    Eigen::VectorXd f0(n), f(n), scale(n), b(n), d(n);
    Eigen::MatrixXd J0(n, n), J(n, n);
    P.unknown_scale(scale);
    ASSERT_TRUE(P.residual(x, f0));
    ASSERT_TRUE(P.jacobian(x, f0, J0));
    const double rate = 3.0;
    ASSERT_TRUE(P.set_damping(x_ref, rate));
    ASSERT_TRUE(P.residual(x, f));
    EXPECT_LT((f - f0 - rate * scale.cwiseProduct(x - x_ref)).norm(), 1e-12 * f.norm());
    ASSERT_TRUE(P.jacobian(x, f, J));
    Eigen::MatrixXd expected = J0;
    expected.diagonal() += rate * scale;
    EXPECT_LT((J - expected).norm(), 1e-9 * J.norm());
    for (int i = 0; i < n; ++i) b[i] = std::sin(1.0 + i);
    ASSERT_TRUE(P.setup_newton_step(x, f));
    d = b;
    ASSERT_TRUE(P.solve_newton_step(d));
    EXPECT_LT((J * d - b).norm(), 1e-9 * b.norm() * std::max(1.0, J.norm()));
    // The undamped step differs: the damping is really in the factors.
    ASSERT_TRUE(P.set_damping(x_ref, 0.0));
    ASSERT_TRUE(P.residual(x, f));
    EXPECT_LT((f - f0).norm(), 1e-14 * f0.norm());
    ASSERT_TRUE(P.setup_newton_step(x, f));
    Eigen::VectorXd d0 = b;
    ASSERT_TRUE(P.solve_newton_step(d0));
    EXPECT_GT((d0 - d).norm(), 1e-3 * d.norm());
  }
}

// The lumped models' sufficient stability test (LumpedProblem::direct_stability: the structured
// Jacobian, Osborne-balanced, a block Cholesky factorisation of its symmetric part) against their
// eigen test (stability()) at the same answers: loaded robots (paper robot, n = 3, 5, 10, 20,
// tensions up to 1.5 T_M and tip forces up to 0.5 N as bench_loaded draws them), the straight
// column below Euler's load (stable) and past it (unstable: Newton from the straight shape).
// Every verdict agrees; where the sufficient test proves stability its margin bounds the eigen
// test's smallest real part from below, elsewhere the eigen test decides (its own margin).
TEST(LumpedStability, SufficientTestAgreesWithTheEigenTest) {
  std::vector<std::pair<std::string, Scene>> scenes;
  unsigned state = 12345u;
  const auto uniform = [&state]() {
    state = state * 1103515245u + 12345u;
    return static_cast<double>((state >> 8) & 0xffffu) / 65535.0;
  };
  for (int n : {3, 5, 10, 20}) {
    for (int c = 0; c < 3; ++c) {
      Scene s = paper::scene(n, 1 + 5 * c, "ccsub");
      const double t_max = paper::max_tension(s.robot);
      for (double& T : s.actuation.values) T = 1.5 * t_max * uniform() * (uniform() < 0.5 ? 0.0 : 1.0);
      s.loads.tip_force = 0.5 * Vec3(2.0 * uniform() - 1.0, 2.0 * uniform() - 1.0, 2.0 * uniform() - 1.0) / std::sqrt(3.0);
      scenes.emplace_back("n = " + std::to_string(n) + ", draw " + std::to_string(c), s);
    }
  }
  for (double factor : {0.8, 1.2, 1.5}) {
    Scene s = paper::scene(10, 1, "ccsub");
    s.effects.shear_extension = false;
    const double EI = s.robot.backbone.effective_stiffness().EI, L = s.robot.total_length();
    s.loads.tip_force = Vec3(0.0, 0.0, -factor * M_PI * M_PI * EI / (4.0 * L * L));
    scenes.emplace_back("column at " + std::to_string(factor) + " of Euler's load", s);
  }
  int unstable = 0, proven = 0, draws = 0;
  for (const bool prb : {false, true}) {
    for (const auto& [label, scene] : scenes) {
      const std::string name = std::string(prb ? "prb, " : "ccsub, ") + label;
      std::unique_ptr<LumpedModel> model;
      if (prb) model = std::make_unique<PrbModel>(scene.robot, scene.effects);
      else model = std::make_unique<CcsubModel>(scene.robot, scene.effects);
      auto ws = model->make_workspace();
      SolverOptions options = scene.solver;
      options.continuation = false;
      options.stability = StabilityCheck::Never;
      const Solution sol = solve(*model, *ws, scene.input(), options);
      if (!sol.converged()) continue;
      detail::LumpedProblem& P = *static_cast<detail::LumpedWorkspace&>(*ws).problem;
      const Eigen::VectorXd x = sol.unknowns.head(P.size());
      const Stability quick = P.direct_stability(x, 1.0);
      const Stability exact = P.stability(x, 1.0);
      EXPECT_EQ(quick.status, exact.status) << name << ": " << quick.method << " vs " << exact.method;
      if (exact.status == StabilityStatus::Unstable) ++unstable;
      if (label.rfind("n = ", 0) == 0) ++draws;
      if (quick.method.find("sufficient test") != std::string::npos) {
        ++proven;
        EXPECT_EQ(quick.status, StabilityStatus::Stable) << name;
        EXPECT_GT(quick.margin, 0.0) << name;
        EXPECT_LE(quick.margin, exact.margin * (1.0 + 1e-4)) << name << ": a lower bound";
      } else {
        EXPECT_NEAR(quick.margin, exact.margin, 1e-9 * std::abs(exact.margin)) << name << ": the eigen test's";
      }
    }
  }
  EXPECT_EQ(unstable, 4) << "the straight columns past Euler's load, in both models";
  EXPECT_GE(draws, 16) << "loaded draws solved directly";
  EXPECT_GE(4 * proven, 3 * draws) << "most loaded answers proven stable by the sufficient test";
}
