// Tests of capstan tendon friction in VC (models/vc/vc_friction.hpp, docs/models.md "Tendon
// friction"): the tension as a state along the fully constrained path. The friction path with
// no loss is the frictionless model, the capstan law on a planar bend, convergence to VCref's
// per-disk friction, hysteresis, global equilibrium, and displacement input.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "tdcr/core/error.hpp"
#include "tdcr/core/paper_robot.hpp"
#include "tdcr/models/static_model.hpp"
#include "tdcr/models/vc.hpp"
#include "tdcr/models/verification.hpp"
#include "fixed_mesh_settings.hpp"

using namespace tdcr;

namespace {

using Motion = TendonFriction::Motion;

Solution solve_with(ModelKind kind, const Robot& robot, const Effects& effects, const ModelInput& in) {
  const auto model = make_model(kind, robot, effects);
  auto ws = model->make_workspace();
  return tdcr::solve(*model, *ws, in, test::fixed_mesh_settings(), nullptr);
}

ModelInput tensions(const std::vector<double>& T, const Vec3& tip_force = Vec3::Zero()) {
  ModelInput in;
  in.actuation.values = T;
  in.loads.tip_force = tip_force;
  return in;
}

Effects friction(double mu, Motion motion) {
  Effects e;
  e.tendon_friction.coefficient = mu;
  e.tendon_friction.motion = motion;
  return e;
}

// One segment of the paper robot with a single tendon at +y.
Robot one_tendon_robot(int disks) {
  Robot r = paper::robot(disks);
  r.segments.resize(1);
  r.segments[0].tendons.resize(1);
  return r;
}

// Angle between the base axis and the tip disk's axis (rad).
double bend(const Solution& s) { return std::acos(std::min(1.0, s.disk_frames.back().R(2, 2))); }

double tip_distance(const Solution& a, const Solution& b) {
  return (a.disk_frames.back().p - b.disk_frames.back().p).norm();
}

}  // namespace

// The friction code path (tension states, friction fixed point) with no loss: friction on only
// for a tendon without tension. The answer is the frictionless one to rounding, with and
// without shear/extension, under a tip force.
TEST(VcFriction, NoLossIsTheFrictionlessAnswer) {
  const Scene s = paper::scene(5, 6, "vc");
  std::vector<double> T = s.actuation.values;
  T[3] = 0.0;
  T[0] = std::max(T[0], 1.0);
  const ModelInput in = tensions(T, Vec3(0.05, -0.02, -0.1));
  for (bool shear : {true, false}) {
    Effects off = s.effects;
    off.shear_extension = shear;
    Effects on = off;
    on.tendon_friction.coefficients = {0.0, 0.0, 0.0, 0.4};
    const Solution a = solve_with(ModelKind::VC, s.robot, off, in);
    const Solution b = solve_with(ModelKind::VC, s.robot, on, in);
    ASSERT_TRUE(a.converged() && b.converged()) << b.summary.message;
    EXPECT_LT(tip_distance(a, b), 1e-12) << "shear " << shear;
    ASSERT_EQ(b.tendon_end_tensions.size(), 4u);
    for (int k = 0; k < 4; ++k) EXPECT_NEAR(b.tendon_end_tensions[k], T[k], 1e-12 * T[0]) << k;
    EXPECT_TRUE(a.tendon_end_tensions.empty());
  }
}

// Capstan law: one tendon bends one segment in a plane; along the continuous path the tension
// follows T0 exp(-/+ mu theta(s)), theta the tendon's turning angle from the base axis, which at
// the end is the tip disk's tilt (the path's tangent is the disk axis on a planar bend, up to a
// shear tilt of order T/GA). Pulling bends less than frictionless, releasing more, and the
// released tendon ends above its base tension.
TEST(VcFriction, CapstanLawOnAPlanarBend) {
  const Robot robot = one_tendon_robot(8);
  const double T0 = 5.0, mu = 0.3;
  const Solution free = solve_with(ModelKind::VC, robot, Effects(), tensions({T0}));
  const Solution pull = solve_with(ModelKind::VC, robot, friction(mu, Motion::Pulling), tensions({T0}));
  const Solution rel = solve_with(ModelKind::VC, robot, friction(mu, Motion::Releasing), tensions({T0}));
  ASSERT_TRUE(free.converged() && pull.converged() && rel.converged());
  ASSERT_EQ(pull.tendon_end_tensions.size(), 1u);
  EXPECT_GT(bend(pull), 0.3);
  const double e_pull = pull.tendon_end_tensions[0] / (T0 * std::exp(-mu * bend(pull))) - 1.0;
  const double e_rel = rel.tendon_end_tensions[0] / (T0 * std::exp(mu * bend(rel))) - 1.0;
  std::printf("capstan: pull end %.9f N (bend %.6f rad, rel. error %.2e), release end %.9f N (rel. error %.2e)\n",
              pull.tendon_end_tensions[0], bend(pull), e_pull, rel.tendon_end_tensions[0], e_rel);
  EXPECT_LT(std::abs(e_pull), 1e-6);
  EXPECT_LT(std::abs(e_rel), 1e-6);
  EXPECT_GT(rel.tendon_end_tensions[0], T0);
  EXPECT_LT(pull.tendon_end_tensions[0], T0);
  EXPECT_LT(bend(pull), 0.95 * bend(free));
  EXPECT_GT(bend(rel), 1.05 * bend(free));
}

