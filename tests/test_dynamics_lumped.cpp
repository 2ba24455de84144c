// Dynamics of the lumped models CCsub and PRB (models/lumped/lumped_dynamics.cpp): the physics
// they must reproduce (the static limit, Euler-Bernoulli's cantilever frequencies, damping that
// dissipates) and the input errors of the dynamics keys.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <iostream>
#include <string>

#include "allocation_counter.hpp"

#include <cstddef>
// Heap use by malloc as well (Eigen's and CVODE's heap goes there, not through operator new):
// this binary's malloc counts and forwards to glibc's (not under AddressSanitizer, which
// replaces malloc itself: GCC says so by __SANITIZE_ADDRESS__, clang 14 by __has_feature).
#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define TDCR_UNDER_ASAN 1
#endif
#endif
#if defined(__GLIBC__) && !defined(__SANITIZE_ADDRESS__) && !defined(TDCR_UNDER_ASAN)
#define TDCR_COUNT_MALLOC 1
extern "C" void* __libc_malloc(std::size_t);
inline std::atomic<long> g_mallocs{0};
extern "C" void* malloc(std::size_t n) {
  ++g_mallocs;
  return __libc_malloc(n);
}
#endif
#include "tdcr/core/error.hpp"
#include "tdcr/core/paper_robot.hpp"
#include "tdcr/core/scene_io.hpp"
#include "tdcr/models/dynamics.hpp"
#include "tdcr/models/lumped_model.hpp"
#include "tdcr/models/static_model.hpp"
#include "tdcr/models/tendon_physics.hpp"

