// VC's Cosserat rod dynamics (models/vc/vc_dynamics*.cpp) against physics: the static limit of
// a damped step, the first two bending frequencies of a straight cantilever against
// Euler-Bernoulli, energy conservation without damping (implicit midpoint) and its decay with
// damping. The integrator is driven through advance_with_input (the Timeline functions belong
// to the dynamics front end).
#include <gtest/gtest.h>

#include <cmath>
#include <utility>
#include <vector>

#include "fixed_mesh_settings.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/core/paper_robot.hpp"
#include "tdcr/models/vc.hpp"
#include "vc/vc_dynamics.hpp"

using namespace tdcr;

namespace {

constexpr double kSteel = 7800.0;  // kg/m^3: the paper robot's spring-steel backbone (E = 211 GPa)

Robot steel_robot(int disks) {
  Robot r = paper::robot(disks);
  r.backbone.density = kSteel;
  return r;
}

ModelInput tensions(const Robot& r, std::vector<double> T) {
  ModelInput in;
  in.actuation.values = T.empty() ? std::vector<double>(r.tendon_count(), 0.0) : T;
  return in;
}

// The static answer of `model` on the dynamics' mesh (rk4_steps per disk interval).
Solution static_answer(const StaticModel& model, const ModelInput& in, int rk4_steps) {
  SolverOptions o = test::fixed_mesh_settings();
  o.rk4_steps = rk4_steps;
  o.rk4_max_step = INFINITY;
  o.function_tolerance = 1e-12;
  auto ws = model.make_workspace();
  Solution s = solve(model, *ws, in, o);
  EXPECT_TRUE(s.converged()) << s.summary.message;
  return s;
}

// Bending stiffness and mass per length of a robot.
double EI(const Robot& r) { return r.backbone.effective_stiffness().EI; }
double rhoA(const Robot& r) { return r.backbone.linear_mass(); }

// Euler-Bernoulli cantilever: frequency (Hz) of the mode with beta L = bl.
double eb_frequency(const Robot& r, double bl) {
  const double L = r.total_length();
  return bl * bl * std::sqrt(EI(r) / (rhoA(r) * std::pow(L, 4))) / (2.0 * M_PI);
}

// The Euler-Bernoulli cantilever mode shape with beta L = bl at s.
double eb_mode(double bl, double L, double s) {
  const double b = bl / L, sg = (std::cosh(bl) + std::cos(bl)) / (std::sinh(bl) + std::sin(bl));
  return std::cosh(b * s) - std::cos(b * s) - sg * (std::sinh(b * s) - std::sin(b * s));
}

// Projection of the x deflection of the disks on a mode (Simpson over the equally spaced disks).
double modal_coordinate(const Solution& shape, const TendonRouting& rt, double bl, double L) {
  const int n = rt.disk_count() - 1;  // even
  double sum = 0.0;
  for (int j = 0; j <= n; ++j) {
    const double c = (j == 0 || j == n) ? 1.0 : (j % 2 ? 4.0 : 2.0);
    sum += c * shape.disk_frames[j].p.x() * eb_mode(bl, L, rt.disk_s[j]);
  }
  return sum * (L / n) / 3.0;
}

// Frequency (Hz) of a signal from its zero crossings (linear interpolation between samples).
double crossing_frequency(const std::vector<double>& t, const std::vector<double>& x) {
  std::vector<double> cross;
  for (std::size_t k = 1; k < x.size(); ++k)
    if ((x[k - 1] < 0.0) != (x[k] < 0.0)) cross.push_back(t[k - 1] + (t[k] - t[k - 1]) * x[k - 1] / (x[k - 1] - x[k]));
  if (cross.size() < 3) return NAN;
  return 0.5 * (cross.size() - 1) / (cross.back() - cross.front());
}

}  // namespace

