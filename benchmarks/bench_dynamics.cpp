// bench_dynamics: the real-time ratio of the dynamics (tdcr::simulate) on the paper robot in
// motion (examples/paper_robot_dynamics.json: n = 10 disks per segment, a tension step held for
// 2 s, output every 1/60 s), and its accuracy: the largest tip distance over the output steps
// from a reference run of the same model.
//   CCsub, PRB: the reference has the dynamics' tolerances 1e-10 (relative) and 1e-9 m at the tip
//               (lumped_dynamics.cpp), i.e. the error of the default, adaptive integration;
//   VC, VCref:  the reference has a 10 times shorter time step (their time discretisation error
//               at the output step dt, the figure the lumped models' error is compared with).
//   bench_dynamics [--quick] [--models ccsub,prb,vc] [--duration T] [--dt H] [--no-reference]
//                  [--rtol R] [--tip-tolerance M]
// --quick: 0.1 s of motion (the ctest smoke run). --dt: the output step (default 1/60 s).
// --rtol, --tip-tolerance: the scene's solver.cvode_rtol, solver.tip_tolerance (m) set explicitly.
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "bench_common.hpp"
#include "tdcr/core/scene_io.hpp"
#include "tdcr/models/dynamics.hpp"
#include "tdcr/models/static_model.hpp"

using namespace tdcr;

int main(int argc, char** argv) {
  double duration = 2.0, dt = 1.0 / 60.0;
  bool reference = true;
  double rtol = 0.0, tip_tol = 0.0;
  std::string models = "ccsub,prb";
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--quick")) duration = 0.1;
    else if (!std::strcmp(argv[i], "--models") && i + 1 < argc) models = argv[++i];
    else if (!std::strcmp(argv[i], "--duration") && i + 1 < argc) duration = std::stod(argv[++i]);
    else if (!std::strcmp(argv[i], "--dt") && i + 1 < argc) dt = std::stod(argv[++i]);
    else if (!std::strcmp(argv[i], "--no-reference")) reference = false;
    else if (!std::strcmp(argv[i], "--rtol") && i + 1 < argc) rtol = std::stod(argv[++i]);
    else if (!std::strcmp(argv[i], "--tip-tolerance") && i + 1 < argc) tip_tol = std::stod(argv[++i]);
    else {
      std::fprintf(stderr,
                   "usage: bench_dynamics [--quick] [--models ccsub,prb,vc,vcref] [--duration T] [--dt H] "
                   "[--no-reference] [--rtol R] [--tip-tolerance M]\n");
      return 2;
    }
  }
  const std::string path = std::string(TDCR_SOURCE_DIR) + "/examples/paper_robot_dynamics.json";
  Scene scene = load_scene(path);
  if (rtol > 0.0) scene.solver.cvode_rtol = rtol;
  if (tip_tol > 0.0) scene.solver.tip_tolerance = tip_tol;
  SimulationOptions options;
  options.duration = duration;
  options.dt = dt;
  std::printf("scene: %s\nduration %g s, dt %.6g s, damping time %g s, %d disks\n", path.c_str(), duration, options.dt,
              scene.dynamics->bending_damping_time, scene.robot.total_disks());
  std::printf("%-6s %10s %12s %8s %14s %10s\n", "model", "cpu_s", "real_time_x", "steps", "tip_err_m", "tip_z_end");
  int status = 0;
  for (ModelKind kind : bench::parse_models(models)) {
    const auto model = make_model(kind, scene);
    const double c0 = bench::thread_cpu_us();
    const SimulationResult r = simulate(*model, *scene.dynamics, scene.timeline, options, scene.solver);
    const double cpu = (bench::thread_cpu_us() - c0) * 1e-6;
    const bool lumped = kind == ModelKind::CCsub || kind == ModelKind::PRB;
    SimulationResult ref;
    int stride = 1;
    if (reference) {
      SolverOptions tight = scene.solver;
      SimulationOptions fine = options;
      if (lumped) {
        tight.tip_tolerance = 1e-9;
        tight.cvode_rtol = 1e-10;
      } else {
        stride = 10;
        fine.dt = options.dt / stride;
      }
      ref = simulate(*model, *scene.dynamics, scene.timeline, fine, tight);
    }
    double err = 0.0;
    long steps = 0;
    for (std::size_t k = 0; k < r.steps.size(); ++k) {
      steps += r.steps[k].iterations;
      if (k * stride < ref.steps.size()) err = std::max(err, (r.steps[k].tip.p - ref.steps[k * stride].tip.p).norm());
    }
    std::printf("%-6s %10.4f %12.1f %8ld %14.3e %10.6f%s\n", to_string(kind).c_str(), cpu, duration / cpu, steps,
                reference ? err : 0.0, r.steps.back().tip.p.z(),
                r.completed && (!reference || ref.completed) ? "" : "  (stopped early)");
    if (!r.completed) {
      std::printf("  %s\n", r.message.c_str());
      status = 1;
    }
  }
  return status;
}
