// Stability of converged answers (Solution::stability) against known answers: Euler buckling of a
// cantilever column (critical tip load pi^2 EI / (4 L^2)), straight and on the loading path from
// rest (where the column's double bifurcation is a path event), and the paper robot's Table 3
// configurations.
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "tdcr/core/paper_robot.hpp"
#include "tdcr/models/static_model.hpp"

using namespace tdcr;

namespace {

// The paper robot as a column: no tension, no gravity, no shear (Euler's inextensible column),
// a tip force of `factor` times the critical load along -z plus `transverse` times it along x.
Scene column(double factor, double transverse = 0.0, bool continuation = true) {
  Scene s = paper::scene(10, 1, "vc");
  s.effects.shear_extension = false;
  const double EI = s.robot.backbone.effective_stiffness().EI;
  const double L = s.robot.total_length();
  const double Fcr = M_PI * M_PI * EI / (4.0 * L * L);
  s.loads.tip_force = Fcr * Vec3(transverse, 0.0, -factor);
  s.solver.continuation = continuation;
  s.solver.stability = StabilityCheck::Always;
  return s;
}

// Solve with the stability check forced on.
Solution solve_with(ModelKind kind, const Scene& s) {
  auto m = make_model(kind, s.robot, s.effects);
  auto ws = m->make_workspace();
  SolverOptions options = s.solver;
  options.stability = StabilityCheck::Always;
  return solve(*m, *ws, s.input(), options);
}

// A solve of scene `s` with the stability rule `check`; `warm`: warm-started from the answer of
// the paper robot's configuration 2 (n = 10) in the same workspace.
Solution solve_checked(ModelKind kind, const Scene& s, StabilityCheck check, bool warm = false) {
  auto m = make_model(kind, s.robot, s.effects);
  auto ws = m->make_workspace();
  SolverOptions options = s.solver;
  options.stability = check;
  if (!warm) return solve(*m, *ws, s.input(), options);
  const Solution start = solve(*m, *ws, paper::scene(10, 2).input(), options);
  return solve(*m, *ws, s.input(), options, &start);
}

bool not_checked(const Solution& sol) {
  return sol.stability.status == StabilityStatus::Undetermined && std::isnan(sol.stability.margin) &&
         sol.stability.method == kStabilityNotChecked;
}

double lateral(const Solution& sol) { return std::hypot(sol.tip().p.x(), sol.tip().p.y()); }

constexpr ModelKind kStaticKinds[] = {ModelKind::VC, ModelKind::CCsub, ModelKind::PRB, ModelKind::VCref};

}  // namespace

// The automatic rule (the default): a plain unloaded tension solve, cold (a direct solve) or
// warm, is not tested, and its Solution says so ("not checked").
TEST(Stability, AutomaticRuleSkipsPlainUnloadedSolves) {
  EXPECT_EQ(SolverOptions().stability, StabilityCheck::Automatic);
  Scene next = paper::scene(10, 2);
  next.actuation.values[0] *= 1.02;
  for (ModelKind kind : kStaticKinds) {
    const Solution cold = solve_checked(kind, paper::scene(10, 2), StabilityCheck::Automatic);
    ASSERT_TRUE(cold.converged()) << to_string(kind) << ": " << cold.summary.message;
    EXPECT_EQ(cold.summary.continuation_steps, 0) << to_string(kind) << ": a direct solve";
    EXPECT_TRUE(not_checked(cold)) << to_string(kind) << ": " << cold.stability.method;
    const Solution warm = solve_checked(kind, next, StabilityCheck::Automatic, true);
    ASSERT_TRUE(warm.converged()) << to_string(kind) << ": " << warm.summary.message;
    EXPECT_TRUE(not_checked(warm)) << to_string(kind) << ": " << warm.stability.method;
  }
}

// Whether the automatic rule tests a model's direct answers under external loads alone: VCref,
// whose test adds 17 % to its median loaded solve, and CCsub and PRB, whose sufficient test
// (from Newton's last Jacobian where it is near the answer) adds less than the rule's 25 %; not
// VC (75 %): docs/models.md, "Stability".
bool tests_loaded_direct_answers(ModelKind kind) { return kind != ModelKind::VC; }
bool lumped(ModelKind kind) { return kind == ModelKind::CCsub || kind == ModelKind::PRB; }