namespace tdcr {
namespace {

constexpr double kDensity = 6450.0;  // NiTi, kg/m^3

// The paper robot with n disks per segment and a backbone density.
Robot paper_robot_with_mass(int n) {
  Robot r = paper::robot(n);
  r.backbone.density = kDensity;
  return r;
}

Timeline step_timeline(const std::vector<double>& from, const std::vector<double>& to, double ramp) {
  Timeline tl;
  TimelineEntry a, b;
  a.t = 0.0;
  a.input.actuation.values = from;
  b.t = ramp;
  b.input.actuation.values = to;
  tl.entries = {a, b};
  return tl;
}

// A straight cantilever without tendons: one segment of n disks.
Robot cantilever(int n, double length) {
  Robot r;
  Segment s;
  s.length = length;
  s.disks = n;
  r.segments = {s};
  r.backbone.density = kDensity;
  return r;
}

double euler_bernoulli_hz(const Robot& r, double beta_l) {
  const double EI = r.backbone.effective_stiffness().EI;
  const double mu = r.backbone.linear_mass();
  const double L = r.total_length();
  return beta_l * beta_l * std::sqrt(EI / (mu * std::pow(L, 4))) / (2.0 * M_PI);
}

class LumpedDynamicsTest : public ::testing::TestWithParam<ModelKind> {};

// With damping, a constant input after a short ramp settles on the static answer of the same
// model (its own statics are the zero of the generalized force).
TEST_P(LumpedDynamicsTest, SettlesOnItsOwnStaticAnswer) {
  const Robot robot = paper_robot_with_mass(3);
  auto model = make_model(GetParam(), robot, Effects());
  const double T = 0.4 * paper::max_tension(robot);
  // Both segments pulled; the proximal one alone (the distal segment, straight in every static
  // answer, swings through the straight shape: PRB's bending planes there are the proximal one's).
  for (const std::vector<double>& to : {std::vector<double>{T, 0, 0, 0.5 * T}, std::vector<double>{T, 0, 0, 0}}) {
    const Timeline tl = step_timeline({0, 0, 0, 0}, to, 0.01);
    DynamicsSettings d;
    d.bending_damping_time = 0.004;
    SimulationOptions o;
    o.duration = 0.4;
    o.dt = 0.02;
    SolverOptions solver;
    solver.tip_tolerance = 1e-11;
    const SimulationResult r = simulate(*model, d, tl, o, solver);
    ASSERT_TRUE(r.completed) << r.message;
    auto ws = model->make_workspace();
    const Solution s = solve(*model, *ws, tl.entries.back().input, solver);
    ASSERT_TRUE(s.converged());
    const Vec3 tip = r.steps.back().tip.p;
    EXPECT_LT((tip - s.disk_frames.back().p).norm(), 1e-8) << "tip " << tip.transpose();
    // It did move: the start is the straight robot.
    EXPECT_GT((tip - r.steps.front().tip.p).norm(), 1e-3);
  }
}

// The input along a ramp changes at every right-hand side: the integration allocates nothing
// there (operator new, and malloc where it can be counted): neither binding the input nor the
// right-hand sides, Jacobians and Newton systems.
TEST_P(LumpedDynamicsTest, RampAllocatesNothing) {
  const Robot robot = paper_robot_with_mass(3);
  auto model = make_model(GetParam(), robot, Effects());
  const double T = 0.4 * paper::max_tension(robot);
  Timeline tl = step_timeline({0, 0, 0, 0}, {T, 0, 0, 0.5 * T}, 1.0);
  tl.entries[1].input.loads.tip_force = Vec3(0.01, 0.0, 0.0);
  DynamicsSettings d;
  d.bending_damping_time = 0.004;
  auto integrator = make_dynamics_integrator(*model, d, 0.01);
  auto ws = model->make_workspace();
  const Solution rest = solve(*model, *ws, tl.entries.front().input);
  ASSERT_TRUE(rest.converged());
  integrator->initialize(rest, tl.entries.front().input);
  ASSERT_EQ(integrator->advance(0.01, tl).status, TerminationType::Converged);  // first: sizes buffers
  const long before = g_allocations.load();
#ifdef TDCR_COUNT_MALLOC
  const long mbefore = g_mallocs.load();
#endif
  for (int k = 2; k <= 20; ++k) ASSERT_EQ(integrator->advance(0.01 * k, tl).status, TerminationType::Converged);
  EXPECT_EQ(g_allocations.load() - before, 0);
#ifdef TDCR_COUNT_MALLOC
  EXPECT_EQ(g_mallocs.load() - mbefore, 0);
#endif
}

// A released cantilever (a small tip force in the x-z plane, released within 0.1 ms).
Timeline release_timeline(const Vec3& force) {
  Timeline tl;
  TimelineEntry a, b;
  a.input.loads.tip_force = force;
  b.t = 1e-4;
  tl.entries = {a, b};
  return tl;
}

// Undamped, the energy of the released cantilever stays; it swings through the straight shape
// (PRB: in the plane of its bend at release, theta changing sign).
TEST_P(LumpedDynamicsTest, UndampedKeepsEnergy) {
  const Robot robot = cantilever(6, 0.1);
  auto model = make_model(GetParam(), robot, Effects());
  SimulationOptions o;
  o.duration = 0.05;
  o.dt = 0.001;
  SolverOptions solver;
  solver.tip_tolerance = 1e-10;
  const SimulationResult u = simulate(*model, DynamicsSettings{}, release_timeline(Vec3(0.01, 0.004, 0.0)), o, solver);
  ASSERT_TRUE(u.completed) << u.message;
  const double E0 = u.steps[1].kinetic_energy + u.steps[1].potential_energy;
  ASSERT_GT(E0, 0.0);
  for (std::size_t k = 2; k < u.steps.size(); ++k)
    EXPECT_NEAR(u.steps[k].kinetic_energy + u.steps[k].potential_energy, E0, 2e-3 * E0) << "t = " << u.steps[k].t;
}

// Damped, the energy never grows and decays. Overdamped (first mode's damping ratio 2): PRB's
// bending-plane chart makes a swing through the straight shape slow (docs/dynamics.md, "Limits").
TEST_P(LumpedDynamicsTest, DampingDissipatesEnergy) {
  const Robot robot = cantilever(6, 0.1);
  auto model = make_model(GetParam(), robot, Effects());
  SimulationOptions o;
  o.duration = 0.1;
  o.dt = 0.001;
  SolverOptions solver;
  solver.tip_tolerance = 1e-10;
  DynamicsSettings damped;
  damped.bending_damping_time = 1e-2;
  const SimulationResult d = simulate(*model, damped, release_timeline(Vec3(0.01, 0.0, 0.0)), o, solver);
  ASSERT_TRUE(d.completed) << d.message;
  const double E0 = d.steps[1].kinetic_energy + d.steps[1].potential_energy;
  double last = E0;
  for (std::size_t k = 2; k < d.steps.size(); ++k) {
    const double E = d.steps[k].kinetic_energy + d.steps[k].potential_energy;
    EXPECT_LE(E, last * (1.0 + 1e-6) + 1e-15) << "t = " << d.steps[k].t;
    last = E;
  }
  EXPECT_LT(last, 0.5 * E0);
}

// The first period of the released cantilever, from the tip's zero crossings, is that of the
// linearised model's first frequency. A damping time of 1 us damps the stiff modes the release
// excites (torsion, PRB's links: damping ratios >> 1) and shifts the first mode by a relative
// (omega tau / 2)^2 / 2 ~ 1e-8.
TEST_P(LumpedDynamicsTest, MotionHasTheFirstNaturalFrequency) {
  const Robot robot = cantilever(8, 0.1);
  auto model = make_model(GetParam(), robot, Effects());
  const auto& lumped = static_cast<const LumpedModel&>(*model);
  const Eigen::VectorXd all =
      lumped.natural_frequencies(Eigen::VectorXd::Zero(lumped.unknowns_per_subsegment() * 8), ModelInput{});
  double f1 = 0.0;
  for (int i = 0; i < all.size() && f1 == 0.0; ++i)
    if (all[i] > 1.0) f1 = all[i];
  Timeline tl;
  TimelineEntry a, b;
  a.input.loads.tip_force = Vec3(0.005, 0.0, 0.0);
  b.t = 1e-5;
  tl.entries = {a, b};
  SimulationOptions o;
  o.duration = 3.0 / f1;
  o.dt = 1.0 / (100.0 * f1);
  SolverOptions solver;
  solver.tip_tolerance = 1e-11;
  DynamicsSettings d;
  d.bending_damping_time = 1e-6;
  const SimulationResult r = simulate(*model, d, tl, o, solver);
  ASSERT_TRUE(r.completed) << r.message;
  std::vector<double> up;  // upward zero crossings of tip_x, interpolated
  for (std::size_t k = 1; k < r.steps.size(); ++k) {
    const double x0 = r.steps[k - 1].tip.p.x(), x1 = r.steps[k].tip.p.x();
    if (x0 < 0.0 && x1 >= 0.0) up.push_back(r.steps[k - 1].t + (r.steps[k].t - r.steps[k - 1].t) * x0 / (x0 - x1));
  }
  ASSERT_GE(up.size(), 3u);
  const double period = (up.back() - up.front()) / static_cast<double>(up.size() - 1);
  EXPECT_NEAR(1.0 / period, f1, 5e-3 * f1);
}

// The lumped cantilever's first two bending frequencies approach Euler-Bernoulli's as n grows
// (bending modes come in pairs, x and y: entries 0 and 2 of the ascending list).
// Relative errors (this test's output, L = 0.1 m, 0.8 mm NiTi rod, no disks):
//   n:          5       10      20      40
//   CCsub f1:  see docs/dynamics.md (measured table)
TEST_P(LumpedDynamicsTest, CantileverFrequenciesApproachEulerBernoulli) {
  double last1 = INFINITY, last2 = INFINITY;
  for (int n : {5, 10, 20, 40}) {
    const Robot robot = cantilever(n, 0.1);
    auto model = make_model(GetParam(), robot, Effects());
    const auto& lumped = static_cast<const LumpedModel&>(*model);
    const Eigen::VectorXd all =
        lumped.natural_frequencies(Eigen::VectorXd::Zero(lumped.unknowns_per_subsegment() * n), ModelInput{});
    // The distinct bending frequencies: CCsub's come in x, y pairs; PRB's straight subsegments
    // bend in their planes phi only (the other plane is a zero mode of the chart).
    std::vector<double> f;
    for (int i = 0; i < all.size(); ++i)
      if (all[i] > 1.0 && (f.empty() || all[i] > f.back() * (1.0 + 1e-6))) f.push_back(all[i]);
    ASSERT_GE(f.size(), 2u);
    const double e1 = std::abs(f[0] / euler_bernoulli_hz(robot, 1.8751) - 1.0);
    const double e2 = std::abs(f[1] / euler_bernoulli_hz(robot, 4.6941) - 1.0);
    std::cout << to_string(GetParam()) << " n = " << n << ": f1 " << f[0] << " Hz (error " << e1 << "), f2 " << f[1]
              << " Hz (error " << e2 << ")\n";
    // PRB's f1 levels off at +0.055 %: its spring factors give a subsegment the compliance
    // sum 1/K_Theta_q = 0.9988 l/EI (paper Table 1), so its limit is EB's times 1/sqrt(0.9988).
    if (GetParam() == ModelKind::CCsub) {
      EXPECT_LT(e1, last1);
    }
    EXPECT_LT(e2, last2);
    last1 = e1, last2 = e2;
  }
  EXPECT_LT(last1, 0.01);
  EXPECT_LT(last2, 0.01);
}

INSTANTIATE_TEST_SUITE_P(Lumped, LumpedDynamicsTest, ::testing::Values(ModelKind::CCsub, ModelKind::PRB),
                         [](const auto& info) { return to_string(info.param); });

// --- Input errors name the field and the value. ---

void expect_input_error(const std::function<void()>& f, const std::string& field, const std::string& value) {
  try {
    f();
    ADD_FAILURE() << "no InputError for " << field;
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), field) << e.what();
    EXPECT_EQ(e.value(), value) << e.what();
  }
}

