#include "tdcr/models/continuation.hpp"

#include <chrono>
#include <cstdio>
#include <optional>

namespace tdcr {

Scene scale_loads(const Scene& scene, double lambda) {
  Scene s = scene;
  for (double& v : s.actuation.values) v *= lambda;
  s.loads.tip_force *= lambda;
  s.loads.tip_moment *= lambda;
  s.loads.gravity *= lambda;
  return s;
}

Solution solve_with_continuation(const StaticModel& model, ModelWorkspace& workspace, const Solution* warm_start) {
  const auto t0 = std::chrono::steady_clock::now();
  Solution direct = model.solve(workspace, warm_start);
  const SolverOptions& opt = model.scene().solver;
  if (direct.converged() || !opt.continuation) return direct;

  SolverSummary total = direct.summary;
  std::optional<Solution> last;  // last converged step
  double lambda = 0.0, step = 0.25;
  int steps = 0;
  std::string last_failure = direct.summary.message;
  while (lambda < 1.0 && steps < opt.max_continuation_steps && step >= 1.0 / 4096) {
    const double next = std::min(1.0, lambda + step);
    // One model per load level; the workspace is shared (same robot, same unknowns).
    const auto scaled = make_model(model.kind(), scale_loads(model.scene(), next));
    Solution s = scaled->solve(workspace, last ? &*last : nullptr);
    ++steps;
    total.iterations += s.summary.iterations;
    total.residual_evaluations += s.summary.residual_evaluations;
    total.jacobian_evaluations += s.summary.jacobian_evaluations;
    if (s.converged()) {
      lambda = next;
      last = std::move(s);
      step *= 2.0;
    } else {
      last_failure = s.summary.message;
      step *= 0.5;
    }
  }

  Solution out;
  if (lambda >= 1.0 && last) {
    out = std::move(*last);
    out.summary.message = "converged by load continuation";
  } else {
    out = last ? std::move(*last) : std::move(direct);
    char buf[160];
    std::snprintf(buf, sizeof buf, "load continuation stopped at %.1f %% of the load after %d steps; last failure: ",
                  100.0 * lambda, steps);
    out.summary.termination = last ? TerminationType::NoConvergence : direct.summary.termination;
    out.summary.message = buf + last_failure;
  }
  out.summary.iterations = total.iterations;
  out.summary.residual_evaluations = total.residual_evaluations;
  out.summary.jacobian_evaluations = total.jacobian_evaluations;
  out.summary.continuation_steps = steps;
  out.summary.solve_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace tdcr
