// Tests of the VCref model (multiple shooting, Cosserat rod per subsegment, discrete disk forces).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tdcr/core/error.hpp"
#include "tdcr/core/lie.hpp"
#include "tdcr/core/metrics.hpp"
#include "tdcr/core/paper_robot.hpp"
#include "tdcr/models/tendon_physics.hpp"
#include "tdcr/models/vcref.hpp"
#include "tdcr/models/static_model.hpp"
#include "fixed_mesh_settings.hpp"

namespace tdcr {
namespace {

Solution run(const Scene& scene, const Solution* warm = nullptr) {
  VcrefModel model(scene.robot, scene.effects);
  auto ws = model.make_workspace();
  return tdcr::solve(model, *ws, scene.input(), scene.solver, warm);
}

double angle_deg(const Mat3& A, const Mat3& B) { return lie::rotation_angle(A, B) * 180.0 / M_PI; }

// Three segments of 6, 7, 8 disks with three tendons each (tendons 3i..3i+2 end at segment i+1).
Scene three_segments() {
  Scene s;
  s.model = "vcref";
  s.robot.backbone.density = 6450.0;
  const double r = 0.006;
  for (int i = 0; i < 3; ++i) {
    Segment seg;
    seg.length = 0.04 - 0.005 * i;
    seg.disks = 6 + i;
    seg.disk_mass = 0.001 * (i + 1);
    for (int k = 0; k < 3; ++k) {
      const double a = 2 * M_PI * k / 3 + 0.4 * i;
      seg.tendons.push_back(TendonSpec{r * std::cos(a), r * std::sin(a)});
    }
    s.robot.segments.push_back(seg);
  }
  return s;
}

// 1. Zero tension: the straight robot, exactly (the straight guess is the solution), for one
// disk per segment and for 500 disks per segment.
TEST(Vcref, ZeroTensionIsStraight) {
  for (int n : {1, 500}) {
    Scene s = paper::scene(n, 1);
    const Solution sol = run(s);
    ASSERT_TRUE(sol.converged()) << n << ": " << sol.summary.message;
    ASSERT_EQ(static_cast<int>(sol.disk_frames.size()), 2 * n + 1);
    EXPECT_EQ(sol.summary.unknowns, 6 + 12 * (2 * n - 1));
    for (std::size_t j = 0; j < sol.disk_frames.size(); ++j) {
      EXPECT_NEAR((sol.disk_frames[j].p - Vec3(0, 0, 0.1 * j / (2.0 * n))).norm(), 0.0, 1e-14);
      EXPECT_NEAR(angle_deg(sol.disk_frames[j].R, Mat3::Identity()), 0.0, 1e-12);
    }
    for (double d : sol.tendon_displacements) EXPECT_NEAR(d, 0.0, 1e-15);
    EXPECT_EQ(sol.summary.linear_solver, n == 1 ? "dense" : "klu");
  }
}

// 2. Pure tip moment, no tension: every subsegment is a circular arc of curvature M / EI,
// exactly (the Cosserat rod with n = 0 has constant m and u), so every disk frame equals
// exp_se3(u s, e_z s). Shear/extension does not enter (n = 0). RK4 integrates the arc with an
// error O(h^4); 16 steps per 25 mm interval at 90 deg of bending give well below 1e-9 m.
TEST(Vcref, PureTipMomentIsCircularArc) {
  Scene s = paper::scene(2, 1);
  const double EI = s.robot.backbone.effective_stiffness().EI;
  const double kappa = (M_PI / 2) / 0.1;  // 90 deg over the robot
  s.loads.tip_moment = Vec3(EI * kappa, 0.0, 0.0);
  s.solver.integrator = IntegratorKind::FixedStepRK4;
  s.solver.rk4_steps = 16;
  const Solution sol = run(s);
  ASSERT_TRUE(sol.converged()) << sol.summary.message;
  const Vec3 u(kappa, 0.0, 0.0);
  for (std::size_t j = 0; j < sol.disk_frames.size(); ++j) {
    const double sj = 0.025 * j;
    const Frame ref = lie::exp_se3(u * sj, Vec3::UnitZ() * sj);
    EXPECT_LT((sol.disk_frames[j].p - ref.p).norm(), 1e-9) << j;
    EXPECT_LT(lie::rotation_angle(sol.disk_frames[j].R, ref.R), 1e-8) << j;
  }
  // Bending about +x moves the tip towards -y.
  EXPECT_LT(sol.tip().p.y(), -0.05);
  // Internal moment equals the tip moment everywhere; internal force vanishes.
  for (const BackboneSample& b : sol.backbone) {
    EXPECT_NEAR((b.m - s.loads.tip_moment).norm(), 0.0, 1e-12);
    EXPECT_NEAR(b.n.norm(), 0.0, 1e-12);
  }
}


Frame tip_of(const Scene& s) {
  const Solution sol = run(s);
  EXPECT_TRUE(sol.converged()) << sol.summary.message;
  return sol.tip();
}

// 3. Discretisation convergence: as the number of disks grows, the discrete tendon forces
// approach the continuous load of the fully constrained tendon (VC), so the tip difference to VC
// (paper Fig. 10) decreases monotonically over n = 1, 2, 5, 10, 20 (configuration 2, T1 = T_M).
// Published figures: 9.12 % at n = 1 and 0.16 % at n = 10 (mean over configurations).
TEST(Vcref, ConvergesTowardsVcAsDisksIncrease) {
  double prev = 1e9;
  for (int n : {1, 2, 5, 10, 20}) {
    Scene s = paper::scene(n, 2);
    s.solver.integrator = IntegratorKind::FixedStepRK4;
    s.solver.rk4_steps = 16;
    const Frame vcref = tip_of(s);
    s.model = "vc";
    const Solution vc = tdcr::solve(s);
    ASSERT_TRUE(vc.converged()) << vc.summary.message;
    const double e = (vcref.p - vc.tip().p).norm();
    RecordProperty("tip_difference_to_vc_n" + std::to_string(n), std::to_string(e));
    std::printf("n = %2d: |p_VCref - p_VC| = %.4e m (%.3f %% of 2L)\n", n, e, e / 0.1 * 100);
    EXPECT_LT(e, prev) << n;
    prev = e;
  }
  EXPECT_LT(prev, 1e-3 * 0.1);  // n = 20: below 0.1 % of 2L
}

// 3b. One tendon on a one-segment robot, no external load: as the disks get denser the shape
// approaches the constant-curvature arc of the continuous tendon load, u = T r_d / EI about x,
// with axial strain 1 - T/EA (paper Eq. 8; the CC model with tension input), error ~ 1/n^2.
TEST(Vcref, TendonLoadedSegmentApproachesArc) {
  double prev = 1e9;
  for (int n : {5, 10, 20, 40}) {
    Scene s = paper::scene(n, 1);
    s.robot.segments.resize(1);
    s.robot.segments[0].tendons = {TendonSpec{0.0, 0.008}};
    const double T = 4.0;
    s.actuation.values = {T};
    s.solver.integrator = IntegratorKind::FixedStepRK4;
    s.solver.rk4_steps = 4;
    const Frame tip = tip_of(s);
    const BackboneStiffness k = s.robot.backbone.effective_stiffness();
    // Tendon at +y pulls the tip towards +y: e_z x r = (-r_y, 0, 0) so u = (-T r_d/EI, 0, 0).
    const Frame arc = lie::exp_se3(Vec3(-T * 0.008 / k.EI, 0, 0) * 0.05, Vec3(0, 0, 1.0 - T / k.EA) * 0.05);
    const double e = (tip.p - arc.p).norm();
    std::printf("n = %2d: |p_VCref - p_arc| = %.4e m\n", n, e);
    EXPECT_LT(e, prev);
    if (n > 5) {
      EXPECT_LT(e, 0.4 * prev);
    }  // second order: halving l quarters the error
    prev = e;
  }
  EXPECT_LT(prev, 2e-5);
}

struct RefRow {
  std::string source;
  int id = 0, n = 0;
  double T[4], F[3], residual;
  Vec3 p;
  Mat3 R;
};

std::vector<RefRow> read_reference() {
  std::ifstream in(std::string(TDCR_TEST_DATA_DIR) + "/reference_vcref.csv");
  std::vector<RefRow> rows;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line.rfind("source", 0) == 0) continue;
    std::stringstream ss(line);
    std::string tok;
    std::vector<std::string> f;
    while (std::getline(ss, tok, ',')) f.push_back(tok);
    if (f.size() != 23) continue;
    RefRow r;
    r.source = f[0];
    r.id = std::stoi(f[1]);
    r.n = std::stoi(f[2]);
    for (int k = 0; k < 4; ++k) r.T[k] = std::stod(f[3 + k]);
    for (int k = 0; k < 3; ++k) r.F[k] = std::stod(f[7 + k]);
    r.residual = std::stod(f[10]);
    r.p = Vec3(std::stod(f[11]), std::stod(f[12]), std::stod(f[13]));
    for (int i = 0; i < 9; ++i) r.R(i / 3, i % 3) = std::stod(f[14 + i]);
    rows.push_back(r);
  }
  return rows;
}