// A tension step with Kelvin-Voigt damping settles on the static answer of the same model (VC,
// VCref) and input on the same mesh, to 1e-8 m.
// `weighted`: 0.2 g disks (five times the backbone's mass in all) and gravity across the
// robot, on from t = 0+ with the tensions (the disks' inertia, weights and, for VC, their kinks
// with damping). With 2 g disks the slowest mode is underdamped (zeta about 0.25) and needs about
// 3 s to settle to 1e-11 m.
// `helical`: the tendons turn half a turn about the backbone (routed offsets r(s)).
void settles_on_static_answer(ModelKind kind, Effects effects, bool weighted = false, bool helical = false) {
  Robot robot = steel_robot(5);
  if (helical)
    for (Segment& seg : robot.segments)
      for (TendonSpec& t : seg.tendons) {
        t.routing.type = TendonRoutingSpec::Type::Helical;
        t.routing.turns = 0.5;
      }
  if (weighted)
    for (Segment& seg : robot.segments) seg.disk_mass = 2e-4;
  const std::unique_ptr<StaticModel> owner = make_model(kind, robot, effects);
  const StaticModel& model = *owner;
  const int steps = 2;
  const ModelInput rest = tensions(robot, {});
  ModelInput pulled = tensions(robot, {1.0, 0.0, 0.5, 0.0});
  if (weighted) pulled.loads.gravity = Vec3(-9.81, 3.0, -1.0);
  DynamicsSettings set;
  set.bending_damping_time = 0.01;
  set.shear_damping_time = 0.01;
  set.alpha = 0.0;
  vc::CosseratDynamicsOptions o;
  o.rk4_steps = steps;
  o.function_tolerance = 1e-12;
  const double dt = 0.005;
  auto dyn = kind == ModelKind::VC ? vc::make_vc_dynamics(static_cast<const VcModel&>(model), set, dt, o)
                                   : vc::make_vcref_dynamics(model, set, dt, o);
  dyn->initialize(static_answer(model, rest, steps), rest);
  const Solution target = static_answer(model, pulled, steps);
  SimulationStep s;
  double early = 0.0;
  for (int k = 1; k <= 100; ++k) {
    s = dyn->advance_with_input(k * dt, pulled);
    ASSERT_EQ(s.status, TerminationType::Converged) << "step " << k << ": " << dyn->last_message();
    if (k == 4) early = (s.tip.p - target.tip().p).norm();
  }
  const double err = (s.tip.p - target.tip().p).norm();
  std::printf("%s: tip error %.3e m after 0.5 s (%.3e m at 20 ms), %ld shots\n", to_string(kind).c_str(), err, early,
              dyn->shots());
  EXPECT_LT(err, 1e-8) << "tip " << s.tip.p.transpose() << " static " << target.tip().p.transpose();
  EXPECT_GT(early, 1e-4);  // it did move: 20 ms after the step it is still on its way
  EXPECT_LT(s.kinetic_energy, 1e-12);
  EXPECT_LT((s.tip.R - target.tip().R).norm(), 1e-7);
  // VC's samples hold the wrench just distal of each disk, as its statics do (the damping's
  // share B v_t of the last strain rates, about 1e-10 /s, is in them: 1e-7 N with EA tau_se).
  const Solution shape = dyn->shape();
  ASSERT_EQ(shape.backbone.size(), target.backbone.size());
  if (kind == ModelKind::VC)
    for (std::size_t j = 0; j < shape.backbone.size(); ++j) {
      EXPECT_LT((shape.backbone[j].n - target.backbone[j].n).norm(), 1e-6) << "disk " << j;
      EXPECT_LT((shape.backbone[j].m - target.backbone[j].m).norm(), 1e-8) << "disk " << j;
    }
}

TEST(DynamicsCosserat, DampedStepSettlesOnTheStaticAnswer) { settles_on_static_answer(ModelKind::VC, Effects{}); }

TEST(DynamicsCosserat, DampedStepWithHelicalTendonsSettlesOnTheStaticAnswer) {
  settles_on_static_answer(ModelKind::VC, Effects{}, false, true);
  settles_on_static_answer(ModelKind::VCref, Effects{}, false, true);
}

TEST(DynamicsCosserat, DampedStepWithWeightsSettlesOnTheStaticAnswer) {
  settles_on_static_answer(ModelKind::VC, Effects{}, true);
  settles_on_static_answer(ModelKind::VCref, Effects{}, true);
}

// VCref with the paper's disk force (Eq. 58: the pass-through force's normal component removed).
TEST(DynamicsCosserat, DampedStepSettlesOnVcrefsStaticAnswer) {
  settles_on_static_answer(ModelKind::VCref, paper::effects("vcref"));
}

// Free vibration of the straight cantilever (no tension, no gravity) released from a small
// tip-loaded static shape: the first two bending frequencies, read from the zero crossings of
// the disks' deflection projected on the Euler-Bernoulli modes, match 1.8751^2 and 4.6941^2
// sqrt(EI / (rho A L^4)) / (2 pi) within 1 %. Implicit midpoint (no numerical damping) with
// dt = 5e-5 s: its frequency error (2 / dt) atan(w dt / 2) / w - 1 is -0.1 % for the second mode.
TEST(DynamicsCosserat, CantileverBendingFrequenciesMatchEulerBernoulli) {
  const Robot robot = steel_robot(10);
  const VcModel model(robot, Effects{});
  const TendonRouting& rt = model.routing();
  const double L = robot.total_length();
  const int steps = 4;
  ModelInput loaded = tensions(robot, {});
  loaded.loads.tip_force = Vec3(1e-4, 0.0, 0.0);  // tip deflection F L^3 / (3 EI) = 8 um: linear
  const ModelInput released = tensions(robot, {});
  DynamicsSettings set;
  set.scheme = TimeScheme::ImplicitMidpoint;
  vc::CosseratDynamicsOptions o;
  o.rk4_steps = steps;
  const double dt = 1e-4;
  auto dyn = vc::make_vc_dynamics(model, set, dt, o);
  dyn->initialize(static_answer(model, loaded, steps), loaded);
  const double f1 = eb_frequency(robot, 1.8751), f2 = eb_frequency(robot, 4.6941);
  const int n = static_cast<int>(std::ceil(3.2 / f1 / dt));  // a bit over 3 periods of mode 1
  std::vector<double> t, eta1, eta2;
  for (int k = 1; k <= n; ++k) {
    const SimulationStep s = dyn->advance_with_input(k * dt, released);
    ASSERT_EQ(s.status, TerminationType::Converged) << "step " << k << ": " << dyn->last_message();
    const Solution shape = dyn->shape();
    t.push_back(s.t);
    eta1.push_back(modal_coordinate(shape, rt, 1.8751, L));
    eta2.push_back(modal_coordinate(shape, rt, 4.6941, L));
  }
  const double g1 = crossing_frequency(t, eta1), g2 = crossing_frequency(t, eta2);
  EXPECT_NEAR(g1 / f1, 1.0, 0.01) << "f1 " << g1 << " Hz, Euler-Bernoulli " << f1 << " Hz";
  EXPECT_NEAR(g2 / f2, 1.0, 0.01) << "f2 " << g2 << " Hz, Euler-Bernoulli " << f2 << " Hz";
  std::printf("f1 %.4f Hz (EB %.4f), f2 %.4f Hz (EB %.4f), %ld shots over %d steps\n", g1, f1, g2, f2, dyn->shots(), n);
}

