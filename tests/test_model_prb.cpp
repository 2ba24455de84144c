// Tests of the extended PRB model (paper Eq. 11-12, 30-33, 44-54, Table 1): analytic cases,
// symmetry, global equilibrium, failure reporting, the paper's own code as reference data, and
// the case-study accuracy against VCref at n = 1.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tdcr/core/lie.hpp"
#include "tdcr/core/metrics.hpp"
#include "tdcr/core/paper_robot.hpp"
#include "lumped_reference.hpp"
#include "tdcr/models/prb.hpp"
#include "tdcr/models/tendon_physics.hpp"

using namespace tdcr;

namespace {

using lumped_reference::RefRow;
using lumped_reference::load_reference;

Scene paper_scene(int n, const std::vector<double>& T, const Vec3& F = Vec3::Zero()) {
  Scene s = paper::scene(n, 1, "prb");
  s.actuation.values = T;
  s.loads.tip_force = F;
  return s;
}

Solution solve_prb(const Scene& s, const Solution* warm = nullptr) {
  const PrbModel model(s.robot, s.effects);
  auto ws = model.make_workspace();
  return tdcr::solve(model, *ws, s.input(), s.solver, warm);
}

}  // namespace

// 1. No tension, no load: the straight robot.
TEST(PrbModel, ZeroTensionIsStraight) {
  const Solution sol = solve_prb(paper_scene(3, {0, 0, 0, 0}));
  ASSERT_TRUE(sol.converged()) << sol.summary.message;
  ASSERT_EQ(sol.disk_frames.size(), 7u);
  for (std::size_t j = 0; j < sol.disk_frames.size(); ++j) {
    EXPECT_NEAR((sol.disk_frames[j].p - Vec3(0, 0, 0.05 * j / 3.0)).norm(), 0.0, 1e-15);
    EXPECT_NEAR((sol.disk_frames[j].R - Mat3::Identity()).norm(), 0.0, 1e-15);
  }
}

// Antagonistic equal tensions compress the inextensible backbone without bending it (the
// bending plane is undetermined there: the gauge keeps the solve regular).
TEST(PrbModel, EqualAntagonisticTensionsStayStraight) {
  const double TM = paper::max_tension(paper::robot(4));
  const Solution sol = solve_prb(paper_scene(4, {TM, TM, 0.5 * TM, 0.5 * TM}));
  ASSERT_TRUE(sol.converged()) << sol.summary.message;
  EXPECT_NEAR((sol.tip().p - Vec3(0, 0, 0.1)).norm(), 0.0, 1e-12);
}

// 2. Pure tip moment M: every joint carries M, so theta_q = M l / (K_q EI) and the tip turns by
// (sum_q 1/K_q) kappa L = 0.99878 kappa L instead of the arc's kappa L (Table 1: 1/3.25 + 1/2.84
// + 1/2.95). That angle is exact; the position error is the 3R model's (Su 2009): measured
// 0.076 % of L at 90 deg (4 subsegments), asserted in [0.05 %, 0.1 %].
TEST(PrbModel, PureTipMomentWithinThreeRAccuracy) {
  Scene s = paper_scene(4, {0, 0, 0, 0});
  const double EI = s.robot.backbone.effective_stiffness().EI;
  const double L = 0.1, theta = M_PI / 2.0, kappa = theta / L;
  const Vec3 axis = Vec3(1.0, 2.0, 0.0).normalized();
  s.loads.tip_moment = EI * kappa * axis;
  const Solution sol = solve_prb(s);
  ASSERT_TRUE(sol.converged()) << sol.summary.message;
  const double factor = 1.0 / 3.25 + 1.0 / 2.84 + 1.0 / 2.95;
  EXPECT_NEAR(lie::rotation_angle(sol.tip().R, Mat3::Identity()), factor * theta, 1e-9);
  EXPECT_LT(lie::rotation_angle(sol.tip().R, lie::exp_so3(factor * theta * axis)), 1e-9);
  const Frame arc = lie::exp_se3(kappa * L * axis, Vec3(0, 0, L));
  const double err = (sol.tip().p - arc.p).norm() / L;
  std::printf("PRB pure moment 90 deg: tip position error %.4f %% of L\n", 100 * err);
  EXPECT_LT(err, 1e-3);
  EXPECT_GT(err, 5e-4);  // the 3R body is not an arc
}

