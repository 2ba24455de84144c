// Contact benchmark (docs/contact.md): the cost of a contact solve against the free-space solve
// of the same scene, and a warm-started trajectory sliding along a wall, for CCsub, PRB, VC and
// VCref on the paper robot (Table 3, 10 mm disks) at n disks per segment.
//
// Scenes: "wall" (examples/robot_against_wall.json: tendons 2 and 1 N bend the robot into a
// wall at y = 25 mm, one disk rim touches), "point" (a straight robot with a 2 mN tip force on a
// point support at mid-length, the propped cantilever of tests/test_contact_lumped.cpp). Each
// cold solve is timed (median of --reps) with its obstacles and without them; the ratio is the
// cost of contact per active contact set (one set per scene here).
// Trajectory: the wall scene with a tip force along x swept 0 -> 50 mN -> 0 over --steps steps,
// every solve warm-started from the previous one; reported as solves per second.
//
// --profile: also the work of each contact solve (Newton iterations, residual evaluations,
// Jacobian evaluations, continuation steps) and the solver's message (fallbacks).
//
// --stability: also each contact solve with its stability test forced on (solver.stability
// true; without it a direct contact answer is not tested, docs/contact.md "Stability"), its
// median time, the test's share and the verdict.
//
// Usage: bench_contact [--quick] [--profile] [--stability] [--reps N] [--steps N] [--n N] [--models a,b,...]
#include <cmath>
#include <cstdio>
#include <cstring>
#include <algorithm>
#include <string>
#include <vector>

#include "bench_common.hpp"
#include "tdcr/core/paper_robot.hpp"

using namespace tdcr;

