// Contact of CCsub and PRB with obstacles (docs/contact.md): the physics their answers must
// show. Untouched obstacles leave the free-space answer; a cantilever on a point support gives
// linear beam theory's propped-cantilever reaction as n grows; symmetric supports carry equal
// forces; the moment of every load about the base balances the backbone's moment there; no
// answer penetrates; compliant contact tends to rigid as the stiffness grows; CCsub and PRB agree
// as n grows on a robot bent against a wall and inside a curved lumen.
#include <gtest/gtest.h>

#include <Eigen/LU>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "contact_scenes.hpp"
#include "elastica_reference.hpp"
#include "lumped/lumped_problem.hpp"
#include "tdcr/core/contact_geometry.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/core/paper_robot.hpp"
#include "tdcr/bvp/residual_system.hpp"
#include "tdcr/models/model_registry.hpp"
#include "tdcr/models/static_model.hpp"

using namespace tdcr;
using namespace contact_test;

namespace {

class ContactLumped : public ::testing::TestWithParam<std::string> {};

}  // namespace

// A straight cantilever (length L = 0.1 m) with a tip force P across it, on a rigid point
// support (a 1 mm sphere touching the backbone, gap 0) at the disk at s = a: linear beam theory
// gives the reaction R = P (3 L - a) / (2 a) (support at a, load at the overhang's end).
// The lumped models tend to it as the disks grow.
TEST_P(ContactLumped, ProppedCantileverReaction) {
  const double P = 0.002;  // tip deflection without the support 0.16 mm: linear
  double last = INFINITY;
  for (int n : {5, 10, 20, 40}) {
    Scene s = robot_scene(GetParam(), n);
    s.loads.tip_force = Vec3(P, 0, 0);
    const double a = 0.05, L = 0.1, r = s.robot.backbone.outer_radius, rho = 0.001;
    s.environment.obstacles = {sphere(Vec3(r + rho, 0, a), rho)};
    const Solution sol = run(s);
    ASSERT_TRUE(sol.converged()) << sol.summary.message;
    ASSERT_EQ(sol.contacts.size(), 1u);
    EXPECT_NEAR(sol.contacts[0].s, a, 1e-15);
    const double R = P * (3 * L - a) / (2 * a);
    const double error = std::abs(sol.contacts[0].force - R) / R;
    std::printf("%s n = %d: reaction %.6g N, beam theory %.6g N, relative error %.2e\n", GetParam().c_str(), n,
                sol.contacts[0].force, R, error);
    EXPECT_LT(error, last);
    last = error;
    EXPECT_GE(smallest_gap(s, sol), -1e-9);
  }
  // Measured at n = 40: CCsub 1.1e-2 (about 0.44 / n: its arcs take the moment at their base
  // disk), PRB 1.6e-5.
  EXPECT_LT(last, GetParam() == "ccsub" ? 0.015 : 1e-4);
}

// Global equilibrium (CCsub: the backbone's moment at the base is EI / l_1 times the first
// subsegment's unknowns, Eq. 43): the moment about the base of the tendon pulls, the tip force
// and the contact forces balances it, to the solver's tolerance. A robot bent by its tendons
// against a wall, with a tip force.
TEST(ContactLumpedEquilibrium, MomentAboutTheBaseBalances) {
  Scene s = robot_scene("ccsub", 10);
  s.actuation.values = {1.0, 0, 0.5, 0};
  s.loads.tip_force = Vec3(0.003, 0, -0.01);
  for (Segment& g : s.robot.segments) g.disk_radius = 0.01;
  s.environment.obstacles = {plane(Vec3(0, 0.015, 0), Vec3(0, -1, -0.2))};
  const Solution sol = run(s);
  ASSERT_TRUE(sol.converged()) << sol.summary.message;
  ASSERT_FALSE(sol.contacts.empty());
  const TendonRouting routing = TendonRouting::from(s.robot);
  Vec3 m = sol.tip().p.cross(s.loads.tip_force);
  double scale = (sol.tip().p.cross(s.loads.tip_force)).norm();
  for (const Contact& c : sol.contacts) {
    m += c.point.cross(c.force * c.normal);
    scale = std::max(scale, (c.point.cross(c.force * c.normal)).norm());
  }
  // A tendon's forces on the disks beyond the base add up to its pull along its first chord
  // (the chords' pairs of forces have one line of action each), through its base hole.
  const Frame& f1 = sol.disk_frames[1];
  for (const RoutedTendon& t : routing.tendons) {
    const double T = s.actuation.values[t.index];
    const Vec3 h0 = t.r, h1 = f1.p + f1.R * t.r;
    m += h0.cross(T * (h0 - h1).normalized());
    scale = std::max(scale, (h0.cross(T * (h0 - h1).normalized())).norm());
  }
  const BackboneStiffness k = s.robot.backbone.effective_stiffness();
  const double l1 = routing.disk_s[1];
  const Eigen::Vector3d x = sol.unknowns.head<3>();
  const Vec3 z = f1.R.col(2);
  const Vec3 backbone = (k.EI / l1) * (Vec3(x[0], x[1], 0.0) + (k.GJ / k.EI) * x[2] * z);
  EXPECT_LT((m - backbone).norm(), 1e-8 * scale) << "moment of the loads " << m.transpose() << ", backbone "
                                                  << backbone.transpose();
}