// 3. Mirror symmetry about the x-z plane, both solved to a residual of 1e-13 (at the default
// 1e-10 the two solves may stop at different points within the tolerance, ~1e-12 m apart).
TEST(PrbModel, MirrorSymmetry) {
  const double TM = paper::max_tension(paper::robot(5));
  Scene sa = paper_scene(5, {TM, 0.2 * TM, 0.5 * TM, 0}, Vec3(0.1, 0.2, 0.05));
  Scene sb = paper_scene(5, {0.2 * TM, TM, 0, 0.5 * TM}, Vec3(0.1, -0.2, 0.05));
  sa.solver.function_tolerance = sb.solver.function_tolerance = 1e-13;
  const Solution a = solve_prb(sa);
  const Solution b = solve_prb(sb);
  ASSERT_TRUE(a.converged()) << a.summary.message;
  ASSERT_TRUE(b.converged()) << b.summary.message;
  const Mat3 S = Vec3(1, -1, 1).asDiagonal();
  for (std::size_t j = 0; j < a.disk_frames.size(); ++j) {
    EXPECT_NEAR((S * a.disk_frames[j].p - b.disk_frames[j].p).norm(), 0.0, 1e-12);
    EXPECT_NEAR((S * a.disk_frames[j].R * S - b.disk_frames[j].R).norm(), 0.0, 1e-10);
  }
  EXPECT_GT(std::abs(a.tip().p.x()), 1e-3);
}

// 4. The paper's own code (rows with chisq < 1e-12): 0.05 % of 2L and 0.05 deg, twice at n <= 3.
// The largest differences (~1e-5 m) are the paper code's: its one-sided plane residual
// n . M* - |M*| ~ |M*| dphi^2 / 2 leaves phi wrong by ~1e-4 rad at chisq 1e-19 (e.g. its n = 1,
// T1-only tip has x = 6.7e-6 m out of the bending plane; tdcr's is 0 to rounding).
TEST(PrbModel, MatchesPaperCodeReferenceRows) {
  const std::vector<RefRow> rows = load_reference();
  int compared = 0;
  double worst_p = 0.0, worst_R = 0.0;
  for (const RefRow& r : rows) {
    if (r.model != "PRB" || r.residual >= 1e-12) continue;
    const Solution sol = solve_prb(paper_scene(r.n, {r.T[0], r.T[1], r.T[2], r.T[3]}, Vec3(r.F[0], r.F[1], r.F[2])));
    ASSERT_TRUE(sol.converged()) << r.source << " " << r.id << " n=" << r.n << ": " << sol.summary.message;
    const TipError e = tip_error(sol.tip(), r.tip);
    const double f = r.n <= 3 ? 2.0 : 1.0;
    EXPECT_LT(e.position, f * 5e-5) << r.source << " " << r.id << " n=" << r.n;
    EXPECT_LT(e.angle * 180.0 / M_PI, f * 0.05) << r.source << " " << r.id << " n=" << r.n;
    worst_p = std::max(worst_p, e.position);
    worst_R = std::max(worst_R, e.angle);
    ++compared;
  }
  EXPECT_GE(compared, 130);
  std::printf("PRB vs paper code: %d rows, max tip error %.3g m, %.3g deg\n", compared, worst_p, worst_R * 180.0 / M_PI);
}

