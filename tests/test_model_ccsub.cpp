// Tests of the CCsub model (paper Eq. 8, 30-33, 43-47): analytic cases, symmetry, global
// equilibrium, failure reporting, and the paper's own code as reference data.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "tdcr/core/lie.hpp"
#include "tdcr/core/metrics.hpp"
#include "tdcr/core/paper_robot.hpp"
#include "lumped_reference.hpp"
#include "tdcr/models/ccsub.hpp"
#include "tdcr/models/model_registry.hpp"
#include "tdcr/models/tendon_physics.hpp"

using namespace tdcr;

namespace {

using lumped_reference::RefRow;
using lumped_reference::load_reference;

Scene paper_scene(int n, const std::vector<double>& T, const Vec3& F = Vec3::Zero()) {
  Scene s = paper::scene(n, 1, "ccsub");
  s.actuation.values = T;
  s.loads.tip_force = F;
  return s;
}

Solution solve_ccsub(const Scene& s, const Solution* warm = nullptr) {
  const CcsubModel model(s.robot, s.effects);
  auto ws = model.make_workspace();
  return tdcr::solve(model, *ws, s.input(), s.solver, warm);
}

}  // namespace

// 1. No tension, no load: the straight robot, with its disks where the routing puts them.
TEST(CcsubModel, ZeroTensionIsStraight) {
  const Scene s = paper_scene(5, {0, 0, 0, 0});
  const Solution sol = solve_ccsub(s);
  ASSERT_TRUE(sol.converged()) << sol.summary.message;
  ASSERT_EQ(sol.disk_frames.size(), 11u);
  for (std::size_t j = 0; j < sol.disk_frames.size(); ++j) {
    EXPECT_NEAR((sol.disk_frames[j].p - Vec3(0, 0, 0.01 * j)).norm(), 0.0, 1e-15);
    EXPECT_NEAR((sol.disk_frames[j].R - Mat3::Identity()).norm(), 0.0, 1e-15);
  }
  for (double d : sol.tendon_displacements) EXPECT_NEAR(d, 0.0, 1e-15);
}

// 2. A pure tip moment bends every subsegment into an arc of curvature M/EI (Eq. 43 with the
// moment constant along the robot): the tip is exactly on the circle, for any moment direction,
// here 90 deg about an oblique axis, and 200 deg (beyond a half turn).
TEST(CcsubModel, PureTipMomentGivesExactArc) {
  for (double angle_deg : {90.0, 200.0}) {
    Scene s = paper_scene(4, {0, 0, 0, 0});
    const double EI = s.robot.backbone.effective_stiffness().EI;
    const double L = 0.1;
    const double kappa = angle_deg * M_PI / 180.0 / L;
    const Vec3 axis = Vec3(1.0, 2.0, 0.0).normalized();
    s.loads.tip_moment = EI * kappa * axis;
    const Solution sol = solve_ccsub(s);
    ASSERT_TRUE(sol.converged()) << sol.summary.message;
    for (std::size_t j = 0; j < sol.disk_frames.size(); ++j) {
      const double sj = 0.0125 * j;
      const Frame ex = lie::exp_se3(kappa * sj * axis, Vec3(0, 0, sj));
      EXPECT_LT((sol.disk_frames[j].p - ex.p).norm(), 1e-10 * L) << angle_deg << " disk " << j;
      EXPECT_LT(lie::rotation_angle(sol.disk_frames[j].R, ex.R), 1e-10) << angle_deg << " disk " << j;
    }
  }
}

// A pure torsional tip moment twists the straight robot by M L / GJ (St Venant). Tolerance: the
// Newton tolerance 1e-10 on each scaled twist residual (GJ/EI) eps_j, summed over 3 subsegments.
TEST(CcsubModel, PureTorsionTwistsStraightRobot) {
  Scene s = paper_scene(3, {0, 0, 0, 0});
  const double GJ = s.robot.backbone.effective_stiffness().GJ;
  const double twist = 0.7;
  s.loads.tip_moment = Vec3(0, 0, GJ * twist / 0.1);
  const Solution sol = solve_ccsub(s);
  ASSERT_TRUE(sol.converged());
  EXPECT_NEAR((sol.tip().p - Vec3(0, 0, 0.1)).norm(), 0.0, 1e-12);
  EXPECT_LT(lie::rotation_angle(sol.tip().R, lie::rot_z(twist)), 1e-9);
}