// Without damping, implicit midpoint keeps kinetic + potential energy of a large free vibration
// (tip deflection about 8 % of the length): midpoint conserves the quadratic energy of the
// semi-discrete rod exactly, so what drifts is the shooting mesh's error, which falls with the
// mesh as RK4's h^4 (rk4_steps 8 -> 16 at dt = 4e-4 s: 3.8e-7 -> 2.1e-8 of the energy over a
// period). With Kelvin-Voigt damping it falls, step after step.
TEST(DynamicsCosserat, EnergyIsKeptWithoutDampingAndDecaysWithIt) {
  const Robot robot = steel_robot(5);
  const VcModel model(robot, Effects{});
  ModelInput loaded = tensions(robot, {});
  loaded.loads.tip_force = Vec3(0.1, 0.0, 0.0);
  const ModelInput released = tensions(robot, {});
  const double period = 1.0 / eb_frequency(robot, 1.8751);
  const auto drift = [&](int steps, double dt, double tau, std::vector<double>* energy, bool multiple = false,
                         double drag = 0.0) {
    const Solution start = static_answer(model, loaded, steps);
    DynamicsSettings set;
    set.scheme = TimeScheme::ImplicitMidpoint;
    set.bending_damping_time = tau;
    set.shear_damping_time = tau;
    set.air_drag = drag;
    vc::CosseratDynamicsOptions o;
    o.rk4_steps = steps;
    o.shooting =
        multiple ? vc::CosseratDynamicsOptions::Shooting::Multiple : vc::CosseratDynamicsOptions::Shooting::Single;
    auto dyn = vc::make_vc_dynamics(model, set, dt, o);
    dyn->initialize(start, loaded);
    const int n = static_cast<int>(std::ceil(period / dt));
    double e0 = NAN, worst = 0.0;
    for (int k = 1; k <= n; ++k) {
      const SimulationStep s = dyn->advance_with_input(k * dt, released);
      if (s.status != TerminationType::Converged) {
        ADD_FAILURE() << "step " << k << ": " << dyn->last_message();
        return static_cast<double>(NAN);
      }
      const double e = s.kinetic_energy + s.potential_energy;
      if (energy) energy->push_back(e);
      if (k == 1) e0 = e;
      worst = std::max(worst, std::abs(e - e0) / e0);
    }
    return worst;
  };
  const double d1 = drift(8, 4e-4, 0.0, nullptr), d2 = drift(16, 4e-4, 0.0, nullptr);
  std::printf("energy drift over a period: %.3e (rk4_steps 8), %.3e (16)\n", d1, d2);
  EXPECT_LT(d1, 1e-6);
  EXPECT_LT(d2, d1 / 8.0);  // RK4: 16 x less
  // At dt = 2e-4 s single shooting's Newton loses its way on this swing (step 7: line search
  // fails); multiple shooting goes through the period. Its drift is larger: the mesh's error
  // grows with c0 = 2 / dt (the rod's response to a step has the length scale (EI / (rho A
  // c0^2))^(1/4), 10 mm here, that RK4's 1.25 mm steps resolve less well than 14 mm).
  const double d3 = drift(8, 2e-4, 0.0, nullptr, true);
  std::printf("multiple shooting, dt 2e-4: %.3e\n", d3);
  EXPECT_LT(d3, 1e-5);
  // Dissipation: Kelvin-Voigt, then air drag alone (0.1 N s^2/m^3, 0.8 N/m at the tip's peak
  // 2.8 m/s, 170 times the drag of air on a 0.8 mm wire, 1/2 rho_air C_d D: half the energy
  // goes in a period).
  for (const auto& [tau, drag] : {std::pair{1e-4, 0.0}, std::pair{0.0, 0.1}}) {
    std::vector<double> e;
    drift(8, 4e-4, tau, &e, false, drag);
    ASSERT_GT(e.size(), 2u);
    int rises = 0;
    for (std::size_t k = 1; k < e.size(); ++k) rises += e[k] >= e[k - 1];
    EXPECT_EQ(rises, 0) << "tau " << tau << ", drag " << drag;
    EXPECT_LT(e.back(), 0.999 * e.front()) << "tau " << tau << ", drag " << drag;
    std::printf("tau %g s, drag %g: energy %.6e -> %.6e J over a period\n", tau, drag, e.front(), e.back());
  }
}

