// Contact of the shooting models VC and VCref with obstacles (docs/contact.md): the same physics
// as the lumped models' (tests/test_contact_lumped.cpp) on the same candidate pairs (backbone at
// each disk, disk rims).
// Untouched obstacles leave the free-space answer; the propped cantilever gives linear beam
// theory's reaction and the elastica's for a large load; symmetric supports carry equal forces;
// every load balances the base wrench; no answer penetrates; compliant contact tends to rigid; the
// contact Jacobian matches central differences (VCref); CCsub, PRB, VC and VCref agree as n grows
// on a robot bent against a wall and inside a curved lumen.
#include <gtest/gtest.h>

#include <Eigen/LU>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "contact_scenes.hpp"
#include "elastica_reference.hpp"
#include "tdcr/core/contact_geometry.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/core/paper_robot.hpp"
#include "tdcr/models/cosserat_rod.hpp"
#include "tdcr/models/model_registry.hpp"
#include "tdcr/models/static_model.hpp"
#include "tdcr/models/vcref.hpp"

using namespace tdcr;
using namespace contact_test;

namespace {

class ContactShooting : public ::testing::TestWithParam<std::string> {};

}  // namespace

// The propped cantilever of tests/test_contact_lumped.cpp (L = 0.1 m, tip force P = 2 mN, a 1 mm
// sphere touching the backbone at s = a = 0.05 m): R = P (3 L - a) / (2 a) = 2.5 P.
TEST_P(ContactShooting, ProppedCantileverReaction) {
  const double P = 0.002;
  double last = INFINITY;
  for (int n : {5, 10, 20}) {
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
    std::printf("%s n = %d: reaction %.8g N, beam theory %.8g N, relative error %.2e; %s\n", GetParam().c_str(), n,
                sol.contacts[0].force, R, error, sol.summary.brief_report().c_str());
    // The rod is exact between the disks, so the reaction does not change with n: with shear and
    // extension (the default effects) 7.5e-5 from beam theory's, as a Kirchhoff rod 1.5e-7 (the
    // 0.16 mm deflection's geometric nonlinearity).
    EXPECT_LT(error, 1e-3);
    if (std::isfinite(last)) {
      EXPECT_NEAR(error, last, 1e-5);
    }
    last = error;
    EXPECT_GE(smallest_gap(s, sol), -1e-9);
    // As a Kirchhoff rod (no shear, no extension): linear theory's own error remains.
    s.effects.shear_extension = false;
    const Solution k = run(s);
    ASSERT_TRUE(k.converged()) << k.summary.message;
    ASSERT_EQ(k.contacts.size(), 1u);
    const double kirchhoff = std::abs(k.contacts[0].force - R) / R;
    std::printf("%s n = %d, Kirchhoff rod: reaction %.8g N, relative error %.2e\n", GetParam().c_str(), n,
                k.contacts[0].force, kirchhoff);
    EXPECT_LT(kirchhoff, 1e-5);
  }
}

// The propped cantilever under P = 1 N (L^2 P / EI = 2.4; the free answer has passed the 1 mm
// support: the shapes between rest and it touch it, so the robot is loaded from rest with the
// contact) as a Kirchhoff rod: the reaction of
// the planar elastica (tests/elastica_reference.hpp), at every n (the rod is exact between disks).
TEST_P(ContactShooting, ProppedCantileverLargeDeflectionMatchesTheElastica) {
  const double P = 1.0, L = 0.1, a = 0.05, rho = 0.001;
  Scene s0 = robot_scene(GetParam(), 5);
  const double EI = s0.robot.backbone.effective_stiffness().EI, r_o = s0.robot.backbone.outer_radius;
  const double R = test::elastica_reaction(EI, L, a, P, r_o, rho);
  for (int n : {5, 10, 20}) {
    Scene s = robot_scene(GetParam(), n);
    s.effects.shear_extension = false;
    s.loads.tip_force = Vec3(P, 0, 0);
    s.environment.obstacles = {sphere(Vec3(r_o + rho, 0, a), rho)};
    const Solution sol = run(s);
    ASSERT_TRUE(sol.converged()) << "n = " << n << ": " << sol.summary.message;
    ASSERT_EQ(sol.contacts.size(), 1u);
    const double error = std::abs(sol.contacts[0].force - R) / R;
    std::printf("%s n = %d: reaction %.8g N, elastica %.8g N, relative error %.2e; %s\n", GetParam().c_str(), n,
                sol.contacts[0].force, R, error, sol.summary.brief_report().c_str());
    // Measured 6.6e-9 .. 4.4e-11 (VC), 7.2e-9 .. 6.6e-11 (VCref) at n = 5 .. 20: the RK4 meshes.
    EXPECT_LT(error, 1e-7);
    EXPECT_GE(smallest_gap(s, sol), -1e-9);
  }
}