TEST(DynamicsInput, SettingsAndOptions) {
  DynamicsSettings d;
  d.bending_damping_time = -1.0;
  expect_input_error([&] { d.validate(); }, "dynamics.bending_damping_time", "-1");
  d = DynamicsSettings{};
  d.alpha = 0.3;
  expect_input_error([&] { d.validate(); }, "dynamics.alpha", "0.3");
  SimulationOptions o;
  o.dt = 0.0;
  expect_input_error([&] { o.validate(); }, "dt", "0");
  o = SimulationOptions{};
  o.duration = -2.0;
  expect_input_error([&] { o.validate(); }, "duration", "-2");
}

TEST(DynamicsInput, TimelineMustIncrease) {
  const Robot robot = paper_robot_with_mass(5);
  Timeline tl = step_timeline({0, 0, 0, 0}, {1, 0, 0, 0}, 0.5);
  tl.entries.push_back(tl.entries.back());
  tl.entries.back().t = 0.5;
  expect_input_error([&] { tl.validate(robot); }, "timeline[2].t", "0.5");
  tl.entries.pop_back();
  tl.entries[1].input.actuation.values = {1, 0};
  try {
    tl.validate(robot);
    ADD_FAILURE() << "a short actuation list passed";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field().rfind("timeline[1].actuation", 0), 0u) << e.what();
  }
}

