// A warm start's path from the previous answer's input to the new one (load_continuation.hpp).
#include <cstdio>
#include <string>

#include "solve/load_continuation.hpp"
#include "tdcr/models/model_problem.hpp"
#include "solve/newton_summary.hpp"

namespace tdcr::detail {

namespace {

// (1 - t) a + t b, every actuation value and load; the rest of the input is b's.
void interpolate(const ModelInput& a, const ModelInput& b, double t, ModelInput& out) {
  out.actuation.kind = b.actuation.kind;
  out.actuation.convention = b.actuation.convention;
  out.actuation.values.resize(b.actuation.values.size());
  for (std::size_t k = 0; k < b.actuation.values.size(); ++k)
    out.actuation.values[k] = (1.0 - t) * a.actuation.values[k] + t * b.actuation.values[k];
  out.loads.tip_force = (1.0 - t) * a.loads.tip_force + t * b.loads.tip_force;
  out.loads.tip_moment = (1.0 - t) * a.loads.tip_moment + t * b.loads.tip_moment;
  out.loads.gravity = (1.0 - t) * a.loads.gravity + t * b.loads.gravity;
}

}  // namespace

bool follow_input_path(const Rebind& rebind, const ModelInput& from, const ModelInput& to, const Solution& previous,
                       const bvp::NewtonOptions& newton_options, Eigen::VectorXd& x, SolverSummary& sum) {
  constexpr double kMinStep = 1.0 / 64.0;
  ModelInput mid;
  // The last equilibrium on the path, as a Solution: a problem's warm guess reads its unknowns
  // in the model's own layout (which may differ between inputs, e.g. the loaded subsegments).
  Solution last = previous;
  Eigen::VectorXd y, f;
  double t = 0.0, step = 0.25;
  int steps = 0;
  bool ok = true;
  std::string failure;
  while (t < 1.0 && ok) {
    const double next = std::min(1.0, t + step);
    interpolate(from, to, next, mid);
    ModelProblem& P = rebind(mid);
    bvp::ParameterizedSystem& sys = *P.system();
    sys.set_parameter(1.0);
    if (!P.warm_guess(last, y)) {
      ok = false;
      failure = "no warm guess from the last equilibrium";
      break;
    }
    const bvp::NewtonResult res = P.newton().solve(sys, y, newton_options);
    sum.iterations += res.iterations;
    sum.residual_evaluations += res.residual_evaluations;
    sum.jacobian_evaluations += res.jacobian_evaluations;
    ++sum.continuation_steps;
    if (!res.converged()) {
      step *= 0.5;
      ok = step >= kMinStep;
      failure = res.message;
      continue;
    }
    // The step's equilibrium becomes the next warm start (outputs of the model's own layout).
    f.resize(sys.size());
    const bool evaluated = P.final_residual(y, f);
    last.unknowns = y;
    P.extract(y, evaluated, last);
    t = next;
    ++steps;
    step *= 2.0;  // the next step is clipped at the end of the path
  }
  ModelProblem& P = rebind(to);
  P.system()->set_parameter(1.0);
  char buf[160];
  if (!ok || !P.warm_guess(last, x)) {
    std::snprintf(buf, sizeof buf, "stopped at %.1f %% of the input path after %d steps: ", 100.0 * t, steps);
    sum.message = buf + failure;
    return false;
  }
  std::snprintf(buf, sizeof buf, "warm start: followed the input path from the previous answer in %d steps", steps);
  sum.message = buf;
  return true;
}

}  // namespace tdcr::detail