// Contact is modelled with tension input only: displacement input with obstacles is refused,
// naming the field.
TEST_P(ContactShooting, DisplacementInputWithObstaclesIsRefused) {
  Scene s = robot_scene(GetParam(), 5);
  s.environment.obstacles = {plane(Vec3(0, 0.012, 0), Vec3(0, -1, 0))};
  s.actuation.kind = Actuation::Kind::Displacements;
  s.actuation.values = {0.001, 0, 0, 0};
  try {
    run(s);
    ADD_FAILURE() << "displacement input took obstacles";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "environment.obstacles") << e.what();
  }
}

// Global equilibrium: the rod's wrench at the base (its unknowns n_0, m_0) balances the tendon
// pulls (a tendon's forces on the disks add up to its pull along its first chord, through its
// base hole), the tip force and the contact forces. A robot bent against a tilted wall.
TEST_P(ContactShooting, BaseWrenchBalancesEveryLoad) {
  Scene s = robot_scene(GetParam(), 10);
  s.actuation.values = {1.0, 0, 0.5, 0};
  s.loads.tip_force = Vec3(0.003, 0, -0.01);
  for (Segment& g : s.robot.segments) g.disk_radius = 0.01;
  s.environment.obstacles = {plane(Vec3(0, 0.015, 0), Vec3(0, -1, -0.2))};
  const Solution sol = run(s);
  ASSERT_TRUE(sol.converged()) << sol.summary.message;
  ASSERT_FALSE(sol.contacts.empty());
  const TendonRouting routing = TendonRouting::from(s.robot);
  Vec3 f = s.loads.tip_force, m = sol.tip().p.cross(s.loads.tip_force);
  double fs = f.norm(), ms = m.norm();
  for (const Contact& c : sol.contacts) {
    f += c.force * c.normal;
    m += c.point.cross(c.force * c.normal);
    fs = std::max(fs, c.force), ms = std::max(ms, c.point.cross(c.force * c.normal).norm());
  }
  const Frame& f1 = sol.disk_frames[1];
  const Vec3 n0 = sol.backbone[0].n, m0 = sol.backbone[0].m;
  const cosserat::Section S = cosserat::Section::from(s);
  const Vec3 u0 = S.curvature(Mat3::Identity(), m0), v0 = S.strain(Mat3::Identity(), n0);
  for (const RoutedTendon& t : routing.tendons) {
    const double T = s.actuation.values[t.index];
    // VCref: the chord to the first disk; VC: the tendon's tangent at the base, v + u x r.
    const Vec3 h0 = t.r, h1 = f1.p + f1.R * t.r;
    const Vec3 pull = T * (GetParam() == "vc" ? -(v0 + u0.cross(t.r)).normalized() : (h0 - h1).normalized());
    f += pull;
    m += h0.cross(pull);
    fs = std::max(fs, T), ms = std::max(ms, h0.cross(pull).norm());
  }
  std::printf("%s: force balance %.2e of %.3g N, moment balance %.2e of %.3g N m\n", GetParam().c_str(), (f - n0).norm(), fs,
              (m - m0).norm(), ms);
  EXPECT_LT((f - n0).norm(), 1e-8 * fs);
  EXPECT_LT((m - m0).norm(), 1e-8 * ms);
}