// 2c. Axial compression (effects.shear_extension, the default): one segment bent by one tendon,
// its antagonist pulled too, so every subsegment carries T1 + T2 and shortens by (T1 + T2) / EA of
// its length. The tendons' moment in the frame of each disk does not depend on the shape (straight
// routing, no external load), so the bend is the inextensible one's and the compressed tip is the
// inextensible tip scaled towards the base by 1 - (T1 + T2) / EA, to rounding (measured 7e-18 m).
TEST(CcsubModel, TendonsCompressTheSubsegmentsAlongTheArc) {
  Robot r = paper::robot(10);
  r.segments.resize(1);
  const std::vector<double> T = {4.0, 1.5};
  Effects on, off;
  off.shear_extension = false;
  ModelInput in;
  in.actuation.values = T;
  const auto a = make_model(ModelKind::CCsub, r, on), b = make_model(ModelKind::CCsub, r, off);
  auto wa = a->make_workspace(), wb = b->make_workspace();
  const Solution sa = tdcr::solve(*a, *wa, in, SolverOptions{}), sb = tdcr::solve(*b, *wb, in, SolverOptions{});
  ASSERT_TRUE(sa.converged() && sb.converged());
  const double eps = (T[0] + T[1]) / r.backbone.effective_stiffness().EA, L = r.total_length();
  const double shift = (sa.tip().p - sb.tip().p).norm();
  const double scaled = (sa.tip().p - (1.0 - eps) * sb.tip().p).norm();
  std::printf("compression eps %.3g: tip moved %.4g m (eps L = %.4g m), off the scaled tip by %.3g m\n", eps, shift,
              eps * L, scaled);
  EXPECT_GT(shift, 0.5 * eps * L);
  EXPECT_LT(shift, 2.0 * eps * L);
  EXPECT_LT(scaled, 1e-15);
}

// 3. Mirror symmetry about the x-z plane: T1 <-> T2 (and T3 <-> T4) with the transverse force
// mirrored gives the mirrored shape.
TEST(CcsubModel, MirrorSymmetry) {
  const double TM = paper::max_tension(paper::robot(5));
  const Solution a = solve_ccsub(paper_scene(5, {TM, 0.2 * TM, 0.5 * TM, 0}, Vec3(0.1, 0.2, 0.05)));
  const Solution b = solve_ccsub(paper_scene(5, {0.2 * TM, TM, 0, 0.5 * TM}, Vec3(0.1, -0.2, 0.05)));
  ASSERT_TRUE(a.converged());
  ASSERT_TRUE(b.converged());
  const Mat3 S = Vec3(1, -1, 1).asDiagonal();
  for (std::size_t j = 0; j < a.disk_frames.size(); ++j) {
    EXPECT_NEAR((S * a.disk_frames[j].p - b.disk_frames[j].p).norm(), 0.0, 1e-12);
    // Mirrored frame: S R S (a reflection of a right-handed frame, re-reflected in y).
    EXPECT_NEAR((S * a.disk_frames[j].R * S - b.disk_frames[j].R).norm(), 0.0, 1e-10);
  }
  EXPECT_GT(std::abs(a.tip().p.x()), 1e-3);  // the transverse force moved it out of plane
}

// 4. The paper's own code (rows with a converged residual, chisq < 1e-12): same model, same
// tip. Tolerance 0.05 % of 2L and 0.05 deg, twice that at n <= 3.
TEST(CcsubModel, MatchesPaperCodeReferenceRows) {
  const std::vector<RefRow> rows = load_reference();
  int compared = 0;
  double worst_p = 0.0, worst_R = 0.0;
  for (const RefRow& r : rows) {
    if (r.model != "CCsub" || r.residual >= 1e-12) continue;
    const Solution sol = solve_ccsub(paper_scene(r.n, {r.T[0], r.T[1], r.T[2], r.T[3]}, Vec3(r.F[0], r.F[1], r.F[2])));
    ASSERT_TRUE(sol.converged()) << r.source << " " << r.id << " n=" << r.n << ": " << sol.summary.message;
    const TipError e = tip_error(sol.tip(), r.tip);
    const double f = r.n <= 3 ? 2.0 : 1.0;
    EXPECT_LT(e.position, f * 5e-5) << r.source << " " << r.id << " n=" << r.n;
    EXPECT_LT(e.angle * 180.0 / M_PI, f * 0.05) << r.source << " " << r.id << " n=" << r.n;
    worst_p = std::max(worst_p, e.position);
    worst_R = std::max(worst_R, e.angle);
    ++compared;
  }
  EXPECT_GE(compared, 150);
  std::printf("CCsub vs paper code: %d rows, max tip error %.3g m, %.3g deg\n", compared, worst_p,
              worst_R * 180.0 / M_PI);
}