TEST(DynamicsInput, RobotWithoutMassAndModelsWithoutDynamics) {
  Robot robot = paper::robot(5);  // density 0, no disk mass
  auto model = make_model(ModelKind::CCsub, robot, Effects());
  expect_input_error([&] { make_dynamics_integrator(*model, DynamicsSettings{}, 0.01); }, "robot.backbone.density",
                     "0");
  // CC is kinematic: it has no equations of motion.
  auto cc = make_model(ModelKind::CC, paper_robot_with_mass(5), Effects());
  expect_input_error([&] { make_dynamics_integrator(*cc, DynamicsSettings{}, 0.01); }, "model", "cc");
  // VC and VCref have theirs (models/vc/vc_dynamics.hpp), reached through the same dispatch.
  auto vc = make_model(ModelKind::VC, paper_robot_with_mass(5), Effects());
  EXPECT_NE(make_dynamics_integrator(*vc, DynamicsSettings{}, 0.01), nullptr);
}

TEST(DynamicsInput, SceneKeys) {
  const std::string robot =
      R"("robot": {"backbone": {"density": 6450}, "segments": [{"length": 0.05, "disks": 5, "tendons": [{"x": 0, "y": 0.008}]}]},
         "actuation": {"tensions": [0]}, "model": "ccsub")";
  const Scene s = parse_scene("{" + robot +
                              R"(, "dynamics": {"bending_damping_time": 0.01},
      "timeline": [{"t": 0}, {"t": 0.1, "actuation": {"tensions": [2]}}, {"t": 0.2, "loads": {"tip_force": [0, 0, 0.1]}}]})");
  ASSERT_TRUE(s.dynamics.has_value());
  EXPECT_EQ(s.dynamics->bending_damping_time, 0.01);
  ASSERT_EQ(s.timeline.entries.size(), 3u);
  EXPECT_EQ(s.timeline.entries[2].input.actuation.values[0], 2.0);  // kept from the entry before
  EXPECT_EQ(s.timeline.at(0.05).actuation.values[0], 1.0);         // linear between entries
  EXPECT_NEAR(s.timeline.at(0.15).loads.tip_force.z(), 0.05, 1e-15);
  // Written and read back the same.
  const Scene back = parse_scene(scene_to_json(s));
  ASSERT_EQ(back.timeline.entries.size(), 3u);
  EXPECT_EQ(back.timeline.entries[1].input.actuation.values[0], 2.0);
  expect_input_error([&] { parse_scene("{" + robot + R"(, "dynamics": {"damping": 1}})"); }, "dynamics.damping", "1");
  expect_input_error([&] { parse_scene("{" + robot + R"(, "dynamics": {"alpha": -0.7}})"); }, "dynamics.alpha",
                     "-0.7");
  expect_input_error([&] { parse_scene("{" + robot + R"(, "timeline": [{"t": 0}, {"t": 0}]})"); }, "timeline[1].t",
                     "0");
}

}  // namespace
}  // namespace tdcr