Scene reference_scene(const RefRow& r) {
  Scene s = paper::scene(r.n, 1);
  s.actuation.values.assign(r.T, r.T + 4);
  s.loads.tip_force = Vec3(r.F[0], r.F[1], r.F[2]);
  return s;
}

// 4. The paper's own code (GSL, converged rows only: chisq < 1e-12). Its RKF45 has an own
// integration error of 2-6e-5 m at n <= 3 and ~2e-6 m at n = 5 (reference README), hence
// 0.05 % of 2L (5e-5 m) and 0.05 deg for n >= 5 and twice that at n = 3.
TEST(Vcref, MatchesPaperCodeReference) {
  const std::vector<RefRow> rows = read_reference();
  ASSERT_EQ(rows.size(), 106u);
  double worst_p = 0.0, worst_R = 0.0;
  for (const RefRow& r : rows) {
    Scene s = reference_scene(r);
    const Solution sol = run(s);
    ASSERT_TRUE(sol.converged()) << r.source << " " << r.id << ": " << sol.summary.message;
    const TipError e = tip_error(sol.tip(), Frame{lie::nearest_rotation(r.R), r.p});
    const double tol = r.n >= 5 ? 1.0 : 2.0;
    EXPECT_LT(e.position, tol * 5e-5) << r.source << " " << r.id << " n=" << r.n;
    EXPECT_LT(e.angle * 180 / M_PI, tol * 0.05) << r.source << " " << r.id << " n=" << r.n;
    worst_p = std::max(worst_p, e.position / tol);
    worst_R = std::max(worst_R, e.angle * 180 / M_PI / tol);
  }
  std::printf("worst (tolerance-normalised) tip difference: %.3e m, %.3e deg\n", worst_p, worst_R);
}