// A step whose Newton solve does not converge says so (never Converged), and leaves the state at
// the last converged time; the inputs a Cosserat integrator cannot take are InputErrors naming
// the field.
TEST(DynamicsCosserat, FailedStepsAndBadInputsAreReported) {
  const Robot robot = steel_robot(5);
  const VcModel model(robot, Effects{});
  const ModelInput rest = tensions(robot, {});
  const ModelInput pulled = tensions(robot, {3.0, 0.0, 0.0, 0.0});
  vc::CosseratDynamicsOptions o;
  o.max_iterations = 1;  // one Newton iteration cannot take a 3 N step
  auto dyn = vc::make_vc_dynamics(model, DynamicsSettings{}, 1.0 / 60.0, o);
  dyn->initialize(static_answer(model, rest, o.rk4_steps), rest);
  const SimulationStep s = dyn->advance_with_input(1.0 / 60.0, pulled);
  EXPECT_NE(s.status, TerminationType::Converged);
  EXPECT_EQ(dyn->time(), 0.0);
  EXPECT_LT(dyn->shape().tip().p.head<2>().norm(), 1e-12);  // still the straight start

  const auto field_of = [](const auto& make) -> std::string {
    try {
      make();
    } catch (const InputError& e) {
      return e.field();
    }
    return "(no error)";
  };
  const VcModel massless(paper::robot(5), Effects{});
  EXPECT_EQ(field_of([&] { vc::make_vc_dynamics(massless, DynamicsSettings{}, 0.01); }), "robot.backbone.density");
  DynamicsSettings bad;
  bad.alpha = 0.5;
  EXPECT_EQ(field_of([&] { vc::make_vc_dynamics(model, bad, 0.01); }), "dynamics.alpha");
  EXPECT_EQ(field_of([&] { vc::make_vc_dynamics(model, DynamicsSettings{}, -1.0); }), "dt");
  auto fresh = vc::make_vc_dynamics(model, DynamicsSettings{}, 0.01);
  fresh->initialize(static_answer(model, rest, 2), rest);
  ModelInput displaced = rest;
  displaced.actuation.kind = Actuation::Kind::Displacements;
  EXPECT_EQ(field_of([&] { fresh->advance_with_input(0.01, displaced); }), "actuation.kind");
}

// VCref's chords approach VC's fully constrained tendons as the disks get closer, in motion too:
// the largest tip distance over a damped tension step (0.1 s) falls with n, as 1 / n^2 (3.1e-5,
// 7.8e-6, 2.0e-6 m at n = 5, 10, 20).
TEST(DynamicsCosserat, VcAndVcrefAgreeAsDisksGetCloser) {
  DynamicsSettings set;
  set.bending_damping_time = 0.01;
  set.shear_damping_time = 0.01;
  set.alpha = 0.0;
  const double dt = 0.005;
  std::vector<double> gap;
  for (const int n : {5, 10, 20}) {
    const Robot robot = steel_robot(n);
    const VcModel vc_model(robot, Effects{});
    const std::unique_ptr<StaticModel> ref_model = make_model(ModelKind::VCref, robot, Effects{});
    const ModelInput rest = tensions(robot, {});
    const ModelInput pulled = tensions(robot, {1.0, 0.0, 0.5, 0.0});
    vc::CosseratDynamicsOptions o;
    auto a = vc::make_vc_dynamics(vc_model, set, dt, o);
    auto b = vc::make_vcref_dynamics(*ref_model, set, dt, o);
    a->initialize(static_answer(vc_model, rest, o.rk4_steps), rest);
    b->initialize(static_answer(*ref_model, rest, o.rk4_steps), rest);
    double worst = 0.0;
    for (int k = 1; k <= 20; ++k) {
      const SimulationStep sa = a->advance_with_input(k * dt, pulled), sb = b->advance_with_input(k * dt, pulled);
      ASSERT_EQ(sa.status, TerminationType::Converged) << "VC, n " << n << ", step " << k << ": " << a->last_message();
      ASSERT_EQ(sb.status, TerminationType::Converged)
          << "VCref, n " << n << ", step " << k << ": " << b->last_message();
      worst = std::max(worst, (sa.tip.p - sb.tip.p).norm());
    }
    gap.push_back(worst);
    std::printf("n = %d: largest tip distance VC - VCref %.3e m\n", n, worst);
  }
  EXPECT_LT(gap[1], 0.35 * gap[0]);
  EXPECT_LT(gap[2], 0.35 * gap[1]);
}