// 6. For n > 5 CCsub approaches the Cosserat rod VC (paper Fig. 10): against the paper code's VC
// at n = 10 over the 16 configurations (rows of the reference file).
TEST(CcsubModel, CloseToVcAtTenDisks) {
  const std::vector<RefRow> rows = load_reference();
  std::vector<Frame> tips, refs;
  for (const RefRow& r : rows) {
    if (r.model != "VC" || r.n != 10) continue;
    const Solution sol = solve_ccsub(paper_scene(10, {r.T[0], r.T[1], r.T[2], r.T[3]}));
    ASSERT_TRUE(sol.converged());
    tips.push_back(sol.tip());
    refs.push_back(r.tip);
  }
  ASSERT_EQ(tips.size(), 16u);
  const MeanTipError e = mean_tip_error(tips, refs, 0.1);
  std::printf("CCsub vs VC (paper code) n=10: e_p %.4f %%, e_R %.4f deg (max %.4f %%)\n", e.e_p_percent, e.e_R_deg,
              e.max_p_percent);
  EXPECT_LT(e.e_p_percent, 1.0);
  EXPECT_LT(e.e_R_deg, 1.0);
}

// 7. Global equilibrium: with gravity (backbone and disks), a tip force and moment, 3 segments
// of 4 tendons at arbitrary angles, the reaction at the base balances all external loads.
// Subsegment 1's residual is the moment balance about the base, so the base moment from the
// constitutive law must equal the moment of every load about the base, computed here directly.
TEST(CcsubModel, GlobalEquilibriumWithGravityAndTipForce) {
  Scene s;
  s.model = "ccsub";
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
  const CcsubModel model(s.robot, s.effects);
  auto ws = model.make_workspace();
  const Solution sol = tdcr::solve(model, *ws, s.input(), s.solver);
  ASSERT_TRUE(sol.converged()) << sol.summary.message;
  ASSERT_EQ(sol.disk_frames.size(), 16u);

  // Base moment from the solution's first subsegment (Eq. 43): EI u_1 + GJ eps_1 / l_1 z_1.
  const BackboneStiffness k = s.robot.backbone.effective_stiffness();
  const TendonRouting routing = TendonRouting::from(s.robot);
  const double l1 = routing.disk_s[1];
  const Vec3 u1(sol.unknowns[0] / l1, sol.unknowns[1] / l1, 0.0);
  const Vec3 m_internal = k.EI * u1 + k.GJ * sol.unknowns[2] / l1 * sol.disk_frames[1].R.col(2);

  // Moment about the base of all external loads acting on the robot distal of the base disk:
  // tendon forces on disks 1..N, disk weights, tip wrench, backbone weight (integrated by
  // Simpson's rule along each arc, independent of the model's closed-form centroid).
  Vec3 m_loads = s.loads.tip_moment + sol.tip().p.cross(s.loads.tip_force);
  const int N = routing.disk_count() - 1;
  const double rhoA = s.robot.backbone.linear_mass();
  for (int j = 1; j <= N; ++j) {
    const tendon::DiskWrench w = tendon::disk_wrench(j, sol.disk_frames.data(), routing, s.actuation.values.data(),
                                                         s.effects.disk_normal_force == DiskNormalForce::Removed);
    m_loads += w.moment + sol.disk_frames[j].p.cross(w.force);
    const double mass = s.robot.segments[routing.disk_segment[j]].disk_mass;
    m_loads += sol.disk_frames[j].p.cross(mass * s.loads.gravity);
    const double l = routing.disk_s[j] - routing.disk_s[j - 1];
    const Vec3 u(sol.unknowns[3 * (j - 1)] / l, sol.unknowns[3 * (j - 1) + 1] / l, 0.0);
    // Shear and extension (the default): the tendons through subsegment j shorten it by their
    // tensions over EA, its bend unchanged, so its points scale.
    double through = 0.0;
    for (const RoutedTendon& t : routing.tendons)
      if (t.end_disk >= j) through += s.actuation.values[static_cast<std::size_t>(t.index)];
    const double stretch = 1.0 - through / k.EA;
    const int K = 64;
    for (int q = 0; q <= K; ++q) {
      const double t = l * q / K;
      const double wq = (q == 0 || q == K) ? 1.0 : (q % 2 ? 4.0 : 2.0);
      const Vec3 p = sol.disk_frames[j - 1].transform(stretch * lie::exp_se3(u * t, Vec3(0, 0, t)).p);
      m_loads += (wq * l / (3.0 * K)) * p.cross(rhoA * s.loads.gravity);
    }
  }
  EXPECT_LT((m_internal - m_loads).norm(), 1e-9 * m_loads.norm()) << m_internal.transpose() << " vs " << m_loads.transpose();
  EXPECT_GT(m_loads.norm(), 1e-3);
}