Scene loaded_scene(int n) {
  Scene s = paper::scene(n, 2);
  s.actuation.values = {0.8 * s.actuation.values[0], 0.0, 1.5, 0.0};
  s.loads.tip_force = Vec3(0.3, 0.2, -0.1);
  s.loads.tip_moment = Vec3(0.0, 0.0, 0.002);
  return s;
}

// 5. KLU and dense LU solve the same linear systems: same answer to round-off.
TEST(Vcref, SparseAndDensePathsAgree) {
  Scene s = loaded_scene(6);
  s.solver.linear_solver = LinearSolverKind::Dense;
  const Solution dense = run(s);
  s.solver.linear_solver = LinearSolverKind::SparseKLU;
  const Solution klu = run(s);
  ASSERT_TRUE(dense.converged()) << dense.summary.message;
  ASSERT_TRUE(klu.converged()) << klu.summary.message;
  EXPECT_EQ(dense.summary.linear_solver, "dense");
  EXPECT_EQ(klu.summary.linear_solver, "klu");
  for (std::size_t j = 0; j < dense.disk_frames.size(); ++j) {
    EXPECT_LT((dense.disk_frames[j].p - klu.disk_frames[j].p).norm(), 1e-10);
    EXPECT_LT(lie::rotation_angle(dense.disk_frames[j].R, klu.disk_frames[j].R), 1e-9);
  }
}

// 6. The assembled block-tridiagonal Jacobian (interval re-integration only where needed,
// translation shortcut, algebra by differences) against central differences of the whole
// residual, also away from the solution, with gravity, a tip wrench and Eq. 58 on and off.
// Metric: every entry, in units of the typical unknown change (columns times the documented
// unknown scales: L, 1, F_s, F_s L), relative to the largest entry of its row. A forward
// difference with h = 1e-7 x scale is accurate to ~h |F''| ~ 1e-7 of the row; a wrong or
// missing entry (missing from the pattern: scattered as 0) shows as O(1).
double row_relative_error(const bvp::JacobianCheck& c, const Eigen::VectorXd& col_scale) {
  const Eigen::MatrixXd A = c.analytic * col_scale.asDiagonal(), B = c.numeric * col_scale.asDiagonal();
  double worst = 0.0;
  for (int i = 0; i < A.rows(); ++i) {
    const double rmax = std::max(A.row(i).cwiseAbs().maxCoeff(), B.row(i).cwiseAbs().maxCoeff());
    if (rmax == 0.0) continue;
    worst = std::max(worst, (A.row(i) - B.row(i)).cwiseAbs().maxCoeff() / rmax);
  }
  return worst;
}

TEST(Vcref, SparseJacobianMatchesFiniteDifferences) {
  for (DiskNormalForce dn : {DiskNormalForce::Removed, DiskNormalForce::Kept}) {
    Scene s = loaded_scene(2);
    s.effects.disk_normal_force = dn;
    s.robot.backbone.density = 8000.0;
    for (auto& seg : s.robot.segments) seg.disk_mass = 0.002;
    s.loads.gravity = Vec3(0.0, -9.81, -3.0);
    VcrefModel model(s.robot, s.effects);
    auto ws = model.make_workspace();
    // Unknown scales (vcref.hpp): positions L, rotations 1, forces F_s, moments F_s L.
    double weight = 0.0;
    for (const auto& seg : s.robot.segments) weight += seg.disks * seg.disk_mass * s.loads.gravity.norm();
    weight += s.robot.backbone.linear_mass() * 0.1 * s.loads.gravity.norm();
    double Fs = 1e-3 + weight + s.loads.tip_force.norm() + s.loads.tip_moment.norm() / 0.1;
    for (double t : s.actuation.values) Fs += t;
    const int n = model.unknowns();
    Eigen::VectorXd cs(n);
    cs.head<3>().setConstant(Fs);
    cs.segment<3>(3).setConstant(Fs * 0.1);
    for (int i = 6; i < n; ++i) {
      const int k = (i - 6) % 12;
      cs[i] = k < 3 ? 0.1 : k < 6 ? 1.0 : k < 9 ? Fs : Fs * 0.1;
    }
    for (double pert : {0.0, 0.05}) {
      const bvp::JacobianCheck c = model.check_jacobian(*ws, s.input(), s.solver, nullptr, pert);
      ASSERT_TRUE(c.evaluated);
      EXPECT_LT(row_relative_error(c, cs), 1e-5) << "perturbation " << pert;
      // The pattern is not too sparse: a dropped entry would be 0 in the analytic matrix.
      EXPECT_GT(c.analytic.cwiseAbs().maxCoeff(), 0.0);
    }
    const Solution sol = tdcr::solve(model, *ws, s.input(), s.solver);
    ASSERT_TRUE(sol.converged()) << sol.summary.message;
    const bvp::JacobianCheck c = model.check_jacobian(*ws, s.input(), s.solver, &sol, 0.0);
    EXPECT_LT(row_relative_error(c, cs), 1e-5);
  }
}

