// VC's Cosserat rod dynamics (models/vc/vc_dynamics*.cpp) against physics: the static limit of
// a damped step, the first two bending frequencies of a straight cantilever against
// Euler-Bernoulli, energy conservation without damping (implicit midpoint) and its decay with
// damping. The integrator is driven through advance_with_input (the Timeline functions belong
// to the dynamics front end).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "fixed_mesh_settings.hpp"
#include "tdcr/core/paper_robot.hpp"
#include "tdcr/core/error.hpp"
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
Solution static_answer(const VcModel& model, const ModelInput& in, int rk4_steps) {
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

// A tension step with Kelvin-Voigt damping settles on VC's static answer of the same input on
// the same mesh, to 1e-8 m.
TEST(DynamicsCosserat, DampedStepSettlesOnTheStaticAnswer) {
  const Robot robot = steel_robot(5);
  const VcModel model(robot, Effects{});
  const int steps = 2;
  const ModelInput rest = tensions(robot, {});
  const ModelInput pulled = tensions(robot, {1.0, 0.0, 0.5, 0.0});
  DynamicsSettings set;
  set.bending_damping_time = 0.01;
  set.shear_damping_time = 0.01;
  set.alpha = 0.0;
  vc::CosseratDynamicsOptions o;
  o.rk4_steps = steps;
  o.function_tolerance = 1e-12;
  const double dt = 0.005;
  auto dyn = vc::make_vc_dynamics(model, set, dt, o);
  dyn->initialize(static_answer(model, rest, steps), rest);
  const Solution target = static_answer(model, pulled, steps);
  SimulationStep s;
  double early = 0.0;
  for (int k = 1; k <= 100; ++k) {
    s = dyn->advance_with_input(k * dt, pulled);
    ASSERT_EQ(s.status, TerminationType::Converged) << "step " << k;
    if (k == 4) early = (s.tip.p - target.tip().p).norm();
  }
  const double err = (s.tip.p - target.tip().p).norm();
  EXPECT_LT(err, 1e-8) << "tip " << s.tip.p.transpose() << " static " << target.tip().p.transpose();
  EXPECT_GT(early, 1e-4);  // it did move: 20 ms after the step it is still on its way
  EXPECT_LT(s.kinetic_energy, 1e-12);
  EXPECT_LT((s.tip.R - target.tip().R).norm(), 1e-7);
}