// VCref drops the tension at each hole by the turn of the chords there; VC along the continuous
// path. With the friction force applied to the disks (disk_normal_force kept: Eq. 58 would drop
// it, being nearly along the disk normal) the two converge as the disks get denser: tip and end
// tension differences fall with n: the tip's at second order, as without friction; the end
// tension's at first order (VCref's last chord turns half a disk interval less than the path).
TEST(VcFriction, ConvergesToVcrefWithDisks) {
  const double T0 = 4.0, mu = 0.3;
  Effects e = friction(mu, Motion::Pulling);
  e.disk_normal_force = DiskNormalForce::Kept;
  double last_tip = INFINITY, last_end = INFINITY;
  for (int n : {5, 10, 20, 40}) {
    const Robot robot = one_tendon_robot(n);
    const Solution vc = solve_with(ModelKind::VC, robot, e, tensions({T0}, Vec3(0.0, 0.0, -0.2)));
    const Solution ref = solve_with(ModelKind::VCref, robot, e, tensions({T0}, Vec3(0.0, 0.0, -0.2)));
    ASSERT_TRUE(vc.converged() && ref.converged()) << n;
    const double tip = tip_distance(vc, ref);
    const double end = std::abs(vc.tendon_end_tensions[0] - ref.tendon_end_tensions[0]);
    std::printf("n = %2d: |tip VC - VCref| = %.3e m, |end tension VC - VCref| = %.3e N (VC %.6f N)\n", n, tip, end,
                vc.tendon_end_tensions[0]);
    EXPECT_LT(tip, 0.3 * last_tip) << n;
    EXPECT_LT(end, 0.6 * last_end) << n;
    last_tip = tip;
    last_end = end;
  }
}

// Two segments (a tendon through both; tendons terminating at the middle make the strains jump
// there, with kink forces): VC and VCref (friction forces kept at the disks) agree on the end
// tension and the tip.
TEST(VcFriction, TwoSegmentsAgreeWithVcref) {
  const Scene s = paper::scene(10, 5, "vc");
  Effects e = friction(0.1, Motion::Pulling);
  e.disk_normal_force = DiskNormalForce::Kept;
  const Solution vc = solve_with(ModelKind::VC, s.robot, e, s.input());
  const Solution ref = solve_with(ModelKind::VCref, s.robot, e, s.input());
  ASSERT_TRUE(vc.converged() && ref.converged()) << vc.summary.message;
  const double T0 = s.actuation.values[2];
  ASSERT_GT(T0, 0.0);
  std::printf("two segments: end tension VC %.6f, VCref %.6f (T0 %.3f N), tip distance %.3e m\n",
              vc.tendon_end_tensions[2], ref.tendon_end_tensions[2], T0, tip_distance(vc, ref));
  EXPECT_LT(vc.tendon_end_tensions[2], 0.95 * T0);
  EXPECT_NEAR(vc.tendon_end_tensions[2], ref.tendon_end_tensions[2], 0.005 * T0);
  EXPECT_LT(tip_distance(vc, ref), 0.005 * s.robot.total_length());
}

// Hysteresis: pull up to 4 N, release from 6 N down to 4 N, warm starting each step. The
// released robot ends bent more: the bending moment at s is about T(s) r, T(s) = T0 exp(-/+ mu
// theta(s)), so with mu theta(L) = 0.08 the two bends differ by about that factor (the disk
// models with Eq. 58 differ by more: they drop the friction force at the disks).
TEST(VcFriction, LoadingAndUnloadingDiffer) {
  const Robot robot = one_tendon_robot(6);
  const auto pulling = make_model(ModelKind::VC, robot, friction(0.2, Motion::Pulling));
  const auto releasing = make_model(ModelKind::VC, robot, friction(0.2, Motion::Releasing));
  auto walk = [](const StaticModel& m, const std::vector<double>& path) {
    auto ws = m.make_workspace();
    Solution s;
    for (double T : path) {
      s = tdcr::solve(m, *ws, tensions({T}), test::fixed_mesh_settings(), s.summary.converged() ? &s : nullptr);
      EXPECT_TRUE(s.converged()) << " at T = " << T;
    }
    return s;
  };
  const Solution up = walk(*pulling, {1.0, 2.0, 3.0, 4.0});
  const Solution down = walk(*releasing, {6.0, 5.0, 4.0});
  std::printf("hysteresis: bend %.6f rad pulled, %.6f released, tip distance %.3e m\n", bend(up), bend(down),
              tip_distance(up, down));
  EXPECT_GT(tip_distance(up, down), 3e-4);
  EXPECT_GT(bend(down), 1.05 * bend(up));
}