// The disk loads' exact derivatives (vcref_tangent.cpp) for tendons whose hole offsets change
// from disk to disk (helical routing, half a turn per segment), Eq. 58 on and off, against central
// differences as above, at the cold guess moved off the answer and at the answer.
TEST(Vcref, SparseJacobianMatchesFiniteDifferencesForHelicalTendons) {
  for (DiskNormalForce dn : {DiskNormalForce::Removed, DiskNormalForce::Kept}) {
    Scene s = paper::scene(6, 6);  // T2 and T3: a tendon ending at each segment
    s.effects.disk_normal_force = dn;
    for (Segment& seg : s.robot.segments)
      for (TendonSpec& t : seg.tendons) {
        t.routing.type = TendonRoutingSpec::Type::Helical;
        t.routing.turns = 0.5;
      }
    s.loads.tip_force = Vec3(0.1, -0.2, 0.0);
    VcrefModel model(s.robot, s.effects);
    auto ws = model.make_workspace();
    double Fs = 1e-3 + s.loads.tip_force.norm();
    for (double t : s.actuation.values) Fs += t;
    const int n = model.unknowns();
    Eigen::VectorXd cs(n);
    cs.head<3>().setConstant(Fs);
    cs.segment<3>(3).setConstant(Fs * 0.1);
    for (int i = 6; i < n; ++i) {
      const int k = (i - 6) % 12;
      cs[i] = k < 3 ? 0.1 : k < 6 ? 1.0 : k < 9 ? Fs : Fs * 0.1;
    }
    const bvp::JacobianCheck c = model.check_jacobian(*ws, s.input(), s.solver, nullptr, 0.05);
    ASSERT_TRUE(c.evaluated);
    EXPECT_LT(row_relative_error(c, cs), 1e-5);
    const Solution sol = tdcr::solve(model, *ws, s.input(), s.solver);
    ASSERT_TRUE(sol.converged()) << sol.summary.message;
    EXPECT_LT(row_relative_error(model.check_jacobian(*ws, s.input(), s.solver, &sol, 0.0), cs), 1e-5);
  }
}

// 7. Eq. 58 (frictionless disks, paper Section 9.1): the normal component of a pass-through
// tendon's two chord forces vanishes when the neighbouring subsegments bend equally, i.e. at
// constant curvature, which holds without external load inside a segment whose tendon
// moments do not change (configuration 2: T1 only, segment 2 straight): Removed and Kept then
// give the same shape up to solver tolerance. A transverse tip force makes the curvature vary and
// the shapes differ visibly (paper: "visibly different robot shapes").
TEST(Vcref, DiskNormalForceRemovedVsKept) {
  auto diff = [](Scene s) {
    s.effects.disk_normal_force = DiskNormalForce::Removed;
    const Solution a = run(s);
    s.effects.disk_normal_force = DiskNormalForce::Kept;
    const Solution b = run(s);
    EXPECT_TRUE(a.converged()) << a.summary.message;
    EXPECT_TRUE(b.converged()) << b.summary.message;
    return (a.tip().p - b.tip().p).norm();
  };
  Scene s = paper::scene(5, 2);
  const double unloaded = diff(s);
  s.loads.tip_force = Vec3(0.5, 0.0, 0.0);  // transverse
  const double loaded = diff(s);
  Scene s6 = paper::scene(5, 6);  // T1 = T3 = T_M
  s6.loads.tip_force = Vec3(0.5, 0.0, 0.0);
  const double loaded6 = diff(s6);
  std::printf("Removed vs Kept tip difference: config 2 unloaded %.3e m, loaded %.3e m; config 6 loaded %.3e m\n",
              unloaded, loaded, loaded6);
  EXPECT_LT(unloaded, 1e-9);
  EXPECT_GT(loaded, 3e-5);
  EXPECT_GT(loaded6, 1e-4);  // 0.1 % of 2L
}

// 8a. Mirror symmetry about the x-z plane: T2 (at -y) gives the mirror image of T1 (at +y).
TEST(Vcref, MirrorSymmetry) {
  const Solution a = run(paper::scene(4, 2));  // T1
  const Solution b = run(paper::scene(4, 3));  // T2
  ASSERT_TRUE(a.converged() && b.converged());
  const Mat3 S = Vec3(1, -1, 1).asDiagonal();
  for (std::size_t j = 0; j < a.disk_frames.size(); ++j) {
    EXPECT_LT((S * a.disk_frames[j].p - b.disk_frames[j].p).norm(), 1e-12);
    EXPECT_LT((S * a.disk_frames[j].R * S - b.disk_frames[j].R).norm(), 1e-10);
  }
  EXPECT_GT(a.tip().p.y(), 0.03);
  EXPECT_NEAR(a.tendon_displacements[0], b.tendon_displacements[1], 1e-12);
}

// 8b. An iteration limit that cannot be met is reported as a failure, with its residual.
TEST(Vcref, NonConvergenceIsReported) {
  Scene s = paper::scene(5, 8);  // T1, T2, T3: 143 deg
  s.solver.max_iterations = 1;
  s.solver.continuation = false;  // a direct failure, not rescued by continuation
  const Solution sol = run(s);
  EXPECT_FALSE(sol.converged());
  EXPECT_EQ(sol.summary.termination, TerminationType::MaxIterations) << sol.summary.message;
  EXPECT_EQ(sol.summary.iterations, 1);
  EXPECT_GT(sol.summary.residual_norm, sol.summary.function_tolerance);
  EXPECT_FALSE(sol.summary.message.empty());
  // The same problem converges with the default limit.
  s.solver.max_iterations = 200;
  EXPECT_TRUE(run(s).converged());
}