// Under moderate external loads (tip force, tip moment, gravity) a cold solve is direct and lands
// on the branch connected to rest. The automatic rule tests it in VCref, with the verdict and
// margin that forcing the test gives, and in CCsub and PRB, whose sufficient test proves it
// stable with a margin that bounds the forced eigen test's from below; VC's is not tested.
// Answers of a loading path are tested (below); true forces the test.
TEST(Stability, AutomaticRuleTestsLoadedAnswers) {
  Scene force = paper::scene(10, 2), moment = force, weight = force;
  force.loads.tip_force = Vec3(0.1, -0.05, -0.1);
  moment.loads.tip_moment = Vec3(0.0, 0.005, 0.0);
  weight.robot.segments[0].disk_mass = weight.robot.segments[1].disk_mass = 0.002;
  weight.loads.gravity = Vec3(0.0, -9.81, 0.0);
  for (const Scene* s : {&force, &moment, &weight}) {
    for (ModelKind kind : kStaticKinds) {
      const Solution sol = solve_checked(kind, *s, StabilityCheck::Automatic);
      ASSERT_TRUE(sol.converged()) << to_string(kind) << ": " << sol.summary.message;
      ASSERT_EQ(sol.summary.continuation_steps, 0) << to_string(kind) << ": a direct solve";
      const Solution forced = solve_checked(kind, *s, StabilityCheck::Always);
      EXPECT_EQ(forced.stability.status, StabilityStatus::Stable) << to_string(kind) << ": " << forced.stability.method;
      if (!tests_loaded_direct_answers(kind)) {
        EXPECT_TRUE(not_checked(sol)) << to_string(kind) << ": " << sol.stability.method;
        continue;
      }
      EXPECT_EQ(sol.stability.status, StabilityStatus::Stable) << to_string(kind) << ": " << sol.stability.method;
      if (lumped(kind)) {
        // The sufficient test: a certified lower bound of the eigen test's smallest real part.
        EXPECT_NE(sol.stability.method.find("sufficient test"), std::string::npos) << to_string(kind);
        EXPECT_GT(sol.stability.margin, 0.0) << to_string(kind);
        EXPECT_LE(sol.stability.margin, forced.stability.margin * (1.0 + 1e-4)) << to_string(kind);
        continue;
      }
      EXPECT_EQ(sol.stability.method, forced.stability.method) << to_string(kind);
      // (forced: the solve from the answer on its mesh, which may move it within the tolerance)
      EXPECT_NEAR(sol.stability.margin, forced.stability.margin, 1e-6 * forced.stability.margin) << to_string(kind);
    }
  }
}

// A direct answer under loads that is unstable: the straight column past Euler's load, Newton
// from the straight shape without continuation. The automatic rule reports it unstable in VCref,
// CCsub and PRB without asking (the lumped models' sufficient test proves nothing there and
// their eigen test decides, as forced on; VC leaves it untested); forced on, every static model
// does.
TEST(Stability, AutomaticRuleReportsAnUnstableDirectLoadedAnswer) {
  for (ModelKind kind : kStaticKinds) {
    const Scene straight = column(1.2, 0.0, false);
    const Solution sol = solve_checked(kind, straight, StabilityCheck::Automatic);
    ASSERT_TRUE(sol.converged()) << to_string(kind) << ": " << sol.summary.message;
    ASSERT_EQ(sol.summary.continuation_steps, 0) << to_string(kind) << ": a direct solve";
    EXPECT_LT(lateral(sol), 1e-9) << to_string(kind) << ": the straight branch";
    if (tests_loaded_direct_answers(kind)) {
      EXPECT_EQ(sol.stability.status, StabilityStatus::Unstable) << to_string(kind) << ": " << sol.stability.method;
      EXPECT_LT(sol.stability.margin, 0.0) << to_string(kind);
      if (lumped(kind)) {
        EXPECT_EQ(sol.stability.method.find("sufficient test"), std::string::npos) << to_string(kind);
      }
    } else {
      EXPECT_TRUE(not_checked(sol)) << to_string(kind) << ": " << sol.stability.method;
    }
    const Solution forced = solve_checked(kind, straight, StabilityCheck::Always);
    EXPECT_EQ(forced.stability.status, StabilityStatus::Unstable) << to_string(kind) << ": " << forced.stability.method;
  }
}