// CCsub and PRB tend to one answer as the disks grow: a robot bent against a wall, and an
// unactuated robot inside a curved lumen (a circular arc of radius 1 m, inner radius 3 mm: the
// straight robot would leave it by 2 mm at its tip).
TEST(ContactLumpedAgreement, CcsubAndPrbConvergeOnAWallAndInALumen) {
  for (const bool in_lumen : {false, true}) {
    double last = INFINITY;
    for (int n : {5, 10, 20}) {
      Vec3 tip[2];
      for (int m = 0; m < 2; ++m) {
        Scene s = robot_scene(m == 0 ? "ccsub" : "prb", n);
        if (in_lumen) {
          s.environment.obstacles = {curved_lumen(0.15)};  // 0.15 m of the 1 m radius arc
        } else {
          s.actuation.values = {1.5, 0, 0.8, 0};
          s.environment.obstacles = {plane(Vec3(0, 0.012, 0), Vec3(0, -1, 0))};
        }
        const Solution sol = run(s);
        ASSERT_TRUE(sol.converged()) << s.model << " n = " << n << ": " << sol.summary.message;
        ASSERT_FALSE(sol.contacts.empty());
        EXPECT_GE(smallest_gap(s, sol), -1e-9);
        tip[m] = sol.tip().p;
      }
      const double d = (tip[0] - tip[1]).norm();
      std::printf("%s n = %d: |tip CCsub - tip PRB| = %.3e m\n", in_lumen ? "lumen" : "wall", n, d);
      EXPECT_LT(d, last);
      last = d;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Models, ContactLumped, ::testing::Values("ccsub", "prb"));

// A tip force of 1.5 N into a wall (load parameter 3.5: the free answer follows the loading path
// from rest and ends 40 mm beyond the wall, its tip rim deep inside): the contact solve from it
// converges (PRB through compliant contact of rising stiffness), without penetration, the tip
// rim on the wall holding most of the force; CCsub and PRB agree to 1e-5 m.
TEST(ContactLumpedAgreement, LargeTipForceIntoAWall) {
  Vec3 tip[2];
  for (int m = 0; m < 2; ++m) {
    Scene s = robot_scene(m == 0 ? "ccsub" : "prb", 10);
    for (Segment& g : s.robot.segments) g.disk_radius = 0.01;
    s.loads.tip_force = Vec3(0, 1.5, 0);
    s.environment.obstacles = {plane(Vec3(0, 0.025, 0), Vec3(0, -1, 0))};
    const Solution sol = run(s);
    ASSERT_TRUE(sol.converged()) << s.model << ": " << sol.summary.message;
    EXPECT_GE(smallest_gap(s, sol), -1e-9);
    ASSERT_FALSE(sol.contacts.empty());
    double fy = 0.0;
    for (const Contact& c : sol.contacts) fy += c.force * c.normal.y();
    EXPECT_LT(fy, -1.0);  // the wall takes most of the 1.5 N
    EXPECT_GT(fy, -1.5);
    tip[m] = sol.tip().p;
  }
  EXPECT_LT((tip[0] - tip[1]).norm(), 1e-5);
}

// Models without contact refuse obstacles, naming the field; so does displacement input (tension
// input only so far); "auto" picks a model with contact (VC and VCref take obstacles too:
// tests/test_contact_vcref.cpp).
TEST(ContactLumpedInput, WhoTakesObstacles) {
  Scene s = robot_scene("vc", 5);
  s.actuation.values = {1.0, 0, 0, 0};
  s.environment.obstacles = {plane(Vec3(0, 0.012, 0), Vec3(0, -1, 0))};
  for (const char* model : {"cc"}) {
    s.model = model;
    try {
      run(s);
      ADD_FAILURE() << model << " took obstacles";
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), "environment.obstacles") << e.what();
    }
  }
  s.model = "auto";
  const Solution a = run(s);
  EXPECT_TRUE(a.model == "ccsub" || a.model == "prb" || a.model == "vc" || a.model == "vcref") << a.model;
  EXPECT_TRUE(a.converged()) << a.summary.message;
  s.model = "ccsub";
  s.actuation.kind = Actuation::Kind::Displacements;
  s.actuation.values = {0.001, 0, 0, 0};
  try {
    run(s);
    ADD_FAILURE() << "displacement input took obstacles";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "environment.obstacles") << e.what();
  }
}