// 9. Global equilibrium of a 3-segment robot with gravity, a tip wrench and tendons anywhere:
// cut at the base, the rod's wrench n_0, m_0 plus the pulls of the first tendon chords on the
// base disk balance the tip wrench and the weights. With Eq. 58 kept, the tendon chords are
// two-force members, so their disk forces telescope to the base pull.
TEST(Vcref, GlobalEquilibriumThreeSegments) {
  Scene s = three_segments();
  s.actuation.values = {2.0, 0.0, 0.5, 0.0, 1.5, 0.0, 0.7, 0.0, 0.3};
  s.loads.tip_force = Vec3(0.1, -0.2, 0.05);
  s.loads.tip_moment = Vec3(0.001, 0.0, -0.002);
  s.loads.gravity = Vec3(0.0, 0.0, -9.81);
  s.effects.disk_normal_force = DiskNormalForce::Kept;
  const Solution sol = run(s);
  ASSERT_TRUE(sol.converged()) << sol.summary.message;
  const TendonRouting routing = TendonRouting::from(s.robot);
  const auto& fr = sol.disk_frames;
  Vec3 force = sol.backbone[0].n, moment = sol.backbone[0].m;
  for (const RoutedTendon& t : routing.tendons) {
    const Vec3 P0 = tendon::hole_position(fr[0], t), P1 = tendon::hole_position(fr[1], t);
    const Vec3 pull = s.actuation.values[t.index] * (P1 - P0).normalized();
    force += pull;
    moment += P0.cross(pull);
  }
  const double rhoA = s.robot.backbone.linear_mass();
  Vec3 F = s.loads.tip_force, M = s.loads.tip_moment + fr.back().p.cross(s.loads.tip_force);
  for (std::size_t j = 1; j < fr.size(); ++j) {
    const Vec3 W = s.robot.segments[routing.disk_segment[j]].disk_mass * s.loads.gravity;
    const double l = routing.disk_s[j] - routing.disk_s[j - 1];
    F += W + rhoA * l * s.loads.gravity;
    // Backbone weight moment: trapezoid over each interval (error O(l^3) per interval).
    M += fr[j].p.cross(W) + (0.5 * (fr[j].p + fr[j - 1].p)).cross(rhoA * l * s.loads.gravity);
  }
  const double Fs = 6.0, Ms = Fs * 0.1;
  EXPECT_LT((force - F).norm(), 1e-9 * Fs);
  EXPECT_LT((moment - M).norm(), 1e-6 * Ms);
  // Gravity matters at this size: the total weight is not negligible against the tip force.
  EXPECT_GT((F - s.loads.tip_force).norm(), 0.01);
}

// Warm start from the answer: converged at once, same shape; and with a nearby load (fewer
// iterations than cold with fresh Jacobians, fewer Jacobians than cold with the reused one).
TEST(Vcref, WarmStart) {
  Scene s = loaded_scene(10);
  s.solver = test::fixed_mesh_settings(s.solver);  // one mesh: the warm solve's iterations are Newton's
  VcrefOptions fresh_jacobians;
  fresh_jacobians.reuse_jacobian = false;
  fresh_jacobians.guess_passes = 0;  // cold solves from the arcs alone: the comparison below
  VcrefModel model(s.robot, s.effects, fresh_jacobians);
  auto ws = model.make_workspace();
  const Solution cold = tdcr::solve(model, *ws, s.input(), s.solver);
  ASSERT_TRUE(cold.converged());
  const Solution warm = tdcr::solve(model, *ws, s.input(), s.solver, &cold);
  ASSERT_TRUE(warm.converged());
  EXPECT_LE(warm.summary.iterations, 1);
  EXPECT_LT((warm.tip().p - cold.tip().p).norm(), 1e-11);
  Scene s2 = s;
  s2.actuation.values[0] *= 1.05;
  const Solution w2 = tdcr::solve(model, *ws, s2.input(), s2.solver, &cold);
  const Solution c2 = tdcr::solve(model, *ws, s2.input(), s2.solver);
  ASSERT_TRUE(w2.converged() && c2.converged());
  EXPECT_LT(w2.summary.iterations, c2.summary.iterations);
  EXPECT_LT((w2.tip().p - c2.tip().p).norm(), 1e-10);
  VcrefOptions reuse;
  reuse.reuse_jacobian = true;
  VcrefModel reusing(s.robot, s.effects, reuse);
  auto rws = reusing.make_workspace();
  const Solution rc = tdcr::solve(reusing, *rws, s.input(), s.solver);
  const Solution r2 = tdcr::solve(reusing, *rws, s2.input(), s2.solver, &rc);
  ASSERT_TRUE(r2.converged()) << r2.summary.message;
  EXPECT_LT(r2.summary.jacobian_evaluations, c2.summary.jacobian_evaluations);
  EXPECT_LT((r2.tip().p - c2.tip().p).norm(), 1e-10);
}