namespace tdcr {
namespace {

// Air drag takes energy out of a swinging cantilever that the (tiny) Kelvin-Voigt damping alone
// leaves in.
TEST(LumpedDynamics, AirDragDissipates) {
  const Robot robot = cantilever(6, 0.1);
  auto model = make_model(ModelKind::CCsub, robot, Effects());
  Timeline tl;
  TimelineEntry a, b;
  a.input.loads.tip_force = Vec3(0.05, 0.0, 0.0);
  b.t = 1e-4;
  tl.entries = {a, b};
  SimulationOptions o;
  o.duration = 0.05;
  o.dt = 0.005;
  DynamicsSettings d;
  d.bending_damping_time = 1e-6;  // damps the stiff modes only
  // Energy step by step to 1e-6: far tighter than the dynamics' default accuracy (1e-4 L).
  SolverOptions solver;
  solver.tip_tolerance = 1e-9;
  const SimulationResult r0 = simulate(*model, d, tl, o, solver);
  d.air_drag = 50.0;
  const SimulationResult r1 = simulate(*model, d, tl, o, solver);
  ASSERT_TRUE(r0.completed && r1.completed) << r0.message << r1.message;
  const auto energy = [](const SimulationStep& s) { return s.kinetic_energy + s.potential_energy; };
  EXPECT_LT(energy(r1.steps.back()), 0.9 * energy(r0.steps.back()));
  for (std::size_t k = 2; k < r1.steps.size(); ++k) EXPECT_LE(energy(r1.steps[k]), energy(r1.steps[k - 1]) * (1 + 1e-6));
}

// --- Displacement input (motors) with elastic tendons: T_k = EA_k / L_k max(0, delta_k - d_k(q)). ---

constexpr double kTendonEA = 400.0;  // N: a 0.2 mm Dyneema-like tendon, a few mm of stretch at 5 N

Robot elastic_paper_robot(int n) {
  Robot r = paper_robot_with_mass(n);
  for (Segment& s : r.segments)
    for (TendonSpec& t : s.tendons) t.stiffness = kTendonEA;
  return r;
}

// A timeline of one kind per tendon (`kinds`), from `from` at 0 to `to` at `ramp`.
Timeline kinds_timeline(const std::vector<Actuation::Kind>& kinds, const std::vector<double>& from,
                        const std::vector<double>& to, double ramp) {
  Timeline tl = step_timeline(from, to, ramp);
  for (TimelineEntry& e : tl.entries) {
    e.input.actuation.kind = Actuation::Kind::Displacements;
    e.input.actuation.kinds = kinds;
  }
  return tl;
}

DynamicsSettings damped() {
  DynamicsSettings d;
  d.bending_damping_time = 0.004;
  return d;
}

class LumpedDisplacementTest : public ::testing::TestWithParam<ModelKind> {};

// With damping, constant motor displacements (after a ramp) settle on the static displacement
// solve of the same model and scene: the same tip to 1e-8 m and the same tensions. Mixed input:
// tendons 1 and 4 by displacement, 2 and 3 by tension 0. With shear and extension (the default:
// the tensions and the backbone's compression are a fixed point at every right-hand side) and
// without (one pass).
TEST_P(LumpedDisplacementTest, SettlesOnTheStaticDisplacementSolve) {
  for (bool shear_extension : {true, false}) {
  SCOPED_TRACE(shear_extension ? "shear_extension" : "inextensible backbone");
  const Robot robot = elastic_paper_robot(3);
  Effects effects;
  effects.shear_extension = shear_extension;
  auto model = make_model(GetParam(), robot, effects);
  using K = Actuation::Kind;
  const std::vector<K> kinds = {K::Displacements, K::Tensions, K::Tensions, K::Displacements};
  const Timeline tl = kinds_timeline(kinds, {0, 0, 0, 0}, {0.006, 0, 0, 0.004}, 0.01);
  SimulationOptions o;
  o.duration = 0.4;
  o.dt = 0.02;
  SolverOptions solver;
  solver.tip_tolerance = 1e-11;
  const SimulationResult r = simulate(*model, damped(), tl, o, solver);
  ASSERT_TRUE(r.completed) << r.message;
  auto ws = model->make_workspace();
  const Solution s = solve(*model, *ws, tl.entries.back().input, solver);
  ASSERT_TRUE(s.converged());
  const SimulationStep& last = r.steps.back();
  const double tip_error = (last.tip.p - s.disk_frames.back().p).norm();
  EXPECT_LT(tip_error, 1e-8) << "tip " << last.tip.p.transpose();
  EXPECT_GT((last.tip.p - r.steps.front().tip.p).norm(), 1e-3);  // it moved
  ASSERT_EQ(last.tensions.size(), 4u);
  for (int k : {0, 3}) {
    EXPECT_GT(s.tensions[k], 0.1);
    EXPECT_NEAR(last.tensions[k], s.tensions[k], 1e-8 * s.tensions[k]) << "tendon " << k + 1;
    // The reported displacement is the motor's (the path's pull plus the stretch).
    EXPECT_NEAR(last.tendon_displacements[k], tl.entries.back().input.actuation.values[k], 1e-9);
  }
  EXPECT_EQ(last.tensions[1], 0.0);
  EXPECT_EQ(last.tensions[2], 0.0);
  std::cout << to_string(GetParam()) << ": tip " << tip_error << " m from the static solve; tensions "
            << last.tensions[0] << " (" << (last.tensions[0] - s.tensions[0]) / s.tensions[0] << " rel.), "
            << last.tensions[3] << " (" << (last.tensions[3] - s.tensions[3]) / s.tensions[3] << " rel.) N\n";
  }
}

// A motor pulls tendon 1 and releases it past its rest (the others driven at 0): it goes slack
// with exactly zero tension, CVODE stops at the kinks (the step reports their times), and the
// robot comes back to straight.
TEST_P(LumpedDisplacementTest, ReleasedTendonGoesSlackWithZeroTension) {
  const Robot robot = elastic_paper_robot(3);
  auto model = make_model(GetParam(), robot, Effects());
  Timeline tl;
  TimelineEntry a, b, c, e;
  for (TimelineEntry* x : {&a, &b, &c, &e}) x->input.actuation.kind = Actuation::Kind::Displacements;
  a.input.actuation.values = {0, 0, 0, 0};
  b.t = 0.02;
  b.input.actuation.values = {0.006, 0, 0, 0};
  c.t = 0.15;
  c.input.actuation.values = {0.006, 0, 0, 0};
  e.t = 0.17;
  e.input.actuation.values = {-0.002, 0, 0, 0};
  tl.entries = {a, b, c, e};
  SimulationOptions o;
  o.duration = 0.5;
  o.dt = 0.01;
  SolverOptions solver;
  solver.tip_tolerance = 1e-10;
  const SimulationResult r = simulate(*model, damped(), tl, o, solver);
  ASSERT_TRUE(r.completed) << r.message;
  const SimulationStep& pulled = r.steps[15];
  EXPECT_GT(pulled.tensions[0], 0.5);
  std::vector<double> events;
  for (const SimulationStep& s : r.steps) events.insert(events.end(), s.tendon_events.begin(), s.tendon_events.end());
  // Tendon 1 goes slack during the release (0.15 .. 0.17 s).
  bool release = false;
  for (double t : events) release = release || (t > 0.15 && t < 0.17 + 1e-12);
  EXPECT_TRUE(release) << events.size() << " events";
  for (std::size_t k = 18; k < r.steps.size(); ++k) EXPECT_EQ(r.steps[k].tensions[0], 0.0) << "t " << r.steps[k].t;
  // Released: straight again (the antagonists held at 0 pull nothing on the straight robot).
  const double L = robot.total_length();
  EXPECT_LT((r.steps.back().tip.p - Vec3(0, 0, L)).norm(), 1e-6) << r.steps.back().tip.p.transpose();
  std::cout << to_string(GetParam()) << ": " << events.size() << " slack/taut events at";
  for (double t : events) std::cout << " " << t;
  std::cout << " s; tip at the end " << (r.steps.back().tip.p - Vec3(0, 0, L)).norm() << " m from straight\n";
}

// Round trip: a tension run's tendon displacements (the pulls of its final shape plus each
// tendon's stretch T L / EA) fed back to the motors give the tension run's tip. Both runs settle
// on one static equilibrium (the displacement one is the tension one's, the stretch included),
// so the tip agrees to the settled runs' accuracy (1e-8 m, as SettlesOnTheStaticDisplacementSolve).
TEST_P(LumpedDisplacementTest, RoundTripFromATensionRun) {
  const Robot robot = elastic_paper_robot(3);
  auto model = make_model(GetParam(), robot, Effects());
  const double T = 0.4 * paper::max_tension(robot);
  const std::vector<double> tensions = {T, 0, 0, 0.5 * T};
  const Timeline tension_tl = step_timeline({0, 0, 0, 0}, tensions, 0.01);
  SimulationOptions o;
  o.duration = 0.4;
  o.dt = 0.02;
  SolverOptions solver;
  solver.tip_tolerance = 1e-11;
  std::vector<Frame> last_frames;
  const SimulationResult rt = simulate(*model, damped(), tension_tl, o, solver,
                                       [&](const SimulationStep&, const Solution& shape) { last_frames = shape.disk_frames; });
  ASSERT_TRUE(rt.completed) << rt.message;
  std::vector<double> d = tendon::chord_displacements(last_frames, model->routing(), Actuation::DisplacementConvention::AtBase);
  tendon::add_elastic_stretch(robot, model->routing(), tensions, d);
  // The tendons at tension 0 are driven too, at the pulls of the tension run's shape: exactly at
  // their slack limit there.
  const Timeline disp_tl = kinds_timeline({}, {0, 0, 0, 0}, d, 0.01);
  const SimulationResult rd = simulate(*model, damped(), disp_tl, o, solver);
  ASSERT_TRUE(rd.completed) << rd.message;
  const double err = (rd.steps.back().tip.p - rt.steps.back().tip.p).norm();
  EXPECT_LT(err, 1e-8);
  EXPECT_NEAR(rd.steps.back().tensions[0], T, 1e-6 * T);
  EXPECT_NEAR(rd.steps.back().tensions[3], 0.5 * T, 1e-6 * T);
  EXPECT_LT(rd.steps.back().tensions[1], 1e-6 * T);
  std::cout << to_string(GetParam()) << ": round-trip tip " << err << " m; tensions " << rd.steps.back().tensions[0] << ", "
            << rd.steps.back().tensions[1] << ", " << rd.steps.back().tensions[2] << ", " << rd.steps.back().tensions[3]
            << " N (given " << T << ", 0, 0, " << 0.5 * T << ")\n";
}

// An inextensible tendon driven by displacement has no tension as a function of the shape: the
// lumped dynamics refuse it, naming its stiffness field (VC and VCref take it).
TEST_P(LumpedDisplacementTest, InextensibleDrivenTendonIsRefused) {
  Robot robot = elastic_paper_robot(3);
  robot.segments[1].tendons[1].stiffness.reset();
  auto model = make_model(GetParam(), robot, Effects());
  const Timeline tl = kinds_timeline({}, {0, 0, 0, 0}, {0.004, 0, 0, 0.002}, 0.01);
  SimulationOptions o;
  o.duration = 0.02;
  o.dt = 0.01;
  expect_input_error([&] { simulate(*model, damped(), tl, o, SolverOptions{}); }, "robot.segments[1].tendons[1].stiffness",
                     "absent (inextensible)");
  // Given by tension instead (mixed input), the same tendon needs no stiffness.
  using K = Actuation::Kind;
  const Timeline mixed = kinds_timeline({K::Displacements, K::Displacements, K::Displacements, K::Tensions}, {0, 0, 0, 0},
                                        {0.004, 0, 0, 0}, 0.01);
  EXPECT_TRUE(simulate(*model, damped(), mixed, o, SolverOptions{}).completed);
}

// A motor ramp (no slack events): the right-hand sides, the driven tensions' fixed point, the
// Jacobians and Newton systems allocate nothing; what an advance allocates is its report (the
// step's tensions and tendon displacements: 2 vectors).
TEST_P(LumpedDisplacementTest, MotorRampAllocatesOnlyTheReport) {
  const Robot robot = elastic_paper_robot(3);
  auto model = make_model(GetParam(), robot, Effects());
  using K = Actuation::Kind;
  const Timeline tl = kinds_timeline({K::Displacements, K::Tensions, K::Tensions, K::Displacements}, {0.001, 0, 0, 0.001},
                                     {0.006, 0, 0, 0.004}, 1.0);
  auto integrator = make_dynamics_integrator(*model, damped(), 0.01);
  auto ws = model->make_workspace();
  const Solution rest = solve(*model, *ws, tl.entries.front().input);
  ASSERT_TRUE(rest.converged());
  integrator->initialize(rest, tl.entries.front().input);
  ASSERT_EQ(integrator->advance(0.01, tl).status, TerminationType::Converged);
  long events = 0, before = 0;
#ifdef TDCR_COUNT_MALLOC
  long mbefore = 0;
#endif
  for (int k = 2; k <= 20; ++k) {
    before = g_allocations.load();
#ifdef TDCR_COUNT_MALLOC
    mbefore = g_mallocs.load();
#endif
    const SimulationStep s = integrator->advance(0.01 * k, tl);
    const long allocations = g_allocations.load() - before;
    ASSERT_EQ(s.status, TerminationType::Converged);
    events += static_cast<long>(s.tendon_events.size());
    EXPECT_LE(allocations, 2) << "t " << s.t;
#ifdef TDCR_COUNT_MALLOC
    EXPECT_LE(g_mallocs.load() - mbefore, 2) << "t " << s.t;
#endif
  }
  EXPECT_EQ(events, 0);
}

INSTANTIATE_TEST_SUITE_P(Lumped, LumpedDisplacementTest, ::testing::Values(ModelKind::CCsub, ModelKind::PRB),
                         [](const auto& info) { return to_string(info.param); });

// Undamped, once the motors stop (held displacements) the energy stays: the driven tendons'
// elastic energy (EA / 2L) max(0, delta - d)^2 is the potential of their tensions. PRB only:
// CCsub's drift is measured and open (docs/dynamics.md, "Displacement input").
TEST(LumpedDisplacement, UndampedKeepsEnergyWithTheMotorsHeldPrb) {
  const Robot robot = elastic_paper_robot(3);
  auto model = make_model(ModelKind::PRB, robot, Effects());
  const Timeline tl = kinds_timeline({}, {0, 0, 0, 0}, {0.004, 0, 0, 0.002}, 0.005);
  SimulationOptions o;
  o.duration = 0.05;
  o.dt = 0.001;
  SolverOptions solver;
  solver.tip_tolerance = 1e-10;
  const SimulationResult r = simulate(*model, DynamicsSettings{}, tl, o, solver);
  ASSERT_TRUE(r.completed) << r.message;
  const auto energy = [](const SimulationStep& s) { return s.kinetic_energy + s.potential_energy; };
  const double E0 = energy(r.steps[5]);
  double worst = 0.0, kinetic = 0.0;
  for (std::size_t k = 5; k < r.steps.size(); ++k) {
    kinetic = std::max(kinetic, r.steps[k].kinetic_energy);
    worst = std::max(worst, std::abs(energy(r.steps[k]) - E0));
  }
  EXPECT_GT(kinetic, 1e-4);          // it swings (J)
  EXPECT_LT(worst, 1e-2 * kinetic);  // kept to 1 % of the kinetic energy it swings with
  std::cout << "prb: kinetic up to " << kinetic << " J; energy " << E0 << " J kept to " << worst << " J\n";
}

}  // namespace
}  // namespace tdcr