// CCsub and PRB under the automatic rule: a cold direct answer under a tip force carries the
// sufficient test's verdict (stable, a margin at most the eigen test's and at least half of it on
// this gently loaded robot); a trajectory's warm step from it (a small change of the force, no
// path) is not tested, as before.
TEST(Stability, LumpedLoadedDirectAnswersAreTestedByDefaultAndTheirWarmStepsAreNot) {
  Scene loaded = paper::scene(10, 2);
  loaded.loads.tip_force = Vec3(0.1, -0.05, -0.1);
  Scene next = loaded;
  next.loads.tip_force.x() += 0.002;
  for (ModelKind kind : {ModelKind::CCsub, ModelKind::PRB}) {
    auto m = make_model(kind, loaded.robot, loaded.effects);
    auto ws = m->make_workspace();
    const Solution cold = solve(*m, *ws, loaded.input(), SolverOptions());
    ASSERT_TRUE(cold.converged()) << to_string(kind) << ": " << cold.summary.message;
    ASSERT_EQ(cold.summary.continuation_steps, 0) << to_string(kind) << ": a direct solve";
    EXPECT_EQ(cold.stability.status, StabilityStatus::Stable) << to_string(kind) << ": " << cold.stability.method;
    EXPECT_NE(cold.stability.method.find("sufficient test"), std::string::npos) << to_string(kind);
    const Solution forced = solve_with(kind, loaded);
    ASSERT_EQ(forced.stability.status, StabilityStatus::Stable) << to_string(kind);
    EXPECT_LE(cold.stability.margin, forced.stability.margin * (1.0 + 1e-4)) << to_string(kind);
    EXPECT_GE(cold.stability.margin, 0.5 * forced.stability.margin * (1.0 - 1e-4)) << to_string(kind);
    const Solution warm = solve(*m, *ws, next.input(), SolverOptions(), &cold);
    ASSERT_TRUE(warm.converged()) << to_string(kind) << ": " << warm.summary.message;
    EXPECT_TRUE(not_checked(warm)) << to_string(kind) << ": " << warm.stability.method;
  }
}

// An answer reached by the loading path from rest is tested by every static model: the column
// past Euler's load (compression parameter 2.96 > 2: loaded from rest) is reported unstable
// without asking.
TEST(Stability, AutomaticRuleTestsAnswersOfALoadingPath) {
  for (ModelKind kind : kStaticKinds) {
    const Solution sol = solve_checked(kind, column(1.2), StabilityCheck::Automatic);
    ASSERT_TRUE(sol.converged()) << to_string(kind) << ": " << sol.summary.message;
    EXPECT_GT(sol.summary.continuation_steps, 0) << to_string(kind);
    EXPECT_EQ(sol.stability.status, StabilityStatus::Unstable) << to_string(kind) << ": " << sol.stability.method;
  }
}

// Accuracy-driven RK4 (the default integrator, to solver.tip_tolerance) solves the answer on
// several meshes and tests only the last one: forced on, VC and VCref report the verdict of the
// solve on the fixed mesh; automatic on a direct solve, nothing.
TEST(Stability, AccuracyDrivenRk4TestsItsLastAnswer) {
  Scene loaded = paper::scene(10, 2);
  loaded.loads.tip_force = Vec3(0.1, -0.05, -0.1);
  for (ModelKind kind : {ModelKind::VC, ModelKind::VCref}) {
    Scene fixed = loaded;
    fixed.solver.integrator = IntegratorKind::FixedStepRK4;
    const Solution plain = solve_checked(kind, fixed, StabilityCheck::Always);
    for (const bool with_force : {true, false}) {
      Scene refined = with_force ? loaded : paper::scene(10, 2);
      refined.solver.tip_tolerance = 1e-9;
      const Solution sol =
          solve_checked(kind, refined, with_force ? StabilityCheck::Always : StabilityCheck::Automatic);
      ASSERT_TRUE(sol.converged()) << to_string(kind) << ": " << sol.summary.message;
      EXPECT_GE(sol.summary.rk4_refinements, 1) << to_string(kind);
      if (!with_force) {
        EXPECT_TRUE(not_checked(sol)) << to_string(kind) << ": " << sol.stability.method;
        continue;
      }
      EXPECT_EQ(sol.stability.status, StabilityStatus::Stable) << to_string(kind) << ": " << sol.stability.method;
      EXPECT_NEAR(sol.stability.margin, plain.stability.margin, 1e-3 * plain.stability.margin) << to_string(kind);
    }
  }
}