// Jacobian reuse is VCref's default; SolverOptions::reuse_jacobian = false turns it off for the
// solve (every model): the warm start then takes a fresh Jacobian at its first iteration. Both
// land on the same answer within the Newton tolerance.
TEST(Vcref, SolverOptionTurnsJacobianReuseOff) {
  Scene s = loaded_scene(10);
  VcrefModel model(s.robot, s.effects);
  ASSERT_TRUE(model.options().reuse_jacobian);
  auto ws = model.make_workspace();
  const Solution cold = tdcr::solve(model, *ws, s.input(), s.solver);
  ASSERT_TRUE(cold.converged()) << cold.summary.message;
  Scene s2 = s;
  s2.actuation.values[0] *= 1.02;
  const Solution reused = tdcr::solve(model, *ws, s2.input(), s2.solver, &cold);
  ASSERT_TRUE(reused.converged()) << reused.summary.message;
  SolverOptions fresh = s2.solver;
  fresh.reuse_jacobian = false;
  tdcr::solve(model, *ws, s.input(), s.solver);  // the same workspace history as before `reused`
  const Solution own = tdcr::solve(model, *ws, s2.input(), fresh, &cold);
  ASSERT_TRUE(own.converged()) << own.summary.message;
  EXPECT_GE(own.summary.jacobian_evaluations, 1);
  EXPECT_LT(reused.summary.jacobian_evaluations, own.summary.jacobian_evaluations);
  EXPECT_LT((reused.tip().p - own.tip().p).norm(), 1e-10);
}

// The Jacobian pattern follows the tensioned tendons: configuration 2 (T1 only, ending at the
// first segment's tip) drops the pass-through rows of the other tendons (the count of the pattern
// before the port onto bvp's shooting: 5796 at n = 10); with every tendon tensioned the model's
// pattern of every routed tendon is used; without tension no disk reads its successor.
TEST(Vcref, PatternFollowsTensionedTendons) {
  const Scene s = paper::scene(10, 2);
  VcrefModel model(s.robot, s.effects);
  const int N = s.robot.total_disks();
  EXPECT_EQ(model.unknowns(), 6 + 12 * (N - 1));
  EXPECT_EQ(model.jacobian_nonzeros(), 6120);
  EXPECT_EQ(model.jacobian_nonzeros(s.input()), 5796);
  EXPECT_EQ(model.jacobian_nonzeros(paper::scene(10, 16).input()), model.jacobian_nonzeros());
  Scene none = s;
  std::fill(none.actuation.values.begin(), none.actuation.values.end(), 0.0);
  // Block tridiagonal without pass-through entries: per disk 12 x 12 from itself and its
  // predecessor, tip block 6 x 12 from node N-1, node 0's 6 columns in blocks 0 (N = 1) and 1.
  EXPECT_EQ(model.jacobian_nonzeros(none.input()), 12 * 12 * (N - 1) + 12 * 12 * (N - 2) + 6 * 12 + 6 * 12);
}

// A trajectory switching tendons on and off gives the answers of fresh workspaces with the same
// warm start (or none). The pass-through masks (none, segment 1, segments 1-2, all) change,
// return, and outnumber the workspace's two cached patterns. Without Jacobian reuse, which
// would make the answers depend on the workspace's last solve (within the Newton tolerance).
TEST(Vcref, TrajectorySwitchingTendonsMatchesFreshWorkspaces) {
  Scene base = three_segments();
  base.loads.gravity = Vec3(0.0, 0.0, -9.81);
  base.loads.tip_force = Vec3(0.05, -0.02, 0.0);
  base.solver = test::fixed_mesh_settings(base.solver);  // answers compared to 1e-10 m
  // Tension of one tendon in each segment.
  const std::vector<Vec3> steps = {{1.5, 0, 0}, {1.5, 1.0, 0}, {0, 1.0, 0.5}, {0, 0, 0},     {1.0, 0, 0},
                                   {0, 0, 0},   {0, 0.8, 0},   {0.5, 0, 0.5}, {0, 0.8, 0.2}, {1.2, 0, 0},
                                   {0, 0, 0.6}, {1.5, 0, 0}};
  VcrefOptions fresh_jacobians;
  fresh_jacobians.reuse_jacobian = false;
  VcrefModel model(base.robot, base.effects, fresh_jacobians);
  auto ws = model.make_workspace();
  VcrefOptions reuse;  // Jacobian reuse through the pattern changes
  reuse.reuse_jacobian = true;
  VcrefModel reusing(base.robot, base.effects, reuse);
  auto rws = reusing.make_workspace();
  Solution prev, rprev;
  for (std::size_t k = 0; k < steps.size(); ++k) {
    Scene s = base;
    s.actuation.values.assign(9, 0.0);
    for (int i = 0; i < 3; ++i) s.actuation.values[3 * i + (k + i) % 3] = steps[k][i];
    const Solution* warm = k % 4 == 3 || k == 0 ? nullptr : &prev;  // some cold solves
    const Solution a = tdcr::solve(model, *ws, s.input(), s.solver, warm);
    auto fresh = model.make_workspace();
    const Solution b = tdcr::solve(model, *fresh, s.input(), s.solver, warm);
    ASSERT_TRUE(a.converged() && b.converged()) << "step " << k << ": " << a.summary.message;
    EXPECT_EQ(a.summary.iterations, b.summary.iterations) << "step " << k;
    EXPECT_LT((a.tip().p - b.tip().p).norm(), 1e-12) << "step " << k;
    EXPECT_LT(lie::rotation_angle(a.tip().R, b.tip().R), 1e-12) << "step " << k;
    const Solution r = tdcr::solve(reusing, *rws, s.input(), s.solver, warm ? &rprev : nullptr);
    ASSERT_TRUE(r.converged()) << "step " << k << ": " << r.summary.message;
    EXPECT_LT((r.tip().p - a.tip().p).norm(), 1e-10) << "step " << k;
    prev = a;
    rprev = r;
  }
  // The patterns of the four masks differ, and the one the trajectory's workspace uses leaves out
  // no dependency: an entry outside it is 0 in the assembled Jacobian, so central differences
  // must be negligible there (relative to their row).
  Scene s = base;
  std::vector<int> nnz;
  for (int segs = 0; segs <= 3; ++segs) {
    s.actuation.values.assign(9, 0.0);
    if (segs > 0) s.actuation.values[3 * (segs - 1)] = 1.0;
    nnz.push_back(model.jacobian_nonzeros(s.input()));
    const bvp::JacobianCheck c = model.check_jacobian(*ws, s.input(), s.solver, &prev, 0.05);
    ASSERT_TRUE(c.evaluated);
    double missing = 0.0;
    for (int i = 0; i < c.numeric.rows(); ++i) {
      const double rmax = c.numeric.row(i).cwiseAbs().maxCoeff();
      for (int j = 0; j < c.numeric.cols(); ++j)
        if (c.analytic(i, j) == 0.0 && rmax > 0.0) missing = std::max(missing, std::abs(c.numeric(i, j)) / rmax);
    }
    EXPECT_LT(missing, 1e-6) << segs << " tensioned segments";
  }
  EXPECT_TRUE(nnz[0] < nnz[1] && nnz[1] < nnz[2] && nnz[2] < nnz[3] && nnz[3] == model.jacobian_nonzeros());
}