// The time schemes converge at their order: the cantilever's tip force (small: a linear swing)
// is taken off smoothly, F (1 + cos(pi t / T)) / 2 over T = 9.6 ms, so that the modes the steps
// cannot resolve are hardly excited; the tip at T with dt = 4e-4, 2e-4, 1e-4 s: for a
// second-order scheme the differences of successive results fall fourfold (Richardson:
// (x1 - x2) / (x2 - x3) -> 2^2). Midpoint, BDF2 (alpha 0) and BDF-alpha (alpha -0.2: still second
// order, Till et al. 2019).
TEST(DynamicsCosserat, TimeSchemesConvergeAtSecondOrder) {
  const Robot robot = steel_robot(5);
  const VcModel model(robot, Effects{});
  const int steps = 4;
  const double T = 9.6e-3;
  const auto input = [&](double t) {
    ModelInput in = tensions(robot, {});
    in.loads.tip_force = Vec3(1e-3 * 0.5 * (1.0 + std::cos(M_PI * std::min(t / T, 1.0))), 0.0, 0.0);
    return in;
  };
  const Solution start = static_answer(model, input(0.0), steps);
  struct Scheme {
    const char* name;
    TimeScheme scheme;
    double alpha;
  };
  for (const Scheme& sc :
       {Scheme{"midpoint", TimeScheme::ImplicitMidpoint, 0.0}, Scheme{"BDF2", TimeScheme::BdfAlpha, 0.0},
        Scheme{"BDF-alpha -0.2", TimeScheme::BdfAlpha, -0.2}}) {
    double x[3];
    for (int r = 0; r < 3; ++r) {
      const double dt = 4e-4 / (1 << r);
      DynamicsSettings set;
      set.scheme = sc.scheme;
      set.alpha = sc.alpha;
      vc::CosseratDynamicsOptions o;
      o.rk4_steps = steps;
      auto dyn = vc::make_vc_dynamics(model, set, dt, o);
      dyn->initialize(start, input(0.0));
      SimulationStep s;
      const bool midpoint = sc.scheme == TimeScheme::ImplicitMidpoint;
      for (int k = 1; k <= (24 << r); ++k) {
        s = dyn->advance_with_input(k * dt, input(midpoint ? (k - 0.5) * dt : k * dt));
        ASSERT_EQ(s.status, TerminationType::Converged) << sc.name << ", dt " << dt << ", step " << k;
      }
      x[r] = s.tip.p.x();
    }
    const double ratio = (x[0] - x[1]) / (x[1] - x[2]);
    std::printf("%s: tip x %.9e, %.9e, %.9e m; Richardson ratio %.2f\n", sc.name, x[0], x[1], x[2], ratio);
    EXPECT_GT(ratio, 3.0) << sc.name;
    EXPECT_LT(ratio, 5.5) << sc.name;
  }
}

// advance(t, timeline) takes the timeline's input: a one-entry timeline (held constant, the same
// under any interpolation) gives advance_with_input's steps bit for bit, for both schemes.
TEST(DynamicsCosserat, AdvanceReadsTheTimeline) {
  const Robot robot = steel_robot(5);
  const VcModel model(robot, Effects{});
  const ModelInput rest = tensions(robot, {});
  const ModelInput pulled = tensions(robot, {1.0, 0.0, 0.0, 0.0});
  Timeline timeline;
  timeline.entries.push_back(TimelineEntry{0.0, pulled});
  for (const TimeScheme scheme : {TimeScheme::BdfAlpha, TimeScheme::ImplicitMidpoint}) {
    DynamicsSettings set;
    set.scheme = scheme;
    set.bending_damping_time = 0.01;
    const Solution start = static_answer(model, rest, 2);
    auto a = vc::make_vc_dynamics(model, set, 0.01);
    auto b = make_cosserat_dynamics_integrator(model, set, 0.01);
    a->initialize(start, rest);
    b->initialize(start, rest);
    for (int k = 1; k <= 5; ++k) {
      const SimulationStep sa = a->advance_with_input(0.01 * k, pulled), sb = b->advance(0.01 * k, timeline);
      ASSERT_EQ(sb.status, TerminationType::Converged);
      EXPECT_EQ(sa.tip.p, sb.tip.p) << "step " << k;
      EXPECT_EQ(sa.kinetic_energy, sb.kinetic_energy) << "step " << k;
    }
    EXPECT_GT(b->shape().tip().p.head<2>().norm(), 1e-4);  // it moved
  }
}

// --- Displacement input (the tensions of the driven tendons are unknowns of every step) ---