// solver.stability true and false force the test on and off, whatever the loads.
TEST(Stability, ForcedOnAndOffAreRespected) {
  Scene loaded = paper::scene(10, 2);
  loaded.loads.tip_force = Vec3(0.1, 0.0, 0.0);
  for (ModelKind kind : kStaticKinds) {
    const Solution on = solve_checked(kind, paper::scene(10, 2), StabilityCheck::Always);
    ASSERT_TRUE(on.converged()) << to_string(kind);
    EXPECT_EQ(on.stability.status, StabilityStatus::Stable) << to_string(kind) << ": " << on.stability.method;
    EXPECT_GT(on.stability.margin, 0.0) << to_string(kind);
    const Solution off = solve_checked(kind, loaded, StabilityCheck::Never);
    ASSERT_TRUE(off.converged()) << to_string(kind);
    EXPECT_TRUE(not_checked(off)) << to_string(kind) << ": " << off.stability.method;
    const Solution path = solve_checked(kind, column(1.2), StabilityCheck::Never);
    ASSERT_TRUE(path.converged()) << to_string(kind);
    EXPECT_TRUE(not_checked(path)) << to_string(kind) << ": " << path.stability.method;
  }
}

// VC's and VCref's tests take their shots on a coarse RK4 mesh (at least 1 step per disk
// interval, steps of at most 8 mm) when the solve integrates with RK4. Their verdicts agree with
// the test on the solve's own integrator (as every test was taken before: here CVODE at rtol
// 1e-12, which keeps it) on loaded, buckled and unstable columns and robots, and their margins
// within 1e-3 relative.
TEST(Stability, CoarseMeshVerdictsAgreeWithTheSolvesIntegrator) {
  Scene bent = paper::scene(10, 5), pushed = paper::scene(5, 3), weighed = paper::scene(20, 9);
  bent.loads.tip_force = Vec3(0.3, -0.2, -0.3);
  pushed.loads.tip_force = Vec3(-0.1, 0.1, -0.45);
  pushed.loads.tip_moment = Vec3(0.002, 0.0, 0.0);
  weighed.robot.segments[0].disk_mass = weighed.robot.segments[1].disk_mass = 0.005;
  weighed.loads.gravity = Vec3(9.81, 0.0, 0.0);
  weighed.loads.tip_force = Vec3(0.0, 0.2, 0.0);
  struct Case {
    const char* name;
    Scene scene;
    StabilityStatus status;
  };
  const Case cases[] = {{"bent robot, tip force", bent, StabilityStatus::Stable},
                        {"n = 5, compressive tip force and moment", pushed, StabilityStatus::Stable},
                        {"n = 20, gravity and tip force", weighed, StabilityStatus::Stable},
                        {"column at 0.9 of Euler's load", column(0.9, 0.0, false), StabilityStatus::Stable},
                        {"column at 1.1 of Euler's load, straight", column(1.1, 0.0, false), StabilityStatus::Unstable},
                        {"column at 1.2 of Euler's load, buckled", column(1.2, 0.1), StabilityStatus::Stable}};
  for (ModelKind kind : {ModelKind::VC, ModelKind::VCref}) {
    for (const Case& c : cases) {
      const std::string name = to_string(kind) + ", " + c.name;
      Scene exact = c.scene;
      exact.solver.integrator = IntegratorKind::Cvode;
      exact.solver.cvode_rtol = 1e-12;
      exact.solver.cvode_atol = 1e-14;
      const Solution a = solve_checked(kind, c.scene, StabilityCheck::Always);
      const Solution b = solve_checked(kind, exact, StabilityCheck::Always);
      ASSERT_TRUE(a.converged() && b.converged()) << name;
      EXPECT_LT((a.tip().p - b.tip().p).norm(), 1e-6) << name << ": the same equilibrium";
      EXPECT_EQ(a.stability.status, c.status) << name << ": " << a.stability.method;
      EXPECT_EQ(b.stability.status, c.status) << name << ": " << b.stability.method;
      EXPECT_NEAR(a.stability.margin, b.stability.margin, 1e-3 * std::abs(b.stability.margin) + 1e-6)
          << name << ": " << a.stability.margin << " (coarse mesh) vs " << b.stability.margin;
    }
  }
}