// 5. Case-study accuracy at n = 1 against the converged VCref of the paper's code (straight guess
// where it converged, else its 10-step ramp), paper Eq. 57 over the 16 configurations.
// The paper's text says "at most 0.47 % and 0.43 deg"; the model as the paper defines (and codes)
// it gives 1.242 % and 1.047 deg (the paper's code: 1.24223 %, 1.04657 deg, reference/
// paper_code_fig10.csv), dominated by configurations 8 and 12 (bent ~143 deg: 5.5 %, 4.8 deg).
// Our solve matches the paper code's PRB rows to 2e-5 m, so the published 0.47 % does not follow
// from the model against a converged VCref; the value asserted is the model's.
TEST(PrbModel, CaseStudyAccuracyAgainstVcrefAtOneDisk) {
  const std::vector<RefRow> rows = load_reference();
  std::vector<Frame> tips, refs;
  for (const RefRow& r : rows) {
    if (r.model != "VCref" || r.n != 1) continue;
    const Solution sol = solve_prb(paper_scene(1, {r.T[0], r.T[1], r.T[2], r.T[3]}));
    ASSERT_TRUE(sol.converged()) << sol.summary.message;
    tips.push_back(sol.tip());
    refs.push_back(r.tip);
  }
  ASSERT_EQ(tips.size(), 16u);
  const MeanTipError e = mean_tip_error(tips, refs, 0.1);
  std::printf("PRB vs VCref n=1: e_p %.4f %% (max %.3f), e_R %.4f deg (max %.3f)\n", e.e_p_percent, e.max_p_percent,
              e.e_R_deg, e.max_R_deg);
  EXPECT_NEAR(e.e_p_percent, 1.2422, 0.005);
  EXPECT_NEAR(e.e_R_deg, 1.0465, 0.005);
  EXPECT_NEAR(e.max_p_percent, 5.50, 0.01);
}