namespace {

// Tendon 1 by displacement `d` (m), the others by tension 0 (mixed input).
ModelInput pull_tendon_1(const Robot& r, double d) {
  ModelInput in = tensions(r, {});
  in.actuation.kind = Actuation::Kind::Displacements;
  in.actuation.kinds.assign(r.tendon_count(), Actuation::Kind::Tensions);
  in.actuation.kinds[0] = Actuation::Kind::Displacements;
  in.actuation.values[0] = d;
  return in;
}

DynamicsSettings damped() {
  DynamicsSettings set;
  set.bending_damping_time = 0.01;
  set.shear_damping_time = 0.01;
  set.alpha = 0.0;
  return set;
}

// Tendon 1 pulled by 1 mm within 10 ms, then held: after 0.5 s the tip is on the static
// displacement solve's answer of the same model on the same mesh (to 1e-8 m), with its tension.
void displacement_settles(ModelKind kind, Effects effects) {
  const Robot robot = steel_robot(5);
  const std::unique_ptr<StaticModel> owner = make_model(kind, robot, effects);
  const StaticModel& model = *owner;
  const int steps = 2;
  vc::CosseratDynamicsOptions o;
  o.rk4_steps = steps;
  o.function_tolerance = 1e-12;
  const double dt = 0.005, d = 1e-3;
  auto dyn = kind == ModelKind::VC ? vc::make_vc_dynamics(static_cast<const VcModel&>(model), damped(), dt, o)
                                   : vc::make_vcref_dynamics(model, damped(), dt, o);
  const ModelInput rest = pull_tendon_1(robot, 0.0), held = pull_tendon_1(robot, d);
  dyn->initialize(static_answer(model, rest, steps), rest);
  const Solution target = static_answer(model, held, steps);
  SimulationStep s;
  double early = 0.0;
  for (int k = 1; k <= 100; ++k) {
    s = dyn->advance_with_input(k * dt, pull_tendon_1(robot, d * std::min(1.0, k * dt / 0.01)));
    ASSERT_EQ(s.status, TerminationType::Converged) << "step " << k << ": " << dyn->last_message();
    if (k == 2) early = (s.tip.p - target.tip().p).norm();
  }
  const double err = (s.tip.p - target.tip().p).norm();
  std::printf("%s: tip error %.3e m after 0.5 s (%.3e m at 10 ms); T1 %.9g N (static %.9g N); pull %.3e m\n",
              to_string(kind).c_str(), err, early, s.tensions[0], target.tensions[0], s.tendon_displacements[0]);
  EXPECT_LT(err, 1e-8);
  // It moved (the tip far from the straight start), and by dynamics: when the pull is complete
  // (10 ms) the robot is still on its way (measured 3.6e-5 m: a pulled tendon drives the robot
  // stiffly, it follows closely).
  EXPECT_GT(s.tip.p.head<2>().norm(), 1e-3);
  EXPECT_GT(early, 1e-6);
  EXPECT_NEAR(s.tensions[0], target.tensions[0], 1e-6 * target.tensions[0]);
  EXPECT_GT(s.tensions[0], 0.1);
  EXPECT_EQ(s.tensions[1], 0.0);
  // The path meets the command (VCref: its chords of the published shape, whose disks meet the
  // solve's nodes to the continuity tolerance; measured 6e-12 m).
  EXPECT_NEAR(s.tendon_displacements[0], d, 1e-10);
}

}  // namespace

TEST(DynamicsCosserat, HeldDisplacementSettlesOnTheStaticDisplacementSolve) {
  displacement_settles(ModelKind::VC, Effects{});
  Effects removed;
  removed.disk_normal_force = DiskNormalForce::Removed;
  displacement_settles(ModelKind::VCref, removed);
}

// A displacement timeline made of a tension run's reported pulls of tendon 1 (one entry per
// output step) moves the robot as the tension run did, and its solved tension is the tension
// run's: both runs solve the same step equations at every step (BDF2, the same mesh), one with
// T_1 given, the other with the pull given, each to Newton's tolerance 1e-10 (scaled); the
// differences are that tolerance carried through the steps (measured: below 1e-9 m, 1e-6 N).
TEST(DynamicsCosserat, DisplacementsOfATensionRunReproduceIt) {
  const Robot robot = steel_robot(5);
  for (const ModelKind kind : {ModelKind::VC, ModelKind::VCref}) {
    const std::unique_ptr<StaticModel> model = make_model(kind, robot, Effects{});
    Timeline pulled;
    pulled.entries.push_back(TimelineEntry{0.0, tensions(robot, {})});
    pulled.entries.push_back(TimelineEntry{0.02, tensions(robot, {2.0, 0.0, 0.0, 0.0})});
    pulled.entries.push_back(TimelineEntry{0.05, tensions(robot, {0.5, 0.0, 0.0, 0.0})});
    SimulationOptions opt;
    opt.duration = 0.1;
    opt.dt = 0.005;
    const SolverOptions solver = test::fixed_mesh_settings();
    const SimulationResult a = simulate(*model, damped(), pulled, opt, solver);
    ASSERT_TRUE(a.completed) << a.message;
    Timeline driven;
    for (const SimulationStep& s : a.steps) {
      ASSERT_EQ(s.tendon_displacements.size(), 4u);
      driven.entries.push_back(TimelineEntry{s.t, pull_tendon_1(robot, s.tendon_displacements[0])});
    }
    const SimulationResult b = simulate(*model, damped(), driven, opt, solver);
    ASSERT_TRUE(b.completed) << b.message;
    ASSERT_EQ(a.steps.size(), b.steps.size());
    double tip = 0.0, tension = 0.0, moved = 0.0;
    for (std::size_t k = 0; k < a.steps.size(); ++k) {
      tip = std::max(tip, (a.steps[k].tip.p - b.steps[k].tip.p).norm());
      tension = std::max(tension, std::abs(a.steps[k].tensions[0] - b.steps[k].tensions[0]));
      moved = std::max(moved, a.steps[k].tip.p.head<2>().norm());
      EXPECT_EQ(b.steps[k].tensions[1], 0.0);
    }
    std::printf("%s: largest tip difference %.3e m, tension difference %.3e N (tip moved %.3e m)\n",
                to_string(kind).c_str(), tip, tension, moved);
    EXPECT_GT(moved, 1e-3);
    EXPECT_LT(tip, 1e-8);
    EXPECT_LT(tension, 1e-5);
    EXPECT_GT(b.steps.back().potential_energy, 0.0);
  }
}