// Global equilibrium (verify_equilibrium): friction loads are internal to the robot and its
// tendons. A spatial bend under a tip force, and a helical tendon (its path leaves the base at
// an angle: the base hole's capstan turn counts).
TEST(VcFriction, GlobalEquilibriumHolds) {
  Scene s = paper::scene(5, 6, "vc");
  s.effects = friction(0.25, Motion::Releasing);
  s.loads.tip_force = Vec3(0.1, 0.05, -0.2);
  const Solution a = solve(s);
  ASSERT_TRUE(a.converged()) << a.summary.message;
  const EquilibriumCheck ea = verify_equilibrium(s, a);
  ASSERT_TRUE(ea.evaluated) << ea.reason;
  std::printf("equilibrium: spatial bend %.2e", ea.relative_error());
  EXPECT_LT(ea.relative_error(), 1e-8);

  Scene h = s;
  h.loads = Loads{};
  h.robot.segments.resize(1);
  h.robot.segments[0].tendons.resize(1);
  h.robot.segments[0].tendons[0].routing.type = TendonRoutingSpec::Type::Helical;
  h.robot.segments[0].tendons[0].routing.turns = 0.25;
  h.actuation.values = {3.0};
  h.effects = friction(0.3, Motion::Pulling);
  const Solution b = solve(h);
  ASSERT_TRUE(b.converged()) << b.summary.message;
  const EquilibriumCheck eb = verify_equilibrium(h, b);
  ASSERT_TRUE(eb.evaluated) << eb.reason;
  std::printf(", helical tendon %.2e (end tension %.6f of 3 N)\n", eb.relative_error(), b.tendon_end_tensions[0]);
  EXPECT_LT(eb.relative_error(), 1e-8);
  EXPECT_LT(b.tendon_end_tensions[0], 3.0);
}

// Displacement input: the displacements of a friction tension solve give its tensions back
// (the tensions stay the actuator's); the stability test reports undetermined with friction.
TEST(VcFriction, DisplacementInputAndStability) {
  const Scene s = paper::scene(5, 6, "vc");
  const Effects e = friction(0.2, Motion::Pulling);
  const auto model = make_model(ModelKind::VC, s.robot, e);
  auto ws = model->make_workspace();
  const Solution ref = tdcr::solve(*model, *ws, s.input(), test::fixed_mesh_settings(), nullptr);
  ASSERT_TRUE(ref.converged());
  EXPECT_EQ(ref.stability.status, StabilityStatus::Undetermined);
  ModelInput in;
  in.actuation.kind = Actuation::Kind::Displacements;
  in.actuation.values = ref.tendon_displacements;
  const Solution back = tdcr::solve(*model, *ws, in, test::fixed_mesh_settings(), nullptr);
  ASSERT_TRUE(back.converged()) << back.summary.message;
  double diff = 0.0, scale = 0.0;
  for (int k = 0; k < 4; ++k) {
    diff = std::max(diff, std::abs(back.tensions[k] - ref.tensions[k]));
    scale = std::max(scale, ref.tensions[k]);
  }
  EXPECT_LT(diff, 1e-8 * scale);
  EXPECT_LT(tip_distance(back, ref), 1e-9);
}

// Multiple shooting has no tension states: asked for explicitly, VC refuses friction naming
// the field; the automatic formulation takes single shooting.
TEST(VcFriction, MultipleShootingRefused) {
  const Scene s = paper::scene(5, 6, "vc");
  VcOptions o;
  o.formulation = VcFormulation::MultipleShooting;
  try {
    VcModel m(s.robot, friction(0.1, Motion::Pulling), o);
    ADD_FAILURE() << "multiple shooting accepted friction";
  } catch (const InputError& err) {
    EXPECT_EQ(err.field(), "effects.tendon_friction");
  }
  o.formulation = VcFormulation::Automatic;
  o.multiple_shooting_threshold = 0.0;
  const VcModel m(s.robot, friction(0.1, Motion::Pulling), o);
  EXPECT_FALSE(m.uses_multiple_shooting(s.input()));
}