// Bad input is refused with the field named.
TEST(Vcref, RejectsNonFiniteDisplacementInput) {
  Scene s = paper::scene(3, 2);
  s.actuation.kind = Actuation::Kind::Displacements;
  s.actuation.values[1] = NAN;
  VcrefModel m(s.robot, s.effects);
  auto ws = m.make_workspace();
  try {
    tdcr::solve(m, *ws, s.input(), s.solver);
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "actuation.displacements[1]");
  }
}

// Hard case (DESIGN: one disk per segment, bending beyond 140 deg): T1 = T2 = T3 = T_M at n = 1
// (configuration 8). The direct solve from the arc guess fails and says so; load continuation
// (SolverOptions::continuation) converges to the paper code's ramp10 answer (fig10_configs,
// n = 1, config 8, ramp10: tip (0, 0.0702442567872, 0.000856379182872) m), within the paper code's own
// RKF45 error at n <= 3 (2-6e-5 m, reference README) plus ours (RK4, 64 steps: < 1e-6 m).
TEST(Vcref, ContinuationSolvesOneDiskPerSegmentAt143Degrees) {
  Scene s = paper::scene(1, 8);
  s.solver.integrator = IntegratorKind::FixedStepRK4;
  s.solver.rk4_steps = 64;
  s.solver.continuation = false;
  const Solution direct = run(s);
  EXPECT_FALSE(direct.converged());
  EXPECT_NE(direct.summary.termination, TerminationType::Converged);
  s.solver.continuation = true;
  const Solution sol = run(s);
  ASSERT_TRUE(sol.converged()) << sol.summary.message;
  EXPECT_GT(sol.summary.continuation_steps, 0);
  EXPECT_LT((sol.tip().p - Vec3(0.0, 0.0702442567872, 0.000856379182872)).norm(), 1e-4);
}

// The reference integrator (CVODE, error controlled) and the fast path (RK4, 8 steps per
// interval) agree on the paper robot at n = 5 to far below the model's discretisation error.
TEST(Vcref, CvodeAndRk4Agree) {
  Scene s = paper::scene(5, 2);
  s.loads.tip_force = Vec3(0.1, 0.2, 0.0);
  const Solution a = run(s);
  s.solver.integrator = IntegratorKind::Cvode;
  const Solution b = run(s);
  ASSERT_TRUE(a.converged() && b.converged()) << b.summary.message;
  EXPECT_EQ(b.summary.integrator, "cvode");
  EXPECT_LT((a.tip().p - b.tip().p).norm(), 1e-8);
  EXPECT_LT(lie::rotation_angle(a.tip().R, b.tip().R), 1e-7);
}

// Cost linear in the disk count (docs/benchmarks.md, "VCref cost against the number of disks").
// A rigid motion of disks 1..N (the base stays clamped) turns no tendon chord against its disks
// and moves every rod with its ends, so the Jacobian maps it to zero outside block 1 (the rows of
// disk 1, next to the base): a translation anywhere, a rotation about the base at an equilibrium
// without external load (the residual turns with it: omega x 0). Units: unknowns in their scales
// (L, 1, F_s, F_s L), residuals scaled. Forward differences with steps of 1e-7 of those scales
// leave a rounding of about eps / 1e-7 = 2.2e-9 in every entry (the residual's terms are of order
// 1, the change 1e-7), whatever the disk count; a row sums at most nine entries: below 2e-8
// (measured: at most 3.4e-9). With the tendon wrenches differentiated in full the steps had to be
// 1e-7 of the shortest interval l_min (the chords turn on that scale) and their truncation and
// rounding grew with L / l_min: 2.0e-6 on the paper robot at n = 10, 2.6e-5 on the robot with
// short disk spacing below, and from 5000 disks per segment on Newton stalled on them.
struct RigidMotionRows {
  // The largest scaled |J d| outside block 1: pose continuity rows, disk equilibrium rows.
  double translation[2] = {0.0, 0.0}, rotation[2] = {0.0, 0.0};
};

