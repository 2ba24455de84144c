// The CC model against hand-computed arcs (paper Eq. 5, 8-10, 15, 20) to 1e-12.
#include <cmath>

#include <gtest/gtest.h>

#include "tdcr/core/error.hpp"
#include "tdcr/core/lie.hpp"
#include "tdcr/core/paper_robot.hpp"
#include "tdcr/models/cc.hpp"

using namespace tdcr;

namespace {

// Eq. 5 and 8: arc of curvature kappa, bending plane phi, at arc length s.
Frame arc(double kappa, double phi, double s) {
  Frame f;
  f.R = lie::rot_z(phi) * lie::rot_y(kappa * s) * lie::rot_z(-phi);
  if (kappa == 0.0) {
    f.p = Vec3(0, 0, s);
  } else {
    f.p = Vec3(std::cos(phi) / kappa * (1 - std::cos(kappa * s)), std::sin(phi) / kappa * (1 - std::cos(kappa * s)),
               std::sin(kappa * s) / kappa);
  }
  return f;
}

Scene one_segment(std::vector<TendonSpec> tendons, std::vector<double> displacements, int disks = 5) {
  Scene s;
  s.robot = paper::robot(disks);
  s.robot.segments.resize(1);
  s.robot.segments[0].tendons = std::move(tendons);
  s.actuation.kind = Actuation::Kind::Displacements;
  s.actuation.values = std::move(displacements);
  s.model = "cc";
  return s;
}

void expect_frame_near(const Frame& a, const Frame& b, double tol) {
  EXPECT_LT((a.p - b.p).norm(), tol) << a.p.transpose() << " vs " << b.p.transpose();
  EXPECT_LT((a.R - b.R).norm(), tol);
}

Solution solve_cc(const Scene& s) {
  const CcModel m(s.robot, s.effects);
  auto ws = m.make_workspace();
  return tdcr::solve(m, *ws, s.input(), s.solver);
}

}  // namespace

TEST(CcModel, StraightRobot) {
  const Solution sol = solve_cc(one_segment({{0, 0.008}, {0, -0.008}}, {0, 0}));
  ASSERT_TRUE(sol.converged());
  ASSERT_EQ(sol.disk_frames.size(), 6u);
  for (int j = 0; j <= 5; ++j) expect_frame_near(sol.disk_frames[j], arc(0, 0, 0.01 * j), 1e-15);
}

TEST(CcModel, PlanarBendTowardsPulledTendon) {
  // Tendon at +y pulled by 2 mm: kappa = d / (L r) = 5 1/m, bending towards +y (phi = 90 deg).
  const Solution sol = solve_cc(one_segment({{0, 0.008}, {0, -0.008}}, {0.002, -0.002}));
  ASSERT_TRUE(sol.converged());
  for (int j = 0; j <= 5; ++j) expect_frame_near(sol.disk_frames[j], arc(5.0, M_PI / 2, 0.01 * j), 1e-12);
  EXPECT_GT(sol.tip().p.y(), 0.0);
  EXPECT_NEAR(sol.tendon_displacements[0], 0.002, 1e-15);
  EXPECT_NEAR(sol.tendon_displacements[1], -0.002, 1e-15);
}

TEST(CcModel, ObliquePlaneWithThreeTendons) {
  // Three tendons at 120 deg (Eq. 15 with sigma_k = (k-1) 2 pi / 3): bend kappa = 4, phi = 30 deg.
  const double r = 0.008, L = 0.05, kappa = 4.0, phi = M_PI / 6;
  std::vector<TendonSpec> t;
  std::vector<double> d;
  for (int k = 0; k < 3; ++k) {
    const double sigma = k * 2 * M_PI / 3;
    t.push_back({r * std::cos(sigma), r * std::sin(sigma)});
    d.push_back(L * kappa * r * std::cos(sigma - phi));
  }
  const Solution sol = solve_cc(one_segment(t, d));
  for (int j = 0; j <= 5; ++j) expect_frame_near(sol.disk_frames[j], arc(kappa, phi, 0.01 * j), 1e-12);
}

TEST(CcModel, OverdeterminedInconsistentInputIsLeastSquares) {
  // Two antagonistic tendons pulled unequally: the least-squares curvature is their mean, and the
  // misfit is reported.
  const Solution sol = solve_cc(one_segment({{0, 0.008}, {0, -0.008}}, {0.002, -0.001}));
  expect_frame_near(sol.tip(), arc(0.0015 / (0.05 * 0.008), M_PI / 2, 0.05), 1e-12);
  EXPECT_NEAR(sol.summary.physical_residual, std::sqrt(2.0) * 0.0005, 1e-15);
}