// The contact system's Jacobian (the shooting's with the contact forces in the disk equilibria,
// the exact force columns, the complementarity rows) against central differences of the whole
// contact residual, at answers with contacts at inner disks and at the tip, and off them.
TEST(ContactVcref, JacobianMatchesCentralDifferences) {
  for (int scene = 0; scene < 2; ++scene) {
    Scene s = robot_scene("vcref", 5);
    if (scene == 0) {  // two spheres holding the backbone at s = 0.05 m
      s.loads.tip_force = Vec3(0.004, 0, 0);
      const double d = s.robot.backbone.outer_radius + 0.001;
      s.environment.obstacles = {sphere(Vec3(d * std::sqrt(0.5), d * std::sqrt(0.5), 0.05), 0.001),
                                 sphere(Vec3(d * std::sqrt(0.5), -d * std::sqrt(0.5), 0.05), 0.001)};
    } else {  // a tilted wall under the tendons: rims, the tip's among them
      s.actuation.values = {1.5, 0, 0.8, 0};
      for (Segment& g : s.robot.segments) g.disk_radius = 0.01;
      s.environment.obstacles = {plane(Vec3(0, 0.02, 0), Vec3(0.1, -1, -0.1))};
    }
    const Solution sol = run(s);
    ASSERT_TRUE(sol.converged()) << sol.summary.message;
    ASSERT_FALSE(sol.contacts.empty());
    bool tip = false;
    for (const Contact& c : sol.contacts) tip = tip || c.disk_index == 10;
    if (scene == 1) {
      EXPECT_TRUE(tip);
    }
    const VcrefModel model(s.robot, s.effects);
    auto ws = model.make_workspace();
    const Solution at = tdcr::solve(model, *ws, s.input(), s.solver);
    ASSERT_TRUE(at.converged()) << at.summary.message;
    for (double offset : {0.0, 1e-3}) {
      const bvp::JacobianCheck check = model.check_jacobian(*ws, s.input(), s.solver, &at, offset);
      ASSERT_TRUE(check.evaluated);
      ASSERT_EQ(check.analytic.rows(), at.unknowns.size());
      // Per row, relative to the row's largest entry: the shooting rows (the contact forces in
      // the disk equilibria) and the complementarity rows. The latter's reference is the less
      // accurate: its step (6e-7 m, 1.2e-3 of r_o) meets Fischer-Burmeister's curvature
      // 1 / sqrt(a^2 + b^2) at a closed contact with b = f / F_s ~ 0.01 (third derivative ~ 1e4),
      // an error of about 1e-3; the system takes phi's derivatives in closed form and only the
      // gap by differences (1e-7 m). A wrong term (a missing moment arm, a normal not turned, a
      // force column of the wrong disk) is 1e-2 .. 1 of its row.
      const int rows = static_cast<int>(check.analytic.rows()), nfree = rows - static_cast<int>(at.contacts.size());
      double worst[2] = {0.0, 0.0};
      int wr[2] = {-1, -1}, wc[2] = {-1, -1};
      for (int i = 0; i < rows; ++i) {
        const double rmax = std::max(check.analytic.row(i).cwiseAbs().maxCoeff(), check.numeric.row(i).cwiseAbs().maxCoeff());
        if (rmax == 0.0) continue;
        Eigen::Index c = 0;
        const double e = (check.analytic.row(i) - check.numeric.row(i)).cwiseAbs().maxCoeff(&c) / rmax;
        const int g = i < nfree ? 0 : 1;
        if (e > worst[g]) worst[g] = e, wr[g] = i, wc[g] = static_cast<int>(c);
      }
      for (int g = 0; g < 2; ++g)
        std::printf("scene %d offset %g: %d unknowns, %zu contacts, %s rows: largest error per row %.2e (row %d, "
                    "column %d)\n", scene, offset, rows, at.contacts.size(), g == 0 ? "shooting" : "contact", worst[g],
                    wr[g], wc[g]);
      EXPECT_LT(worst[0], 1e-5);
      EXPECT_LT(worst[1], 1e-3);
      // The force columns alone (exact) against the differences (linear in b: exact too).
      const double cs = check.numeric.rightCols(rows - nfree).cwiseAbs().maxCoeff();
      EXPECT_LT((check.analytic - check.numeric).rightCols(rows - nfree).topRows(nfree).cwiseAbs().maxCoeff(), 1e-7 * cs);
    }
  }
}