// Below the critical load the straight column is stable, above it the straight column is
// unstable (Newton started on the straight shape, no continuation: it stays there). For VC this
// is a double conjugate point (the round column buckles in both planes at once), which the sign
// of det M(s) missed; vc_stability.cpp counts conjugate points with their multiplicity.
TEST(Stability, EulerColumnStraightBranch) {
  for (ModelKind kind : kStaticKinds) {
    const std::string name = to_string(kind);
    const Solution below = solve_with(kind, column(0.8));
    ASSERT_TRUE(below.converged()) << name << ": " << below.summary.message;
    EXPECT_EQ(below.stability.status, StabilityStatus::Stable) << name << ": " << below.stability.method;
    EXPECT_GT(below.stability.margin, 0.0) << name;

    const Solution above = solve_with(kind, column(1.2, 0.0, false));
    ASSERT_TRUE(above.converged()) << name << ": " << above.summary.message;
    EXPECT_LT(lateral(above), 1e-9) << name << ": the straight branch";
    EXPECT_EQ(above.stability.status, StabilityStatus::Unstable) << name << ": " << above.stability.method;
    EXPECT_LT(above.stability.margin, 0.0) << name;
  }
}

// VC: just below the critical load the margin is small and positive (the first conjugate point
// approaches the base).
TEST(Stability, VcMarginSmallBelowTheCriticalLoad) {
  const Solution a = solve_with(ModelKind::VC, column(0.99, 0.0, false));
  const Solution b = solve_with(ModelKind::VC, column(0.5, 0.0, false));
  ASSERT_TRUE(a.converged() && b.converged());
  EXPECT_EQ(a.stability.status, StabilityStatus::Stable);
  EXPECT_GT(a.stability.margin, 0.0);
  EXPECT_LT(a.stability.margin, 0.05);
  EXPECT_GT(b.stability.margin, 5.0 * a.stability.margin);
}

// Above the critical load with a tiny transverse imperfection the column buckles; the buckled
// shape is stable. (Reached through a larger imperfection: from the straight guess Newton finds
// the unstable near-straight equilibrium of the imperfect column.)
TEST(Stability, BuckledColumnIsStable) {
  for (ModelKind kind : {ModelKind::VC, ModelKind::PRB, ModelKind::VCref}) {
    const std::string name = to_string(kind);
    const Scene s = column(1.2, 1e-3);
    auto m = make_model(kind, s.robot, s.effects);
    auto ws = m->make_workspace();
    const Solution bent = solve(*m, *ws, column(1.2, 0.1).input(), s.solver);
    ASSERT_TRUE(bent.converged()) << name << ": " << bent.summary.message;
    const Solution sol = solve(*m, *ws, s.input(), s.solver, &bent);
    ASSERT_TRUE(sol.converged()) << name << ": " << sol.summary.message;
    EXPECT_GT(lateral(sol), 0.01) << name << ": buckled";
    EXPECT_EQ(sol.stability.status, StabilityStatus::Stable) << name << ": " << sol.stability.method << " "
                                                             << sol.stability.margin;
  }
}

// Every configuration of the case study (Table 3) is stable; CC is a kinematic model and does
// not decide.
TEST(Stability, PaperConfigurationsAreStable) {
  for (int c = 1; c <= 16; ++c) {
    for (ModelKind kind : kStaticKinds) {
      const Solution sol = solve_with(kind, paper::scene(10, c));
      ASSERT_TRUE(sol.converged()) << to_string(kind) << " configuration " << c;
      EXPECT_EQ(sol.stability.status, StabilityStatus::Stable)
          << to_string(kind) << " configuration " << c << ": " << sol.stability.method << " " << sol.stability.margin;
    }
    const Solution cc = solve_with(ModelKind::CC, paper::scene(10, c));
    EXPECT_EQ(cc.stability.status, StabilityStatus::Undetermined);
    EXPECT_FALSE(cc.stability.method.empty());
  }
}