// A solve that cannot converge reports failure with its residual and iterations, never success.
TEST(CcsubModel, NonConvergentSolveReportsFailure) {
  const double TM = paper::max_tension(paper::robot(10));
  Scene s = paper_scene(10, {6 * TM, 0, 6 * TM, 0}, Vec3(0, 2.0, 0));
  s.solver.max_iterations = 2;
  s.solver.continuation = false;  // a direct failure, not rescued by continuation
  const Solution sol = solve_ccsub(s);
  EXPECT_FALSE(sol.converged());
  EXPECT_EQ(sol.summary.termination, TerminationType::MaxIterations) << sol.summary.message;
  EXPECT_GT(sol.summary.residual_norm, sol.summary.function_tolerance);
  EXPECT_GT(sol.summary.iterations, 0);
  EXPECT_FALSE(sol.summary.message.empty());
}

// Warm start: solving again from a previous solution converges at once to the same answer.
TEST(CcsubModel, WarmStartFromPreviousSolution) {
  const double TM = paper::max_tension(paper::robot(10));
  const Scene s = paper_scene(10, {TM, 0, 0.5 * TM, 0}, Vec3(0.1, 0, 0));
  const CcsubModel model(s.robot, s.effects);
  auto ws = model.make_workspace();
  const Solution cold = tdcr::solve(model, *ws, s.input(), s.solver);
  ASSERT_TRUE(cold.converged());
  const Solution warm = tdcr::solve(model, *ws, s.input(), s.solver, &cold);
  ASSERT_TRUE(warm.converged());
  EXPECT_LE(warm.summary.iterations, 1);
  EXPECT_LT(cold.summary.iterations, 30);
  EXPECT_LT((warm.tip().p - cold.tip().p).norm(), 1e-12);
}

// Unloaded distal subsegments are straight and are no unknowns; loaded ones are.
TEST(CcsubModel, OnlyLoadedSubsegmentsAreUnknowns) {
  const double TM = paper::max_tension(paper::robot(10));
  const Solution a = solve_ccsub(paper_scene(10, {TM, 0, 0, 0}));
  EXPECT_EQ(a.summary.unknowns, 30);
  EXPECT_EQ(a.unknowns.size(), 60);
  for (int j = 10; j < 20; ++j)
    EXPECT_NEAR((a.disk_frames[j + 1].p - a.disk_frames[j].p - 0.005 * a.disk_frames[j].R.col(2)).norm(), 0.0, 1e-15);
  const Solution b = solve_ccsub(paper_scene(10, {0, 0, TM, 0}));
  EXPECT_EQ(b.summary.unknowns, 60);
}