TEST(CcModel, TwoSegmentsDisplacementsAtBase) {
  // Segment 1 bends kappa1 = 5 towards +y; segment 2 bends kappa2 = 3 towards -y relative to it.
  // A distal tendon at the base sees both segments' shortening (AtBase convention).
  Scene s = paper::scene(4, 1, "cc");
  s.actuation.kind = Actuation::Kind::Displacements;
  const double L = 0.05, r = 0.008, k1 = 5, k2 = -3;
  s.actuation.values = {L * k1 * r, -L * k1 * r, L * (k1 + k2) * r, -L * (k1 + k2) * r};
  const Solution sol = solve_cc(s);
  const Frame e1 = arc(k1, M_PI / 2, L);
  expect_frame_near(sol.disk_frames[4], e1, 1e-12);
  expect_frame_near(sol.tip(), e1 * arc(-k2, -M_PI / 2, L), 1e-12);
  // The per-segment convention of the paper's code gives the same shape from relative values.
  s.actuation.convention = Actuation::DisplacementConvention::PerSegment;
  s.actuation.values = {L * k1 * r, -L * k1 * r, L * k2 * r, -L * k2 * r};
  expect_frame_near(solve_cc(s).tip(), e1 * arc(-k2, -M_PI / 2, L), 1e-12);
}

TEST(CcModel, PartiallyConstrainedChords) {
  // Eq. 20: the chord path of a tendon at lever d over n subsegments is 2 n (1/kappa - d)
  // sin(kappa L / 2n). Feed those displacements; the arc must be recovered.
  const double r = 0.008, L = 0.05, kappa = 20.0;
  const int n = 3;
  auto chord_disp = [&](double d) { return L - 2 * n * (1 / kappa - d) * std::sin(kappa * L / (2 * n)); };
  Scene s = one_segment({{0, r}, {0, -r}}, {chord_disp(r), chord_disp(-r)}, n);
  s.effects.tendon_path = TendonPath::PartiallyConstrained;
  const Solution sol = solve_cc(s);
  expect_frame_near(sol.tip(), arc(kappa, M_PI / 2, L), 1e-12);
}

TEST(CcModel, TensionsGiveTheLoadFreeCosseratArc) {
  // u = T r / EI about -x for the +y tendon; with extension the arc is shortened by T / EA.
  Scene s = paper::scene(5, 2, "cc");
  const BackboneStiffness k = s.robot.backbone.effective_stiffness();
  const double T = s.actuation.values[0];
  const double kappa = T * 0.008 / k.EI, stretch = 1 - T / k.EA;
  const Solution sol = solve_cc(s);
  const Frame seg1 = lie::exp_se3(Vec3(-kappa, 0, 0) * 0.05, Vec3(0, 0, stretch) * 0.05);
  expect_frame_near(sol.disk_frames[5], seg1, 1e-14);
  expect_frame_near(sol.tip(), seg1 * Frame{Mat3::Identity(), Vec3(0, 0, 0.05)}, 1e-14);
  // The paper's theta_M: T_M on tendons 1 and 3 bends the tip by 90 deg (Eq. 55).
  Scene s2 = paper::scene(5, 6, "cc");  // T1 = T3 = T_M
  s2.effects.shear_extension = false;
  const Solution sol2 = solve_cc(s2);
  EXPECT_NEAR(lie::rotation_angle(sol2.tip().R, Mat3::Identity()), M_PI / 2, 1e-12);
}

TEST(CcModel, RefusesExternalLoadsNamingTheField) {
  auto field_of = [](const Scene& s) {
    try {
      solve_cc(s);
    } catch (const InputError& e) {
      return e.field() + " " + e.value();
    }
    return std::string("accepted");
  };
  Scene s = paper::scene(5, 2, "cc");
  s.loads.tip_force = Vec3(0, 0.5, 0);
  EXPECT_EQ(field_of(s), "loads.tip_force [0, 0.5, 0]");
  s.loads.tip_force.setZero();
  s.loads.tip_moment = Vec3(0.01, 0, 0);
  EXPECT_EQ(field_of(s), "loads.tip_moment [0.01, 0, 0]");
  s.loads.tip_moment.setZero();
  s.loads.gravity = Vec3(0, 0, -9.81);
  s.robot.backbone.density = 6450;
  EXPECT_EQ(field_of(s), "loads.gravity [0, 0, -9.81]");
}

TEST(CcModel, GeometryCheckSeesArcsPastTheTendonLimit) {
  // The driver skips the frame-by-frame geometry check when CC's curvature bound makes every
  // disk pair quiet (kappa r <= 1/2); past it the check runs. Displacement d bends a segment of
  // length L to kappa = d / (L r): kappa r = 0.4 is gentle, kappa r = 1.2 puts the inner tendon
  // beyond the backbone.
  const double L = 0.05, r = 0.008;
  for (double kr : {0.4, 1.2}) {
    SCOPED_TRACE(kr);
    const double d = kr * L;
    const Solution sol = solve_cc(one_segment({{0, r}, {0, -r}}, {d, -d}, 10));
    ASSERT_TRUE(sol.converged());
    bool crossing = false;
    for (const GeometryWarning& w : sol.geometry_warnings)
      if (w.what.find("cross the backbone") != std::string::npos) {
        crossing = true;
        EXPECT_NEAR(w.value, kr, 0.01) << w.what;
      }
    EXPECT_EQ(crossing, kr > 1.0);
  }
}