// VCref: the smallest eigenvalue of the reduced stiffness of the straight column is linear in
// the load and changes sign at Euler's critical load (the rods between the disks are exact
// Cosserat rods): symmetric about it to 5 %, and half as large at 0.99 as at 0.98.
TEST(Stability, VcrefMarginChangesSignAtTheCriticalLoad) {
  const Solution a = solve_with(ModelKind::VCref, column(0.98, 0.0, false));
  const Solution b = solve_with(ModelKind::VCref, column(0.99, 0.0, false));
  const Solution c = solve_with(ModelKind::VCref, column(1.01, 0.0, false));
  ASSERT_TRUE(a.converged() && b.converged() && c.converged());
  EXPECT_EQ(b.stability.status, StabilityStatus::Stable) << b.stability.margin;
  EXPECT_EQ(c.stability.status, StabilityStatus::Unstable) << c.stability.margin;
  EXPECT_NEAR(b.stability.margin, -c.stability.margin, 0.05 * b.stability.margin);
  EXPECT_NEAR(a.stability.margin, 2.0 * b.stability.margin, 0.05 * b.stability.margin);
}

// VC: the margin (the smallest singular value of M(s), negative from the first conjugate point
// on) changes sign at Euler's load: the rod is continuous, so its critical load is Euler's
// whatever the disks (n = 5 and 20 alike), up to the RK4 error of the Jacobi fields. Measured:
// +-0.00331 at 0.995 and 1.005, zero at 1.000 to 1e-9.
TEST(Stability, VcMarginChangesSignAtTheCriticalLoad) {
  for (int n : {5, 20}) {
    Scene below = column(0.995, 0.0, false), above = column(1.005, 0.0, false);
    below.robot = above.robot = paper::scene(n, 1, "vc").robot;
    const Solution b = solve_with(ModelKind::VC, below), c = solve_with(ModelKind::VC, above);
    ASSERT_TRUE(b.converged() && c.converged());
    EXPECT_EQ(b.stability.status, StabilityStatus::Stable) << n << ": " << b.stability.margin;
    EXPECT_EQ(c.stability.status, StabilityStatus::Unstable) << n << ": " << c.stability.margin;
    EXPECT_NEAR(b.stability.margin, -c.stability.margin, 0.01 * b.stability.margin) << n;
  }
}

namespace {

// The paper robot as a column (column()) with n disks per segment, loaded from rest to `factor`
// times Euler's load.
Solution column_on_loading_path(ModelKind kind, int n, double factor) {
  Scene s = column(factor);
  s.robot = paper::scene(n, 1, "vc").robot;
  const double EI = s.robot.backbone.effective_stiffness().EI, L = s.robot.total_length();
  s.loads.tip_force = Vec3(0.0, 0.0, -factor * M_PI * M_PI * EI / (4.0 * L * L));
  return solve_with(kind, s);
}

// The model's critical load over Euler's, from the bifurcation event on the loading path to 1.2
// times Euler's load (NaN if the path did not report exactly one).
double critical_load(ModelKind kind, int n) {
  const Solution sol = column_on_loading_path(kind, n, 1.2);
  EXPECT_TRUE(sol.converged()) << to_string(kind) << " n = " << n << ": " << sol.summary.message;
  EXPECT_LT(lateral(sol), 1e-9) << to_string(kind) << " n = " << n << ": the straight branch";
  EXPECT_EQ(sol.stability.status, StabilityStatus::Unstable) << to_string(kind) << " n = " << n;
  if (sol.path_events.size() != 1 || sol.path_events[0].type != PathEvent::Type::Bifurcation) {
    ADD_FAILURE() << to_string(kind) << " n = " << n << ": " << sol.path_events.size() << " path events; "
                  << sol.summary.message;
    return NAN;
  }
  return 1.2 * sol.path_events[0].load_fraction;
}

}  // namespace