// 7. Global equilibrium with gravity, tip force and moment, 3 segments x 4 tendons at arbitrary
// angles. The moments of all loads about the base and about the first joint are summed here
// directly (tendon forces, disk weights, link weights at link midpoints, tip wrench) and must
// satisfy the first subsegment's equations: Eq. 48 at joint 1, Eq. 52 (in-plane moment along the
// joint axis) and Eq. 54 (twist).
TEST(PrbModel, GlobalEquilibriumWithGravityAndTipForce) {
  Scene s;
  s.model = "prb";
  s.robot.backbone.density = 6450.0;
  const double angles[3][4] = {{0.1, 1.7, 3.3, 4.6}, {0.5, 2.2, 3.9, 5.5}, {1.0, 2.6, 4.0, 6.0}};
  for (int i = 0; i < 3; ++i) {
    Segment seg;
    seg.length = 0.04 + 0.01 * i;
    seg.disks = 4 + i;
    seg.disk_mass = 2e-4;
    for (double a : angles[i]) seg.tendons.push_back(TendonSpec{0.007 * std::cos(a), 0.007 * std::sin(a)});
    s.robot.segments.push_back(seg);
  }
  s.actuation.values = {2.0, 0.0, 0.5, 0.0, 0.0, 1.0, 0.3, 0.0, 0.0, 0.0, 0.8, 0.2};
  s.loads.tip_force = Vec3(0.05, -0.1, 0.02);
  s.loads.tip_moment = Vec3(0.0, 0.002, 0.001);
  s.loads.gravity = Vec3(0.0, -9.81, 0.0);
  const PrbModel model(s.robot, s.effects);
  auto ws = model.make_workspace();
  const Solution sol = tdcr::solve(model, *ws, s.input(), s.solver);
  ASSERT_TRUE(sol.converged()) << sol.summary.message;
  const std::vector<Vec3> pts = model.joint_points(sol.unknowns, s.input());
  const TendonRouting routing = TendonRouting::from(s.robot);
  const int N = routing.disk_count() - 1;
  const double gamma[4] = {0.125 / 0.999, 0.35 / 0.999, 0.388 / 0.999, 0.136 / 0.999};
  const double rhoA = s.robot.backbone.linear_mass();

  Vec3 F = s.loads.tip_force, Mb = s.loads.tip_moment + sol.tip().p.cross(s.loads.tip_force);
  for (int j = 1; j <= N; ++j) {
    const tendon::DiskWrench w = tendon::disk_wrench(j, sol.disk_frames.data(), routing, s.actuation.values.data(),
                                                         s.effects.disk_normal_force == DiskNormalForce::Removed);
    const Vec3 dw = s.robot.segments[routing.disk_segment[j]].disk_mass * s.loads.gravity;
    F += w.force + dw;
    Mb += w.moment + sol.disk_frames[j].p.cross(w.force + dw);
    const double l = routing.disk_s[j] - routing.disk_s[j - 1];
    const Vec3 chain[5] = {sol.disk_frames[j - 1].p, pts[4 * (j - 1)], pts[4 * (j - 1) + 1], pts[4 * (j - 1) + 2],
                           pts[4 * (j - 1) + 3]};
    for (int i = 0; i < 4; ++i) {
      const Vec3 W = rhoA * gamma[i] * l * s.loads.gravity;
      const Vec3 mid = 0.5 * (chain[i] + chain[i + 1]);
      F += W;
      Mb += mid.cross(W);
    }
  }
  const BackboneStiffness k = s.robot.backbone.effective_stiffness();
  const double l1 = routing.disk_s[1];
  const double th1 = sol.unknowns[0], phi = sol.unknowns[3], eps = sol.unknowns[4];
  const Vec3 y(-std::sin(phi), std::cos(phi), 0.0), x(std::cos(phi), std::sin(phi), 0.0);
  // Moment about joint 1 (P_1 = pts[0]) of everything distal of it: all loads but link 0's
  // weight (at its midpoint P_1 / 2, the base being the origin).
  const Vec3 W0 = rhoA * gamma[0] * l1 * s.loads.gravity;
  const Vec3 M_j1 = (Mb - (0.5 * pts[0]).cross(W0)) - pts[0].cross(F - W0);
  const double scale = 3.25 * k.EI / l1;
  EXPECT_NEAR(y.dot(M_j1), scale * th1, 1e-9 * Mb.norm());
  EXPECT_NEAR(x.dot(Mb), 0.0, 1e-9 * Mb.norm());
  EXPECT_NEAR(sol.disk_frames[1].R.col(2).dot(Mb), k.GJ * eps / l1, 1e-9 * Mb.norm());
  EXPECT_GT(std::abs(th1), 1e-3);
  EXPECT_GT(std::abs(eps), 1e-6);
}

// A solve that cannot converge reports failure with residual and iterations.
TEST(PrbModel, NonConvergentSolveReportsFailure) {
  const double TM = paper::max_tension(paper::robot(10));
  Scene s = paper_scene(10, {6 * TM, 0, 6 * TM, 0}, Vec3(0, 2.0, 0));
  s.solver.max_iterations = 2;
  s.solver.continuation = false;  // a direct failure, not rescued by continuation
  const Solution sol = solve_prb(s);
  EXPECT_FALSE(sol.converged());
  EXPECT_EQ(sol.summary.termination, TerminationType::MaxIterations) << sol.summary.message;
  EXPECT_GT(sol.summary.residual_norm, sol.summary.function_tolerance);
  EXPECT_GT(sol.summary.iterations, 0);
}