// Tendon 1 pulled by 1 mm, then released within 5 ms to 1 mm beyond its straight length: the
// robot cannot follow a release that fast, so the tendon goes slack with exactly zero tension
// while the robot swings back, and stays slack once the robot is straight again (the command is
// longer than its path), the tip back on the straight robot's.
TEST(DynamicsCosserat, ReleasedTendonGoesSlackWithZeroTension) {
  const Robot robot = steel_robot(5);
  for (const ModelKind kind : {ModelKind::VC, ModelKind::VCref}) {
    const std::unique_ptr<StaticModel> model = make_model(kind, robot, Effects{});
    Timeline timeline;
    timeline.entries.push_back(TimelineEntry{0.0, pull_tendon_1(robot, 0.0)});
    timeline.entries.push_back(TimelineEntry{0.01, pull_tendon_1(robot, 1e-3)});
    timeline.entries.push_back(TimelineEntry{0.2, pull_tendon_1(robot, 1e-3)});
    timeline.entries.push_back(TimelineEntry{0.205, pull_tendon_1(robot, -1e-3)});
    SimulationOptions opt;
    opt.duration = 0.6;
    opt.dt = 0.005;
    const SimulationResult r = simulate(*model, damped(), timeline, opt, test::fixed_mesh_settings());
    ASSERT_TRUE(r.completed) << r.message;
    const SimulationStep& held = r.steps[40];  // t = 0.2 s
    const SimulationStep& released = r.steps[42];  // t = 0.21 s, just after the release
    const SimulationStep& end = r.steps.back();
    std::printf("%s: T1 %.6g N held, %.3g N released (pull %.3e m, command -1e-3 m), %.3g N at the end; tip %.3e m "
                "off the axis\n",
                to_string(kind).c_str(), held.tensions[0], released.tensions[0], released.tendon_displacements[0],
                end.tensions[0], end.tip.p.head<2>().norm());
    EXPECT_GT(held.tensions[0], 0.1);
    EXPECT_GT(held.tip.p.head<2>().norm(), 1e-3);
    EXPECT_EQ(released.tensions[0], 0.0);
    EXPECT_GT(released.tendon_displacements[0], -1e-3);  // the path is shorter than the command: slack
    EXPECT_EQ(end.tensions[0], 0.0);
    EXPECT_LT(end.tip.p.head<2>().norm(), 1e-8);
    EXPECT_NEAR(end.tip.p.z(), robot.total_length(), 1e-8);
    EXPECT_NEAR(end.tendon_displacements[0], 0.0, 1e-9);
  }
}

// The start's energies, every model with dynamics: kinetic 0 at rest, potential the start's true
// one, the same as the next step's at rest under the same input (each integrator's own
// expression). A constant tension's potential is T times its path length, so the straight robot
// under 1 N on tendon 1 (path 0.05 m) has 0.05 J; bent, the elastic energy U_e and the pull d
// give 0.05 J + U_e - T d = 0.05 J - U_e (linear: T d = 2 U_e), measured 0.0496 J by all four
// models, 1.5e-5 apart (their shapes differ).
TEST(DynamicsCosserat, StartReportsItsPotentialEnergy) {
  const Robot robot = steel_robot(5);
  std::vector<double> starts;
  for (const ModelKind kind : {ModelKind::VC, ModelKind::VCref, ModelKind::CCsub, ModelKind::PRB}) {
    const std::unique_ptr<StaticModel> model = make_model(kind, robot, Effects{});
    Timeline timeline;
    timeline.entries.push_back(TimelineEntry{0.0, tensions(robot, {1.0, 0.0, 0.0, 0.0})});
    SimulationOptions opt;
    opt.duration = 0.01;
    opt.dt = 0.005;
    const SimulationResult r = simulate(*model, damped(), timeline, opt, test::fixed_mesh_settings());
    ASSERT_TRUE(r.completed) << to_string(kind) << ": " << r.message;
    const double U0 = r.steps[0].potential_energy;
    std::printf("%s: potential energy at t = 0 %.9e J, at 5 ms %.9e J\n", to_string(kind).c_str(), U0,
                r.steps[1].potential_energy);
    EXPECT_EQ(r.steps[0].kinetic_energy, 0.0);
    EXPECT_LT(U0, 0.05 - 1e-4) << to_string(kind);  // bent: below the straight robot's 0.05 J
    EXPECT_GT(U0, 0.04) << to_string(kind);
    EXPECT_NEAR(r.steps[1].potential_energy, U0, 1e-6 * std::abs(U0)) << to_string(kind);
    starts.push_back(U0);
  }
  for (const double U : starts) EXPECT_NEAR(U, starts[0], 1e-4 * starts[0]);
}

