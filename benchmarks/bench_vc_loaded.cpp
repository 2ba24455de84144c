// VC on loaded scenes: the paper robot (n = 10) with tensions (0.3, 0, 0.5, 0.1) T_M
// and a tip force (0.2, -0.3, 0.1) N, cold solves; and a warm-started trajectory (n = 10, tip
// force 0.05 N along x, tendon 1 at 0.5 T_M (1 - cos(2 pi k / 1000)), one model and one
// workspace, each step warm-started from the last). Tip errors against CVODE at rtol 1e-12.
//
// Every case runs with forward-difference and exact Jacobians (VcOptions::exact_jacobian), each
// with and without Jacobian reuse along warm starts (VcOptions::reuse_jacobian), in one run.
//
// Usage: bench_vc_loaded [--quick] [--steps N]   (--quick: a few repeats and 20 steps)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "tdcr/core/paper_robot.hpp"
#include "tdcr/models/vc.hpp"

using namespace tdcr;

namespace {

using Clock = std::chrono::steady_clock;

double elapsed_us(Clock::time_point t0) {
  return std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
}

Scene reference_settings(Scene s) {
  s.solver.integrator = IntegratorKind::Cvode;
  s.solver.cvode_rtol = 1e-12;
  s.solver.cvode_atol = 1e-14;
  s.solver.function_tolerance = 1e-13;
  return s;
}

Solution solve_once(const Scene& s, const Solution* warm = nullptr) {
  VcModel model(s.robot, s.effects);
  auto ws = model.make_workspace();
  return solve(model, *ws, s.input(), s.solver, warm);
}

struct Variant {
  const char* name;
  VcOptions options;
};

}  // namespace

int main(int argc, char** argv) {
  bool quick = false;
  int steps = 200;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--quick") == 0) {
      quick = true;
      steps = 20;
    } else if (std::strcmp(argv[i], "--steps") == 0 && i + 1 < argc) {
      steps = std::atoi(argv[++i]);
    }
  }
  const int repeat = quick ? 3 : 100;
  bool ok = true;
  std::vector<Variant> variants;
  for (bool exact : {false, true})
    for (bool reuse : {false, true}) {
      VcOptions o;
      o.exact_jacobian = exact;
      o.reuse_jacobian = reuse;
      variants.push_back({exact ? (reuse ? "exact J, reuse" : "exact J") : (reuse ? "FD J, reuse" : "FD J"), o});
    }

  // Loaded case, cold.
  Scene loaded = paper::scene(10, 1, "vc");
  const double tm = paper::max_tension(loaded.robot);
  loaded.actuation.values = {0.3 * tm, 0.0, 0.5 * tm, 0.1 * tm};
  loaded.loads.tip_force = Vec3(0.2, -0.3, 0.1);
  const Solution ref = solve_once(reference_settings(loaded));
  std::printf("loaded cold (n = 10, T = (0.3, 0, 0.5, 0.1) T_M, F = (0.2, -0.3, 0.1) N), %d repeats:\n", repeat);
  for (const Variant& v : variants) {
    VcModel model(loaded.robot, loaded.effects, v.options);
    auto ws = model.make_workspace();
    std::vector<double> t;
    Solution sol;
    for (int r = 0; r < repeat; ++r) {
      const auto t0 = Clock::now();
      sol = solve(model, *ws, loaded.input(), loaded.solver);
      t.push_back(elapsed_us(t0));
    }
    std::sort(t.begin(), t.end());
    std::printf("  %-15s median %8.1f us, min %8.1f us, %d iterations, %d Jacobians, tip error %.3e m%s\n", v.name,
                t[t.size() / 2], t.front(), sol.summary.iterations, sol.summary.jacobian_evaluations,
                (sol.tip().p - ref.tip().p).norm(), sol.converged() ? "" : "  NOT CONVERGED");
    ok = ok && sol.converged();
  }

  // Trajectory, warm-started; references every 20 steps.
  Scene traj = paper::scene(10, 1, "vc");
  traj.loads.tip_force = Vec3(0.05, 0.0, 0.0);
  const auto set_step = [&](int k) {
    traj.actuation.values = {0.5 * tm * (1.0 - std::cos(2.0 * M_PI * k / 1000.0)), 0.0, 0.0, 0.0};
  };
  std::vector<Vec3> ref_tips;
  for (int k = 0; k < steps; k += 20) {
    set_step(k);
    ref_tips.push_back(solve_once(reference_settings(traj)).tip().p);
  }
  std::printf("trajectory (n = 10, F = 0.05 N x, T1 = 0.5 T_M (1 - cos(2 pi k/1000)), %d warm steps):\n", steps);
  for (const Variant& v : variants) {
    VcModel model(traj.robot, traj.effects, v.options);
    auto ws = model.make_workspace();
    Solution previous;
    double total_us = 0.0, max_err = 0.0;
    long iterations = 0, jacobians = 0;
    bool converged = true;
    for (int k = 0; k < steps; ++k) {
      set_step(k);
      const auto t0 = Clock::now();
      Solution sol = solve(model, *ws, traj.input(), traj.solver, k == 0 ? nullptr : &previous);
      total_us += elapsed_us(t0);
      iterations += sol.summary.iterations;
      jacobians += sol.summary.jacobian_evaluations;
      converged = converged && sol.converged();
      if (k % 20 == 0) max_err = std::max(max_err, (sol.tip().p - ref_tips[k / 20]).norm());
      previous = std::move(sol);
    }
    std::printf("  %-15s %8.1f us per step (%5.0f Hz), %.2f iterations, %.2f Jacobians per step, max tip error "
                "%.3e m%s\n",
                v.name, total_us / steps, 1e6 * steps / total_us, double(iterations) / steps,
                double(jacobians) / steps, max_err, converged ? "" : "  NOT CONVERGED");
    ok = ok && converged;
  }
  return ok ? 0 : 1;
}