// A trajectory on one model and one workspace: a Solution of an input that loads segment 1 only
// (J = N/2) warm-starts an input that loads every subsegment, and back.
TEST(CcsubModel, WarmStartAcrossInputsWithOtherLoadedSubsegments) {
  const double TM = paper::max_tension(paper::robot(10));
  const Scene a = paper_scene(10, {TM, 0, 0, 0});
  const Scene b = paper_scene(10, {TM, 0, 0.2 * TM, 0});
  const CcsubModel model(a.robot, a.effects);
  auto ws = model.make_workspace();
  const Solution sa = tdcr::solve(model, *ws, a.input(), a.solver);
  ASSERT_TRUE(sa.converged());
  const Solution sb = tdcr::solve(model, *ws, b.input(), b.solver, &sa);
  ASSERT_TRUE(sb.converged()) << sb.summary.message;
  EXPECT_EQ(sb.summary.unknowns, 60);
  const Solution sb_cold = solve_ccsub(b);
  EXPECT_LT((sb.tip().p - sb_cold.tip().p).norm(), 1e-9);
  const Solution sa2 = tdcr::solve(model, *ws, a.input(), a.solver, &sb);
  ASSERT_TRUE(sa2.converged());
  EXPECT_LT((sa2.tip().p - sa.tip().p).norm(), 1e-9);
}

// Reduced Newton steps (Automatic, 100 loaded subsegments) match the recursive form.
TEST(CcsubModel, ReducedNewtonMatchesRecursive) {
  const double TM = paper::max_tension(paper::robot(50));
  const Scene s = paper_scene(50, {0.3 * TM, 0, 0.6 * TM, 0}, Vec3(0.03, -0.02, 0.0));
  lumped_reference::expect_reduced_matches_recursive<CcsubModel>(s);
}

// The banded formulation matches the recursive one under tendons, a tip force and gravity
// (backbone centroids): lumped_reference::expect_banded_matches_recursive.
TEST(CcsubModel, BandedFormulationMatchesRecursive) {
  const double TM = paper::max_tension(paper::robot(6));
  Scene s = paper_scene(6, {0.3 * TM, 0, 0.6 * TM, 0}, Vec3(0.03, -0.02, 0.0));
  s.loads.gravity = Vec3(0.0, -9.81, 0.0);
  lumped_reference::expect_banded_matches_recursive<CcsubModel>(s);
}

// The cold guess (fixed-point passes of Eq. 43 from the straight robot, ccsub_model.cpp): under a
// pure tip moment the moment is the same in every subsegment's frame whatever the shape, so the
// first pass is already the exact arc and Newton has nothing left to do.
TEST(CcsubModel, ColdGuessIsTheExactArcUnderPureTipMoment) {
  for (double angle_deg : {90.0, 200.0}) {
    Scene s = paper_scene(4, {0, 0, 0, 0});
    const double EI = s.robot.backbone.effective_stiffness().EI;
    s.loads.tip_moment = EI * (angle_deg * M_PI / 180.0 / 0.1) * Vec3(1.0, 2.0, 0.0).normalized();
    const Solution sol = solve_ccsub(s);
    ASSERT_TRUE(sol.converged()) << sol.summary.message;
    EXPECT_EQ(sol.summary.iterations, 0) << angle_deg << " deg: " << sol.summary.message;
  }
}

// ... and under tendons and a tip force (case 14 of benchmarks/data/paper_code_cases_inputs.csv:
// n = 10, tensions 0.87-1.45 T_M, 0.47 N obliquely down, load parameter 1.3) the passes bring
// the direct solve from 8 Newton iterations (from the straight robot) to 3, on the paper code's
// answer (benchmarks/data/paper_code_cases_timing.csv, CCsub row of case 14).
TEST(CcsubModel, ColdGuessShortensLoadedDirectSolve) {
  const Scene s = paper_scene(10, {8.033547215, 7.34380927063, 4.80800016499, 6.02588378056},
                              Vec3(0.334562710152, -0.00508794674257, -0.335202507993));
  const Solution sol = solve_ccsub(s);
  ASSERT_TRUE(sol.converged()) << sol.summary.message;
  EXPECT_EQ(sol.summary.continuation_steps, 0);
  EXPECT_LE(sol.summary.iterations, 4) << sol.summary.message;
  EXPECT_LT((sol.tip().p - Vec3(0.0344213906525212, -0.00906305256452425, 0.0918165235558875)).norm(), 1e-8);
}