// The propped cantilever under a large tip force (P = 1 N: L^2 P / EI = 2.4, where linear
// theory's 2.5 P is 3 % off) on the 1 mm support: the free robot's answer has passed the support
// entirely, so the robot is loaded from rest with the contact; the reaction tends to the
// elastica's as the disks grow.
TEST_P(ContactLumped, ProppedCantileverLargeDeflectionMatchesTheElastica) {
  const double P = 1.0, L = 0.1, a = 0.05, rho = 0.001;
  Scene s0 = robot_scene(GetParam(), 5);
  const double EI = s0.robot.backbone.effective_stiffness().EI, r_o = s0.robot.backbone.outer_radius;
  const double R = test::elastica_reaction(EI, L, a, P, r_o, rho);
  std::printf("elastica reaction %.6g N (linear theory %.6g N)\n", R, 2.5 * P);
  const double linear_error = std::abs(R - 2.5 * P) / R;
  EXPECT_GT(linear_error, 0.02);  // a case linear theory does not answer
  double last = INFINITY;
  for (int n : {5, 10, 20, 40}) {
    Scene s = robot_scene(GetParam(), n);
    s.loads.tip_force = Vec3(P, 0, 0);
    s.environment.obstacles = {sphere(Vec3(r_o + rho, 0, a), rho)};
    const Solution sol = run(s);
    ASSERT_TRUE(sol.converged()) << "n = " << n << ": " << sol.summary.message;
    ASSERT_EQ(sol.contacts.size(), 1u);
    const double error = std::abs(sol.contacts[0].force - R) / R;
    std::printf("%s n = %d: reaction %.6g N, relative error to the elastica %.2e\n", GetParam().c_str(), n,
                sol.contacts[0].force, error);
    // CCsub: about 0.44 / n. PRB: 4.1e-4 at n = 5, then within 1e-4 (7.5e-5, 2.0e-5, 4.8e-5 at
    // n = 10, 20, 40: PRB's own; VC and VCref match the elastica to 4.4e-11 and 6.6e-11 at n = 20,
    // tests/test_contact_shooting.cpp).
    if (GetParam() == "ccsub") EXPECT_LT(error, last);
    else EXPECT_LT(error, n >= 10 ? 1e-4 : 1e-3);
    last = error;
  }
  EXPECT_LT(last, GetParam() == "ccsub" ? 0.015 : 0.01 * linear_error);
}

