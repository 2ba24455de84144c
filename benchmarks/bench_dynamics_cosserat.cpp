// Speed and accuracy of VC's Cosserat rod dynamics (models/vc/vc_dynamics*.cpp) on the paper's
// robot: n = 10 disks per segment, a spring-steel backbone (density 7800 kg/m^3; the paper gives
// none), massless disks, no gravity. From rest (straight), tendon 1 steps to T_M (Eq. 55, the
// 90 deg bend of configuration 2) at t = 0+ and holds for 2 s; dt = 1/60 s, BDF-alpha
// (alpha -0.2), Kelvin-Voigt damping tau_bt = tau_se = 0.01 s; RK4 with 2 steps per 5 mm disk
// interval (160 evaluation points, the "200 grid points" of Till, Aloi and Rucker 2019).
//
// Reports the real-time ratio (simulated time / wall time, best of the repeats), Newton
// iterations and shots per step, and the accuracy: the tip over time against a run with dt / 4 on
// the same mesh (time error) and against a run on a 4 x finer mesh with the same dt (space
// error), and the final tip against VC's static answer of the held input on the same mesh.
//
// Usage: bench_dynamics_cosserat [--quick]   (--quick: 0.5 s simulated, one repeat: the ctest
// smoke run)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <vector>

#include "bench_common.hpp"
#include "tdcr/core/paper_robot.hpp"
#include "tdcr/models/vc.hpp"
#include "vc/vc_dynamics.hpp"

using namespace tdcr;