namespace {

Scene wall_scene(const std::string& model, int n) {
  Scene s = paper::scene(n, 1, model);
  s.effects = Effects{};
  for (Segment& g : s.robot.segments) g.disk_radius = 0.01;
  s.actuation.values = {2.0, 0, 1.0, 0};
  Obstacle wall;
  wall.type = Obstacle::Type::Plane;
  wall.point = Vec3(0, 0.025, 0);
  wall.normal = Vec3(0, -1, 0);
  s.environment.obstacles = {wall};
  return s;
}

Scene point_scene(const std::string& model, int n) {
  Scene s = paper::scene(n, 1, model);
  s.effects = Effects{};
  s.actuation.values = {0, 0, 0, 0};
  s.loads.tip_force = Vec3(0.002, 0, 0);
  Obstacle support;
  support.type = Obstacle::Type::Sphere;
  support.radius = 0.001;
  support.center = Vec3(s.robot.backbone.outer_radius + 0.001, 0, 0.05);
  s.environment.obstacles = {support};
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  int reps = 50, steps = 1000, n = 10;
  bool profile = false, stability = false;
  std::vector<std::string> models = {"ccsub", "prb", "vc", "vcref"};
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--quick") reps = 3, steps = 20;
    else if (a == "--profile") profile = true;
    else if (a == "--stability") stability = true;
    else if (a == "--reps" && i + 1 < argc) reps = std::atoi(argv[++i]);
    else if (a == "--steps" && i + 1 < argc) steps = std::atoi(argv[++i]);
    else if (a == "--n" && i + 1 < argc) n = std::atoi(argv[++i]);
    else if (a == "--models" && i + 1 < argc) {
      models.clear();
      std::string list = argv[++i];
      for (std::size_t at = 0; at <= list.size();) {
        const std::size_t comma = std::min(list.find(',', at), list.size());
        models.push_back(list.substr(at, comma - at));
        at = comma + 1;
      }
    } else {
      std::fprintf(stderr, "usage: bench_contact [--quick] [--profile] [--stability] [--reps N] [--steps N] [--n N] "
                           "[--models a,b,...]\n");
      return 2;
    }
  }
  bool ok = true;
  std::printf("%s\n# n = %d disks per segment, median of %d cold solves\n", bench::machine_stamp().c_str(), n, reps);
  std::printf("%-6s %-6s %9s %12s %12s %8s %9s %10s\n", "model", "scene", "contacts", "free_us", "contact_us", "ratio",
              "free_it", "contact_it");
  for (const std::string& model : models) {
    for (const std::string name : {"wall", "point"}) {
      Scene s = name == "wall" ? wall_scene(model, n) : point_scene(model, n);
      const auto m = make_model(parse_model_kind(model), s);
      Scene free = s;
      free.environment.obstacles.clear();
      const bench::Timing tf = bench::time_solves(*m, free, reps);
      const bench::Timing tc = bench::time_solves(*m, s, reps);
      ok = ok && tf.last.converged() && tc.last.converged() && !tc.last.contacts.empty();
      std::printf("%-6s %-6s %9zu %12.1f %12.1f %8.2f %9d %10d\n", model.c_str(), name.c_str(), tc.last.contacts.size(),
                  tf.median_us, tc.median_us, tc.median_us / tf.median_us, tf.last.summary.iterations,
                  tc.last.summary.iterations);
      if (stability) {
        Scene tested = s;
        tested.solver.stability = StabilityCheck::Always;
        const bench::Timing ts = bench::time_solves(*m, tested, reps);
        Scene free_tested = free;
        free_tested.solver.stability = StabilityCheck::Always;
        const bench::Timing tfs = bench::time_solves(*m, free_tested, reps);
        ok = ok && ts.last.converged() && tfs.last.converged();
        std::printf("  with the stability test: %.1f us (+%.1f us, %.0f %% of the contact solve): %s, margin %.6g\n"
                    "  method: %s\n  free space with the test: %.1f us (+%.1f us): %s, margin %.6g\n",
                    ts.median_us, ts.median_us - tc.median_us, 100.0 * (ts.median_us - tc.median_us) / tc.median_us,
                    to_string(ts.last.stability.status).c_str(), ts.last.stability.margin,
                    ts.last.stability.method.c_str(), tfs.median_us, tfs.median_us - tf.median_us,
                    to_string(tfs.last.stability.status).c_str(), tfs.last.stability.margin);
      }
      if (profile) {
        const SolverSummary& w = tc.last.summary;
        std::printf("  work: %d iterations, %d residuals, %d Jacobians, %d continuation steps; free: %d residuals, "
                    "%d Jacobians\n  message: %s\n",
                    w.iterations, w.residual_evaluations, w.jacobian_evaluations, w.continuation_steps,
                    tf.last.summary.residual_evaluations, tf.last.summary.jacobian_evaluations, w.message.c_str());
      }
    }
  }
  std::printf("\n# trajectory along the wall: %d warm-started steps, tip force x 0 -> 50 mN -> 0\n", steps);
  std::printf("%-6s %10s %10s %12s %10s\n", "model", "total_ms", "rate_hz", "iterations", "contacts");
  for (const std::string& model : models) {
    Scene s = wall_scene(model, n);
    const auto m = make_model(parse_model_kind(model), s);
    auto ws = m->make_workspace();
    Solution last = solve(*m, *ws, s.input(), s.solver);
    ok = ok && last.converged();
    int iterations = 0, failed = 0, residuals = 0, jacobians = 0;
    std::size_t contacts = 0;
    const double us = bench::wall_us([&] {
      for (int k = 1; k <= steps; ++k) {
        s.loads.tip_force = Vec3(0.05 * std::sin(M_PI * k / steps), 0, 0);
        Solution next = solve(*m, *ws, s.input(), s.solver, last.converged() ? &last : nullptr);
        iterations += next.summary.iterations;
        residuals += next.summary.residual_evaluations;
        jacobians += next.summary.jacobian_evaluations;
        contacts += next.contacts.size();
        if (!next.converged()) ++failed;
        last = std::move(next);
      }
    });
    ok = ok && failed == 0;
    std::printf("%-6s %10.2f %10.0f %12.2f %10.2f%s\n", model.c_str(), us * 1e-3, steps / (us * 1e-6),
                double(iterations) / steps, double(contacts) / steps, failed ? "  (some steps failed)" : "");
    if (profile)
      std::printf("  work per step: %.2f residuals, %.2f Jacobians\n", double(residuals) / steps,
                  double(jacobians) / steps);
  }
  return ok ? 0 : 1;
}