// Warm start from a previous solution; the straight guess puts the joint angles on the positive
// branch (the paper's one-sided Eq. 52), the plane along the moment.
TEST(PrbModel, WarmStartAndBranch) {
  const double TM = paper::max_tension(paper::robot(10));
  const Scene s = paper_scene(10, {TM, 0, 0.5 * TM, 0});
  const PrbModel model(s.robot, s.effects);
  auto ws = model.make_workspace();
  const Solution cold = tdcr::solve(model, *ws, s.input(), s.solver);
  ASSERT_TRUE(cold.converged()) << cold.summary.message;
  for (int j = 0; j < 20; ++j)
    for (int q = 0; q < 3; ++q) EXPECT_GT(cold.unknowns[5 * j + q], 0.0) << j << " " << q;
  const Solution warm = tdcr::solve(model, *ws, s.input(), s.solver, &cold);
  ASSERT_TRUE(warm.converged());
  EXPECT_LE(warm.summary.iterations, 1);
  // Both satisfy the tolerance 1e-10 on angle-sized residuals: tips agree to ~N * 1e-10 * L.
  EXPECT_LT((warm.tip().p - cold.tip().p).norm(), 1e-9);
}

// A trajectory on one model and one workspace: warm starts across inputs that load a different
// number of subsegments (J = N/2, then N, then N/2 again).
TEST(PrbModel, WarmStartAcrossInputsWithOtherLoadedSubsegments) {
  const double TM = paper::max_tension(paper::robot(5));
  const Scene a = paper_scene(5, {TM, 0, 0, 0});
  const Scene b = paper_scene(5, {TM, 0, 0.2 * TM, 0});
  const PrbModel model(a.robot, a.effects);
  auto ws = model.make_workspace();
  const Solution sa = tdcr::solve(model, *ws, a.input(), a.solver);
  ASSERT_TRUE(sa.converged());
  const Solution sb = tdcr::solve(model, *ws, b.input(), b.solver, &sa);
  ASSERT_TRUE(sb.converged()) << sb.summary.message;
  EXPECT_EQ(sb.summary.unknowns, 50);
  EXPECT_LT((sb.tip().p - solve_prb(b).tip().p).norm(), 1e-9);
  const Solution sa2 = tdcr::solve(model, *ws, a.input(), a.solver, &sb);
  ASSERT_TRUE(sa2.converged());
  EXPECT_LT((sa2.tip().p - sa.tip().p).norm(), 1e-9);
}

// Reduced Newton steps (Automatic, 100 loaded subsegments) match the recursive form.
TEST(PrbModel, ReducedNewtonMatchesRecursive) {
  const double TM = paper::max_tension(paper::robot(50));
  const Scene s = paper_scene(50, {0.3 * TM, 0, 0.6 * TM, 0}, Vec3(0.03, -0.02, 0.0));
  lumped_reference::expect_reduced_matches_recursive<PrbModel>(s);
}

// The banded formulation matches the recursive one under tendons, a tip force and gravity
// (backbone centroids): lumped_reference::expect_banded_matches_recursive.
TEST(PrbModel, BandedFormulationMatchesRecursive) {
  const double TM = paper::max_tension(paper::robot(6));
  Scene s = paper_scene(6, {0.3 * TM, 0, 0.6 * TM, 0}, Vec3(0.03, -0.02, 0.0));
  s.loads.gravity = Vec3(0.0, -9.81, 0.0);
  lumped_reference::expect_banded_matches_recursive<PrbModel>(s);
}