// Loaded from rest past Euler's load, the straight column loses stability at a bifurcation of
// even multiplicity (both bending planes at once, so the path's determinant keeps its sign). The
// path reports it as an event where the model's own critical load lies, and stays on the
// straight branch, whose answer is unstable (docs/models.md, "Stability"). Below that load the
// path has no event and the answer is stable. Each model's critical load, over Euler's:
// - VC and VCref: Euler's (a continuous rod; rods between the disks), to the event's location
//   tolerance 1e-5 and the coarse path mesh's RK4 error: measured 1.000000 at n = 10.
// - CCsub: each subsegment's curvature from the moment at its proximal end, a first-order rule
//   in the subsegment length: 0.97679 at n = 10, 0.98796 at n = 20 (errors 0.232 / n, 0.241 / n),
//   whose Richardson extrapolation 2 P(20) - P(10) = 0.99913 is second order (0.99977 from
//   n = 20 and 40).
// - PRB: the chain's bending compliance per length is sum(1 / k_theta) / EI (0.99879 with Table 1's
//   k_theta), so its limit is Euler's load over that sum, 1.00121; 1.00109 at n = 10 (1.00084 at
//   n = 5, 1.00117 at n = 20: second order).
TEST(Stability, EulerCriticalLoadIsABifurcationOfTheLoadingPath) {
  for (ModelKind kind : kStaticKinds) {
    const Solution below = column_on_loading_path(kind, 10, 0.9);
    ASSERT_TRUE(below.converged()) << to_string(kind) << ": " << below.summary.message;
    EXPECT_EQ(below.stability.status, StabilityStatus::Stable) << to_string(kind) << ": " << below.stability.method;
    EXPECT_TRUE(below.path_events.empty()) << to_string(kind) << ": " << below.summary.message;
  }
  EXPECT_NEAR(critical_load(ModelKind::VC, 10), 1.0, 1e-4);
  EXPECT_NEAR(critical_load(ModelKind::VCref, 10), 1.0, 1e-4);
  const double ccsub10 = critical_load(ModelKind::CCsub, 10), ccsub20 = critical_load(ModelKind::CCsub, 20);
  EXPECT_LT(ccsub10, ccsub20);
  EXPECT_LT(ccsub20, 1.0);
  EXPECT_NEAR(1.0 - ccsub10, 0.25 / 10, 0.03 / 10);  // first order: c / n, c -> 0.245
  EXPECT_NEAR(2.0 * ccsub20 - ccsub10, 1.0, 2e-3);   // its Richardson extrapolation: second order
  const PrbParameters prb;
  const double compliance = 1.0 / prb.k_theta[0] + 1.0 / prb.k_theta[1] + 1.0 / prb.k_theta[2];
  EXPECT_NEAR(critical_load(ModelKind::PRB, 10), 1.0 / compliance, 3e-4);
}

// The reported scene: a soft straight robot (the paper robot with E x 0.25, 20 disks per
// segment, shear and extension on), no tension, a tip force (0, 0, -0.3 N) above its Euler load
// pi^2 EI / (4 L^2) = 0.2617 N. Every static model, with the disk normal forces of Eq. 58 kept
// or removed (no tension: the same loads), converges on the straight branch, unstable, with the
// bifurcation on its loading path where its own critical load lies: within 1.3 % of Euler's
// (CCsub's first-order error at n = 20, 0.0120; the others within 1.2e-3, PRB's Table 1 bias).
TEST(Stability, SoftColumnPastItsBucklingLoadIsReported) {
  Scene s = paper::scene(20, 1, "vc");
  s.robot.backbone.youngs_modulus *= 0.25;
  s.actuation.values.assign(s.actuation.values.size(), 0.0);
  const double EI = s.robot.backbone.effective_stiffness().EI, L = s.robot.total_length();
  const double euler = M_PI * M_PI * EI / (4.0 * L * L);
  ASSERT_NEAR(euler, 0.2617, 1e-4);
  s.loads.tip_force = Vec3(0.0, 0.0, -0.3);
  for (ModelKind kind : kStaticKinds) {
    for (DiskNormalForce d : {DiskNormalForce::Kept, DiskNormalForce::Removed}) {
      if (kind == ModelKind::VC && d == DiskNormalForce::Kept) continue;  // VC has no Eq. 58
      s.effects.disk_normal_force = d;
      const std::string name = to_string(kind) + (d == DiskNormalForce::Kept ? " kept" : " removed");
      const Solution sol = solve_with(kind, s);
      ASSERT_TRUE(sol.converged()) << name << ": " << sol.summary.message;
      EXPECT_LT(lateral(sol), 1e-9) << name << ": the straight branch";
      EXPECT_EQ(sol.stability.status, StabilityStatus::Unstable) << name << ": " << sol.stability.method;
      ASSERT_EQ(sol.path_events.size(), 1u) << name << ": " << sol.summary.message;
      EXPECT_EQ(sol.path_events[0].type, PathEvent::Type::Bifurcation) << name;
      const double critical = 0.3 * sol.path_events[0].load_fraction / euler;
      EXPECT_NEAR(critical, 1.0, kind == ModelKind::CCsub ? 0.013 : 1.3e-3) << name;
    }
  }
}