RigidMotionRows rigid_motion_rows(const Scene& s) {
  VcrefModel model(s.robot, s.effects);
  auto ws = model.make_workspace();
  const Solution sol = tdcr::solve(model, *ws, s.input(), s.solver);
  EXPECT_TRUE(sol.converged()) << sol.summary.message;
  const bvp::JacobianCheck c = model.check_jacobian(*ws, s.input(), s.solver, &sol, 0.0);
  EXPECT_TRUE(c.evaluated);
  const int n = model.unknowns(), N = s.robot.total_disks();
  const double L = s.robot.total_length();
  double Fs = 1e-3;  // physics::LoadCase::force_scale without external loads
  for (double t : s.actuation.values) Fs += t;
  Eigen::VectorXd fs(n);
  std::vector<int> group(n);
  for (int i = 0; i < n; ++i) {
    group[i] = i < 6 ? 2 + i / 3 : ((i - 6) % 12) / 3;  // rows of p, w continuity, force, moment balance
    fs[i] = group[i] == 0 ? 1.0 / L : group[i] == 1 ? 1.0 : group[i] == 2 ? 1.0 / Fs : 1.0 / (Fs * L);
  }
  const auto outside_block_1 = [&](const Eigen::VectorXd& d, double* worst) {
    const Eigen::VectorXd r = (c.analytic * d).cwiseProduct(fs).cwiseAbs();
    for (int i = 0; i < n; ++i)
      if (i < 6 || i >= 18) worst[group[i] / 2] = std::max(worst[group[i] / 2], r[i]);
  };
  const Vec3 e = Vec3(1.0, 2.0, 3.0).normalized();
  const Eigen::VectorXd& x = sol.unknowns;  // the check's point, up to the rotation charts (w = 0)
  Eigen::VectorXd shift = Eigen::VectorXd::Zero(n), turn = Eigen::VectorXd::Zero(n);
  turn.head<3>() = e.cross(Vec3(x.head<3>()));
  turn.segment<3>(3) = e.cross(Vec3(x.segment<3>(3)));
  for (int k = 1; k < N; ++k) {
    const int o = 6 + 12 * (k - 1);
    shift.segment<3>(o) = L * e;
    turn.segment<3>(o) = e.cross(Vec3(x.segment<3>(o)));
    turn.segment<3>(o + 3) = sol.disk_frames[k].R.transpose() * e;
    turn.segment<3>(o + 6) = e.cross(Vec3(x.segment<3>(o + 6)));
    turn.segment<3>(o + 9) = e.cross(Vec3(x.segment<3>(o + 9)));
  }
  RigidMotionRows rows;
  outside_block_1(shift, rows.translation);
  outside_block_1(turn, rows.rotation);
  return rows;
}

TEST(Vcref, JacobianMapsRigidMotionsOfTheDisksToZero) {
  // The paper robot (configuration 2), and one whose second segment is 0.5 mm long with 50
  // disks: L / l_min = 1e4, as with 5000 disks per segment, at 714 unknowns.
  Scene fine = paper::scene(10, 2);
  fine.robot.segments[1].length = 5e-4;
  fine.robot.segments[1].disks = 50;
  for (const Scene& s : {paper::scene(10, 2), fine}) {
    const RigidMotionRows r = rigid_motion_rows(s);
    const std::string robot = std::to_string(s.robot.segments[1].disks) + " disks in segment 2";
    for (int g = 0; g < 2; ++g) {
      EXPECT_LT(r.translation[g], 2e-8) << robot << (g ? ", equilibrium rows" : ", continuity rows");
      EXPECT_LT(r.rotation[g], 2e-8) << robot << (g ? ", equilibrium rows" : ", continuity rows");
    }
  }
}

// The user's scene: the paper robot with 5000 disks per segment (configuration 2). The cold guess
// misses only the axial compression (strain T / EA ~ 5e-5), and one Newton step takes it out;
// before the disk loads were linearised the first steps of the direct solve were rejected, it
// stalled for 30 iterations, the loading path then ran for minutes in 9 GB. Continuation off and
// few iterations allowed: a stall fails here within seconds.
TEST(Vcref, FiveThousandDisksPerSegmentConvergeInOneNewtonStep) {
  Scene s = paper::scene(5000, 2);
  s.solver.continuation = false;
  s.solver.max_iterations = 4;
  const Solution sol = run(s);
  ASSERT_TRUE(sol.converged()) << sol.summary.message;
  EXPECT_EQ(sol.summary.linear_solver, "klu");
  EXPECT_LE(sol.summary.iterations, 2);
  EXPECT_LT(sol.summary.residual_norm, 1e-10);
}

}  // namespace
}  // namespace tdcr
