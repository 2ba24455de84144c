// A complete small research program using tdcr through find_package(tdcr):
// solve a trajectory of the paper's robot (tendon 1 pulled from 0 to T_M in 20 steps, with a
// small transverse tip force) with the VC model: one model and one workspace for the whole
// trajectory, each step warm-started from the previous one; then compare the final pose with the
// reference model VCref.
//
// Build:  cmake -S examples/research_program -B build-research -DCMAKE_PREFIX_PATH=<tdcr prefix>
//         cmake --build build-research && ./build-research/research_program
#include <cmath>
#include <cstdio>

#include <tdcr/core/metrics.hpp>
#include <tdcr/core/paper_robot.hpp>
#include <tdcr/models/static_model.hpp>

int main() {
  tdcr::Scene scene = tdcr::paper::scene(/*disks_per_segment=*/10, /*configuration=*/1, "vc");
  scene.loads.tip_force = tdcr::Vec3(0.05, 0.0, 0.0);  // N, base frame
  const double t_max = tdcr::paper::max_tension(scene.robot);

  // The model describes the robot and its effects (immutable, validated); the workspace is its
  // reusable memory; the input (tensions, loads) changes along the trajectory.
  const auto model = tdcr::make_model(tdcr::ModelKind::VC, scene.robot, scene.effects);
  const auto workspace = model->make_workspace();
  tdcr::ModelInput input = scene.input();
  const int steps = 20;
  tdcr::Solution previous;
  int iterations = 0;
  for (int i = 1; i <= steps; ++i) {
    input.actuation.values[0] = t_max * i / steps;  // N, tendon 1
    tdcr::Solution sol = tdcr::solve(*model, *workspace, input, scene.solver, i > 1 ? &previous : nullptr);
    if (!sol.converged()) {
      std::fprintf(stderr, "step %d failed: %s\n", i, sol.summary.brief_report().c_str());
      return 1;
    }
    iterations += sol.summary.iterations;
    previous = std::move(sol);
  }
  const tdcr::Vec3 p = previous.tip().p;
  std::printf("research_program: trajectory of %d steps, %d Newton iterations in total\n", steps, iterations);
  std::printf("research_program: final tip = (%.3f, %.3f, %.3f) mm\n", p.x() * 1e3, p.y() * 1e3, p.z() * 1e3);

  // The reference model for the final configuration.
  const auto ref_model = tdcr::make_model(tdcr::ModelKind::VCref, scene.robot, scene.effects);
  const auto ref_ws = ref_model->make_workspace();
  const tdcr::Solution ref = tdcr::solve(*ref_model, *ref_ws, input, scene.solver);
  if (!ref.converged()) {
    std::fprintf(stderr, "VCref failed: %s\n", ref.summary.brief_report().c_str());
    return 1;
  }
  const tdcr::TipError e = tdcr::tip_error(previous.tip(), ref.tip());
  std::printf("research_program: VC vs VCref tip error = %.3f %% of length, %.3f deg\n",
              100.0 * e.position / scene.robot.total_length(), e.angle * 180.0 / M_PI);
  return 0;
}