// The cold guess (fixed-point passes of Eq. 48-54 from the straight robot, prb_model.cpp): under a
// pure tip moment every joint carries the same moment whatever the shape, so the first pass is
// the answer; under tendons and a tip force (case 14 of
// benchmarks/data/paper_code_cases_inputs.csv: n = 10, tensions 0.87-1.45 T_M, 0.47 N obliquely
// down) the passes bring the direct solve from 4 exact Newton iterations (from the straight robot
// with its bending planes along the moment) to 2 exact ones and frozen ones after them, on the
// answer of a 20-step loading path. Exact Newton's count is the test's (modified Newton off).
TEST(PrbModel, ColdGuessShortensDirectSolves) {
  Scene m = paper_scene(4, {0, 0, 0, 0});
  m.loads.tip_moment = m.robot.backbone.effective_stiffness().EI * (M_PI / 2 / 0.1) * Vec3(1.0, 2.0, 0.0).normalized();
  const Solution arc = solve_prb(m);
  ASSERT_TRUE(arc.converged()) << arc.summary.message;
  EXPECT_EQ(arc.summary.iterations, 0) << arc.summary.message;

  Scene s = paper_scene(10, {8.033547215, 7.34380927063, 4.80800016499, 6.02588378056},
                        Vec3(0.334562710152, -0.00508794674257, -0.335202507993));
  Scene exact = s;
  exact.solver.reuse_jacobian = false;
  const Solution newton = solve_prb(exact);
  ASSERT_TRUE(newton.converged()) << newton.summary.message;
  EXPECT_LE(newton.summary.iterations, 2) << newton.summary.message;
  const Solution sol = solve_prb(s);
  ASSERT_TRUE(sol.converged()) << sol.summary.message;
  EXPECT_EQ(sol.summary.continuation_steps, 0);
  EXPECT_LT((sol.tip().p - newton.tip().p).norm(), 1e-9);
  // The loading path in 20 warm-started steps of all loads together.
  Solution path;
  for (int k = 1; k <= 20; ++k) {
    Scene step = s;
    for (double& t : step.actuation.values) t *= k / 20.0;
    step.loads.tip_force *= k / 20.0;
    path = k == 1 ? solve_prb(step) : solve_prb(step, &path);
    ASSERT_TRUE(path.converged()) << k << ": " << path.summary.message;
  }
  EXPECT_LT((sol.tip().p - path.tip().p).norm(), 1e-8);
}

// The stability verdict is a property of the shape, not of the chart: a subsegment's
// (theta_1..3, phi, eps) and (-theta_1..3, phi + pi, eps) are the same rigid-link chain (the plane
// turned by pi maps x' to -x', and Rz(pi) Ry(-a) Rz(-pi) = Ry(a)). A warm start from the answer
// with one subsegment written in the other chart stays there (Newton has nothing to do) and must
// give the same tip and the same margin. Without the stability test's own chart (every bend
// positive), each flipped subsegment turned the smallest eigenvalue negative.
TEST(PrbModel, StabilityDoesNotDependOnTheBendingPlaneChart) {
  const double TM = paper::max_tension(paper::robot(5));
  Scene s = paper_scene(5, {0.6 * TM, 0, 0.3 * TM, 0}, Vec3(0.2, -0.3, -0.1));
  s.solver.stability = StabilityCheck::Always;
  const PrbModel model(s.robot, s.effects);
  auto ws = model.make_workspace();
  const Solution cold = tdcr::solve(model, *ws, s.input(), s.solver);
  ASSERT_TRUE(cold.converged()) << cold.summary.message;
  ASSERT_EQ(cold.stability.status, StabilityStatus::Stable) << cold.stability.method;
  const int subsegments = static_cast<int>(cold.unknowns.size()) / 5;
  ASSERT_EQ(subsegments, 10);
  for (int j = 0; j < subsegments; j += 3) {
    SCOPED_TRACE(j);
    Solution flipped = cold;
    for (int q = 0; q < 3; ++q) flipped.unknowns[5 * j + q] = -cold.unknowns[5 * j + q];
    flipped.unknowns[5 * j + 3] = cold.unknowns[5 * j + 3] + M_PI;
    const Solution warm = tdcr::solve(model, *ws, s.input(), s.solver, &flipped);
    ASSERT_TRUE(warm.converged()) << warm.summary.message;
    EXPECT_LT(warm.unknowns.segment(5 * j, 3).sum(), 0.0);  // still in the flipped chart
    EXPECT_LT((warm.tip().p - cold.tip().p).norm(), 1e-9);
    EXPECT_EQ(warm.stability.status, StabilityStatus::Stable) << warm.stability.method;
    EXPECT_NEAR(warm.stability.margin, cold.stability.margin, 1e-4 * std::abs(cold.stability.margin));
  }
}