namespace {

struct Run {
  std::vector<SimulationStep> steps;
  double best_wall_s = INFINITY;
  double best_transient_s = INFINITY;  ///< Wall time of the first 0.5 s (the motion).
  long shots = 0;
  int points = 0;
  bool ok = true;
  std::string message;
};

// `multiple`: VC by multiple shooting; VCref always is.
Run simulate(const StaticModel& model, const ModelInput& rest, const ModelInput& pulled, const DynamicsSettings& set,
             double dt, double duration, int rk4_steps, int repeat, bool multiple = false) {
  SolverOptions so;
  so.integrator = IntegratorKind::FixedStepRK4;
  so.rk4_steps = rk4_steps;
  so.rk4_max_step = std::numeric_limits<double>::infinity();
  so.function_tolerance = 1e-10;
  auto ws = model.make_workspace();
  const Solution start = solve(model, *ws, rest, so);
  Run r;
  vc::CosseratDynamicsOptions o;
  o.rk4_steps = rk4_steps;
  o.shooting =
      multiple ? vc::CosseratDynamicsOptions::Shooting::Multiple : vc::CosseratDynamicsOptions::Shooting::Automatic;
  const int n = static_cast<int>(std::lround(duration / dt));
  for (int rep = 0; rep < repeat; ++rep) {
    auto dyn = model.kind() == ModelKind::VC ? vc::make_vc_dynamics(static_cast<const VcModel&>(model), set, dt, o)
                                             : vc::make_vcref_dynamics(model, set, dt, o);
    dyn->initialize(start, rest);
    std::vector<SimulationStep> steps;
    steps.reserve(n);
    const auto t0 = std::chrono::steady_clock::now();
    for (int k = 1; k <= n; ++k) {
      steps.push_back(dyn->advance_with_input(k * dt, pulled));
      if (k == static_cast<int>(std::lround(0.5 / dt)))
        r.best_transient_s =
            std::min(r.best_transient_s, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      if (steps.back().status != TerminationType::Converged) {
        r.ok = false;
        r.message = "step " + std::to_string(k) + ": " + dyn->last_message();
        break;
      }
    }
    r.best_wall_s =
        std::min(r.best_wall_s, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    r.steps = steps;
    r.shots = dyn->shots();
    r.points = dyn->mesh_points();
    if (!r.ok) break;
  }
  return r;
}

// Largest tip distance between two runs at their common output times (`b` every `every` steps).
double max_tip_difference(const Run& a, const Run& b, int every) {
  double worst = 0.0;
  for (std::size_t k = 0; k < a.steps.size(); ++k) {
    const std::size_t kb = (k + 1) * every - 1;
    if (kb >= b.steps.size()) break;
    worst = std::max(worst, (a.steps[k].tip.p - b.steps[kb].tip.p).norm());
  }
  return worst;
}

}  // namespace

int main(int argc, char** argv) {
  const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
  const double duration = quick ? 0.5 : 2.0;
  const int repeat = quick ? 1 : 5;
  const double dt = 1.0 / 60.0;
  const int rk4_steps = 2;

  Robot robot = paper::robot(10);
  robot.backbone.density = 7800.0;
  const VcModel model(robot, Effects{});
  const double t_max = paper::max_tension(robot);
  ModelInput rest, pulled;
  rest.actuation.values.assign(robot.tendon_count(), 0.0);
  pulled = rest;
  pulled.actuation.values[0] = t_max;
  DynamicsSettings set;
  set.bending_damping_time = 0.01;
  set.shear_damping_time = 0.01;
  set.alpha = -0.2;

  std::printf("%s", bench::machine_stamp().c_str());
  std::printf(
      "VC dynamics: paper robot n = 10 (2 x 50 mm, 0.8 mm steel backbone, rho 7800 kg/m^3, massless disks),\n"
      "tension step T1 = %.4f N (T_M) at t = 0+, held %.1f s; dt = 1/60 s, BDF-alpha alpha = %.1f,\n"
      "tau_bt = tau_se = %.3f s, no gravity, no drag; RK4 x%d per disk interval\n",
      t_max, duration, set.alpha, set.bending_damping_time, rk4_steps);

  const Run main_run = simulate(model, rest, pulled, set, dt, duration, rk4_steps, repeat);
  if (!main_run.ok) {
    std::printf("FAILED: %s\n", main_run.message.c_str());
    return 1;
  }
  const std::size_t n = main_run.steps.size();
  int it_sum = 0, it_max = 0;
  for (const SimulationStep& s : main_run.steps) {
    it_sum += s.iterations;
    it_max = std::max(it_max, s.iterations);
  }
  const double rtr = duration / main_run.best_wall_s;
  std::printf("evaluation points %d, steps %zu, wall %.4f s (best of %d): real-time ratio %.1f\n", main_run.points, n,
              main_run.best_wall_s, repeat, rtr);
  std::printf("Newton iterations per step: mean %.2f, max %d; shots per step %.2f\n", double(it_sum) / n, it_max,
              double(main_run.shots) / n);
  std::printf("the motion alone (first 0.5 s, %ld steps): wall %.4f s, real-time ratio %.1f\n", std::lround(0.5 / dt),
              main_run.best_transient_s, 0.5 / main_run.best_transient_s);

  // Accuracy: dt / 4 on the same mesh; 4 x finer mesh with the same dt; the static answer.
  const Run fine_t = simulate(model, rest, pulled, set, dt / 4.0, duration, rk4_steps, 1);
  const Run fine_s = simulate(model, rest, pulled, set, dt, duration, 4 * rk4_steps, 1);
  SolverOptions so;
  so.integrator = IntegratorKind::FixedStepRK4;
  so.rk4_steps = rk4_steps;
  so.rk4_max_step = std::numeric_limits<double>::infinity();
  so.function_tolerance = 1e-12;
  auto ws = model.make_workspace();
  const Solution held = solve(model, *ws, pulled, so);
  if (!fine_t.ok || !fine_s.ok || !held.converged()) {
    std::printf("FAILED: reference runs (%s %s)\n", fine_t.message.c_str(), fine_s.message.c_str());
    return 1;
  }
  const Vec3 tip = main_run.steps.back().tip.p;
  std::printf("tip at t = %.2f s: (%.6f, %.6f, %.6f) m\n", duration, tip.x(), tip.y(), tip.z());
  std::printf("time error (vs dt/4):        max over t %.3e m\n", max_tip_difference(main_run, fine_t, 4));
  std::printf("space error (vs RK4 x%d):     max over t %.3e m\n", 4 * rk4_steps,
              max_tip_difference(main_run, fine_s, 1));
  std::printf("tip vs dt/4 at t =");
  for (const double t : {1.0 / 60.0, 0.05, 0.1, 0.25, 0.5, 1.0, 2.0}) {
    const int k = static_cast<int>(std::lround(t / dt)) - 1;
    if (k >= static_cast<int>(n)) break;
    std::printf(" %.3f s: %.2e m;", t, (main_run.steps[k].tip.p - fine_t.steps[4 * k + 3].tip.p).norm());
  }
  std::printf("\n");
  std::printf("final tip vs static answer:  %.3e m\n", (tip - held.tip().p).norm());
  std::printf("real-time ratio %.1f over %.1f s, %.1f over the motion (target >= 20; Till et al. 2019: 3.5)\n", rtr,
              duration, 0.5 / main_run.best_transient_s);

  // The same step by multiple shooting: VC (the formulation for short time steps), and VCref
  // (the paper's disk force, Eq. 58 removed; the paper's robot with its effects).
  const std::unique_ptr<StaticModel> vcref = make_model(ModelKind::VCref, robot, paper::effects("vcref"));
  struct Other {
    const char* name;
    const StaticModel* model;
    bool multiple;
  };
  int status = 0;
  for (const Other& v :
       {Other{"VC, multiple shooting", &model, true}, Other{"VCref (Eq. 58 removed)", vcref.get(), true}}) {
    const Run r = simulate(*v.model, rest, pulled, set, dt, duration, rk4_steps, repeat, v.multiple);
    if (!r.ok) {
      std::printf("%s: FAILED: %s\n", v.name, r.message.c_str());
      status = 1;
      continue;
    }
    int its = 0, itmax = 0;
    for (const SimulationStep& s : r.steps) {
      its += s.iterations;
      itmax = std::max(itmax, s.iterations);
    }
    std::printf(
        "%s: wall %.4f s, real-time ratio %.1f (%.1f over the motion); iterations per step mean %.2f, max %d; "
        "shots per step %.2f; tip at %.1f s (%.6f, %.6f, %.6f) m, %.3e m from VC's single shooting\n",
        v.name, r.best_wall_s, duration / r.best_wall_s, 0.5 / r.best_transient_s, double(its) / r.steps.size(), itmax,
        double(r.shots) / r.steps.size(), duration, r.steps.back().tip.p.x(), r.steps.back().tip.p.y(),
        r.steps.back().tip.p.z(), (r.steps.back().tip.p - tip).norm());
  }
  std::printf("(targets: VC >= 20, VCref >= 5)\n");
  return status;
}