// CCsub, PRB, VC and VCref tend to one answer as the disks grow: the scenes of
// tests/test_contact_lumped.cpp (a robot bent against a wall; an unactuated robot inside a curved
// lumen, an arc of radius 1 m and inner radius 3 mm). VCref as a Kirchhoff rod (no shear or
// extension, as the lumped models): with them its tip differs from PRB's by 1.5e-6 m on the wall
// at every n.
TEST(ContactShootingAgreement, FourModelsAgreeOnAWallAndInALumen) {
  for (const bool in_lumen : {false, true}) {
    double last = INFINITY, last_vc = INFINITY;
    for (int n : {5, 10, 20}) {
      const char* models[4] = {"ccsub", "prb", "vc", "vcref"};
      Vec3 tip[4], free_tip[4];
      for (int m = 0; m < 4; ++m) {
        Scene s = robot_scene(models[m], n);
        s.effects.shear_extension = false;
        if (in_lumen) {
          s.environment.obstacles = {curved_lumen(0.15)};
        } else {
          s.actuation.values = {1.5, 0, 0.8, 0};
          s.environment.obstacles = {plane(Vec3(0, 0.012, 0), Vec3(0, -1, 0))};
        }
        const Solution sol = run(s);
        ASSERT_TRUE(sol.converged()) << s.model << " n = " << n << ": " << sol.summary.message;
        ASSERT_FALSE(sol.contacts.empty());
        EXPECT_GE(smallest_gap(s, sol), -1e-9);
        tip[m] = sol.tip().p;
        s.environment.obstacles.clear();
        const Solution free = run(s);
        ASSERT_TRUE(free.converged()) << free.summary.message;
        free_tip[m] = free.tip().p;
      }
      const double d_cc = (tip[0] - tip[3]).norm(), d_prb = (tip[1] - tip[3]).norm(), d_vc = (tip[2] - tip[3]).norm();
      const double free_prb = (free_tip[1] - free_tip[3]).norm(), free_vc = (free_tip[2] - free_tip[3]).norm();
      std::printf("%s n = %d: |tip - tip VCref| CCsub %.3e m, PRB %.3e m (free space %.3e m), VC %.3e m (free space "
                  "%.3e m)\n", in_lumen ? "lumen" : "wall", n, d_cc, d_prb, free_prb, d_vc, free_vc);
      EXPECT_LT(d_cc, last);
      last = d_cc;
      // PRB: 3.7e-8 .. 4.9e-8 m on the wall at every n (its springs' calibrated factors), 3e-10 ..
      // 5e-10 m in the lumen. VC: the distributed tendon loads tend to VCref's disk loads (wall:
      // 5.3e-8, 1.3e-8, 3.2e-9 m); in the lumen no tendon pulls and the two rods are one model.
      EXPECT_LT(d_prb, in_lumen ? 1e-9 : 1e-7);
      if (in_lumen) {
        EXPECT_LT(d_vc, 1e-12);
      } else {
        EXPECT_LT(d_vc, last_vc);
        last_vc = d_vc;
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Models, ContactShooting, ::testing::Values("vc", "vcref"));