// Displacement input is refused per model: CCsub's dynamics take tensions only so far.
TEST(DynamicsCosserat, DisplacementInputIsRefusedWhereNotSupported) {
  const Robot robot = steel_robot(5);
  const std::unique_ptr<StaticModel> model = make_model(ModelKind::CCsub, robot, Effects{});
  Timeline timeline;
  timeline.entries.push_back(TimelineEntry{0.0, pull_tendon_1(robot, 0.0)});
  SimulationOptions opt;
  opt.duration = 0.01;
  try {
    simulate(*model, damped(), timeline, opt, SolverOptions{});
    ADD_FAILURE() << "CCsub took displacement input on an inextensible tendon";
  } catch (const InputError& e) {
    // CCsub's dynamics take motors on elastic tendons only (tests/test_dynamics_lumped.cpp).
    EXPECT_EQ(e.field(), "robot.segments[0].tendons[0].stiffness") << e.what();
  }
}

// The disks' rotary inertia: a robot with heavy wide disks (1 g, 10 mm radius: polar inertia
// 5e-8 kg m^2 each, 16 000 times its backbone interval's 3.1e-12) twisted by a tip moment and
// released twists back and forth as the chain of torsional springs GJ / h and disk inertias
// m r^2 / 2: fixed at the base, free at the tip, its first frequency is
// (1 / pi) sqrt(k / J) sin(pi / (2 (2 n + 1))) Hz for n disks. Measured through the disks' twist
// projected on that mode (sin(j pi / (2 n + 1)), disk j), zero crossings, VC by implicit
// midpoint; undamped, its energy (the disks' rotation included) is kept.
TEST(DynamicsCosserat, DiskRotaryInertiaSetsTheTorsionalFrequency) {
  Robot robot = steel_robot(5);
  for (Segment& seg : robot.segments) {
    seg.disk_mass = 1e-3;
    seg.disk_radius = 0.01;
  }
  const VcModel model(robot, Effects{});
  const TendonRouting& rt = model.routing();
  const int n = rt.disk_count() - 1;
  const double h = robot.total_length() / n;
  const double GJ = robot.backbone.effective_stiffness().GJ, J = 1e-3 * 0.01 * 0.01 / 2.0;
  const double theta = M_PI / (2.0 * (2 * n + 1));
  const double f1 = std::sqrt(GJ / h / J) * std::sin(theta) / M_PI;
  ModelInput twisted = tensions(robot, {});
  twisted.loads.tip_moment = Vec3(0.0, 0.0, 1e-3);  // 0.03 rad at the tip: linear
  const ModelInput released = tensions(robot, {});
  DynamicsSettings set;
  set.scheme = TimeScheme::ImplicitMidpoint;
  const double dt = 1e-4;
  auto dyn = vc::make_vc_dynamics(model, set, dt);
  dyn->initialize(static_answer(model, twisted, 2), twisted);
  std::vector<double> t, eta;
  double e0 = NAN, drift = 0.0, peak_kinetic = 0.0;
  const int steps = static_cast<int>(std::ceil(3.2 / f1 / dt));
  for (int k = 1; k <= steps; ++k) {
    const SimulationStep s = dyn->advance_with_input(k * dt, released);
    ASSERT_EQ(s.status, TerminationType::Converged) << "step " << k << ": " << dyn->last_message();
    const Solution shape = dyn->shape();
    double q = 0.0;
    for (int j = 1; j <= n; ++j)
      q += std::sin(j * 2.0 * theta) * std::atan2(shape.disk_frames[j].R(1, 0), shape.disk_frames[j].R(0, 0));
    t.push_back(s.t);
    eta.push_back(q);
    const double e = s.kinetic_energy + s.potential_energy;
    if (k == 1) e0 = e;
    drift = std::max(drift, std::abs(e - e0));
    peak_kinetic = std::max(peak_kinetic, s.kinetic_energy);
  }
  const double g1 = crossing_frequency(t, eta);
  std::printf("torsion f1 %.4f Hz (disk chain %.4f Hz), energy drift %.3e of the peak kinetic %.3e J\n", g1, f1,
              drift / peak_kinetic, peak_kinetic);
  // Without the disks' rotary inertia the twist would ring at the backbone's own polar inertia,
  // over a hundred times faster.
  EXPECT_NEAR(g1 / f1, 1.0, 0.005);
  EXPECT_LT(drift, 1e-4 * peak_kinetic);
}