// The contact system's own Jacobian (LumpedProblem::jacobian with candidates: the structured
// differences with the contact forces in the loads, their columns and the complementarity rows,
// lumped_contact_jacobian.cpp) against central differences of the whole contact residual, at an
// answer with 2+ contacts and off it: two spheres holding the backbone (curved obstacles: the
// normals turn with the contact points) under a tip force, and a robot pressing a disk rim
// on a tilted wall under gravity (a rim point turning in their disks, external loads).
TEST_P(ContactLumped, ContactJacobianMatchesDifferences) {
  std::vector<Scene> scenes;
  {
    Scene s = robot_scene(GetParam(), 20);
    s.loads.tip_force = Vec3(0.004, 0.001, 0);
    const double d = s.robot.backbone.outer_radius + 0.001;
    s.environment.obstacles = {sphere(Vec3(d * std::sqrt(0.5), d * std::sqrt(0.5), 0.05), 0.001),
                               sphere(Vec3(d * std::sqrt(0.5), -d * std::sqrt(0.5), 0.05), 0.001)};
    scenes.push_back(s);
  }
  {
    Scene s = robot_scene(GetParam(), 20);
    s.actuation.values = {1.5, 0, 0.8, 0};
    s.loads.tip_force = Vec3(0.01, 0, -0.01);
    s.loads.gravity = Vec3(0, 0, -9.81);
    for (Segment& g : s.robot.segments) g.disk_radius = 0.01, g.disk_mass = 2e-4;
    s.environment.obstacles = {plane(Vec3(0, 0.02, 0), Vec3(0, -1, -0.3))};
    scenes.push_back(s);
  }
  for (std::size_t sc = 0; sc < scenes.size(); ++sc) {
    SCOPED_TRACE(sc);
    const Scene& s = scenes[sc];
    const auto model = make_model(parse_model_kind(GetParam()), s);
    auto ws = model->make_workspace();
    const Solution sol = solve(*model, *ws, s.input(), s.solver);
    ASSERT_TRUE(sol.converged()) << sol.summary.message;
    ASSERT_GE(sol.contacts.size(), sc == 0 ? 2u : 1u) << sol.summary.message;
    detail::LumpedProblem& P = *static_cast<detail::LumpedWorkspace&>(*ws).problem;
    P.bind(s.input());
    P.set_parameter(1.0);
    Eigen::VectorXd y0;
    ASSERT_TRUE(P.warm_guess(sol, y0));  // the answer's contacts become the candidates
    ASSERT_TRUE(P.has_jacobian());
    const int n = P.size();
    ASSERT_EQ(n, static_cast<int>(y0.size()));
    ASSERT_EQ(n, static_cast<int>(sol.unknowns.size() + sol.contacts.size()));
    for (double offset : {0.0, 0.01, -0.03}) {
      SCOPED_TRACE(offset);
      Eigen::VectorXd y = y0;
      for (int i = 0; i < n; ++i) y[i] += offset * (i % 2 ? -1.0 : 1.0) * (1.0 + 0.1 * (i % 7));
      Eigen::VectorXd f(n), fp(n), fm(n);
      ASSERT_TRUE(P.residual(y, f));
      Eigen::MatrixXd own(n, n), central(n, n);
      ASSERT_TRUE(P.jacobian(y, f, own));
      Eigen::VectorXd yp = y;
      for (int c = 0; c < n; ++c) {
        const double h = 1e-7 * std::max(1.0, std::abs(y[c]));
        yp[c] = y[c] + h;
        ASSERT_TRUE(P.residual(yp, fp));
        yp[c] = y[c] - h;
        ASSERT_TRUE(P.residual(yp, fm));
        yp[c] = y[c];
        central.col(c) = (fp - fm) / (2.0 * h);
      }
      Eigen::MatrixXd plain(n, n);  // KINSOL's forward differences (same increments as own)
      ASSERT_TRUE(bvp::finite_difference_jacobian(P, y, f, plain));
      const double scale = central.cwiseAbs().maxCoeff();
      ASSERT_GT(scale, 0.0);
      Eigen::Index r = 0, c = 0;
      const double err = (own - plain).cwiseAbs().maxCoeff() / scale;
      const double plain_err = (plain - central).cwiseAbs().maxCoeff() / scale;
      const double own_err = (own - central).cwiseAbs().maxCoeff(&r, &c) / scale;
      std::printf("%s scene %zu offset %.2f: %d unknowns, %d contacts: |own - forward| %.2e, |own - central| %.2e, "
                  "|forward - central| %.2e (of the largest entry)\n",
                  GetParam().c_str(), sc, offset, n, static_cast<int>(sol.contacts.size()), err, own_err, plain_err);
      // Central differences (h = 1e-7: Fischer-Burmeister's curvature 1 / b at a closed contact
      // makes larger steps inaccurate) carry about 1e-8 of the largest entry. The structured
      // differences take KINSOL's forward increments (PRB's bending-plane angle: 1.5e-4), so the
      // x columns are as accurate as forward differences of the free-space residual (1e-6 of the
      // largest entry, or twice the forward differences' error of the whole contact residual,
      // tests/test_lumped_jacobian.cpp); the force columns are exact. A wrong contact term (a
      // missing moment arm, a normal not turned) is 1e-3 .. 1 of the largest entry.
      EXPECT_LT(own_err, std::max(1e-6, 2.0 * plain_err))
          << "at row " << r << ", column " << c << " of " << n << ": own " << own(r, c) << ", forward " << plain(r, c)
          << ", central " << central(r, c);
      // The contact columns and rows alone, relative to their own size.
      const int nc = static_cast<int>(sol.contacts.size()), nx = n - nc;
      const double cs = central.rightCols(nc).cwiseAbs().maxCoeff(), rs = central.bottomRows(nc).cwiseAbs().maxCoeff();
      EXPECT_LT((own - central).rightCols(nc).cwiseAbs().maxCoeff() / cs, 1e-6);
      const double rows_plain = (plain - central).bottomRows(nc).leftCols(nx).cwiseAbs().maxCoeff() / rs;
      EXPECT_LT((own - central).bottomRows(nc).leftCols(nx).cwiseAbs().maxCoeff() / rs, std::max(1e-6, 2.0 * rows_plain));
      // The structured Newton step (block-banded, KLU) solves the same Jacobian.
      ASSERT_TRUE(P.has_newton_step());
      ASSERT_TRUE(P.residual(y, f));
      ASSERT_TRUE(P.setup_newton_step(y, f));
      Eigen::VectorXd step = -f;
      ASSERT_TRUE(P.solve_newton_step(step));
      ASSERT_TRUE(P.jacobian(y, f, own));
      const Eigen::VectorXd dense = own.partialPivLu().solve(-f);
      EXPECT_LT((step - dense).norm(), 1e-8 * dense.norm()) << "structured " << step.norm() << ", dense " << dense.norm();
    }
  }
}
