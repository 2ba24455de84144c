// bench_dynamics: the real-time ratio of the lumped models' dynamics (tdcr::simulate) on the
// paper robot in motion (examples/paper_robot_dynamics.json: n = 10 disks per segment, a tension
// step held for 2 s, output every 1/60 s), and its accuracy: the largest tip distance over the
// output steps from a run with 100 times tighter tolerances.
//   bench_dynamics [--quick] [--models ccsub,prb] [--duration T]
// --quick: 0.1 s of motion (the ctest smoke run).
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
  double duration = 2.0;
  std::string models = "ccsub,prb";
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--quick")) duration = 0.1;
    else if (!std::strcmp(argv[i], "--models") && i + 1 < argc) models = argv[++i];
    else if (!std::strcmp(argv[i], "--duration") && i + 1 < argc) duration = std::stod(argv[++i]);
    else {
      std::fprintf(stderr, "usage: bench_dynamics [--quick] [--models ccsub,prb] [--duration T]\n");
      return 2;
    }
  }
  const std::string path = std::string(TDCR_SOURCE_DIR) + "/examples/paper_robot_dynamics.json";
  const Scene scene = load_scene(path);
  SimulationOptions options;
  options.duration = duration;
  options.dt = 1.0 / 60.0;
  std::printf("scene: %s\nduration %g s, dt %.6g s, damping time %g s, %d disks\n", path.c_str(), duration, options.dt,
              scene.dynamics->bending_damping_time, scene.robot.total_disks());
  std::printf("%-6s %10s %12s %8s %14s %10s\n", "model", "cpu_s", "real_time_x", "steps", "tip_err_m", "tip_z_end");
  int status = 0;
  for (ModelKind kind : bench::parse_models(models)) {
    const auto model = make_model(kind, scene);
    const double c0 = bench::thread_cpu_us();
    const SimulationResult r = simulate(*model, *scene.dynamics, scene.timeline, options, scene.solver);
    const double cpu = (bench::thread_cpu_us() - c0) * 1e-6;
    // The reference: tolerances 100 times tighter.
    SolverOptions tight = scene.solver;
    tight.tip_tolerance = SolverOptions::kTipToleranceOverLength * scene.robot.total_length() * 1e-2;
    tight.cvode_rtol = scene.solver.cvode_rtol * 1e-2;
    const SimulationResult ref = simulate(*model, *scene.dynamics, scene.timeline, options, tight);
    double err = 0.0;
    long steps = 0;
    for (std::size_t k = 0; k < r.steps.size() && k < ref.steps.size(); ++k) {
      err = std::max(err, (r.steps[k].tip.p - ref.steps[k].tip.p).norm());
      steps += r.steps[k].iterations;
    }
    std::printf("%-6s %10.4f %12.1f %8ld %14.3e %10.6f%s\n", to_string(kind).c_str(), cpu, duration / cpu, steps, err,
                r.steps.back().tip.p.z(), r.completed && ref.completed ? "" : "  (stopped early)");
    if (!r.completed) {
      std::printf("  %s\n", r.message.c_str());
      status = 1;
    }
  }
  return status;
}
