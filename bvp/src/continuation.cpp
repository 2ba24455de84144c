#include "tdcr/bvp/continuation.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "tdcr/core/error.hpp"

namespace tdcr::bvp {

void ContinuationOptions::validate() const {
  auto fail = [](const char* name, double v, const char* why) {
    throw InputError(std::string("continuation.") + name, format_value(v), why);
  };
  if (!std::isfinite(start)) fail("start", start, "must be finite");
  if (!std::isfinite(target) || target == start) fail("target", target, "must be finite and differ from start");
  if (!(initial_step > 0.0 && initial_step <= 1.0)) fail("initial_step", initial_step, "must be in (0, 1]");
  if (!(min_step > 0.0 && min_step <= 1.0)) fail("min_step", min_step, "must be in (0, 1]");
  if (!(max_step > 0.0 && max_step <= 1.0)) fail("max_step", max_step, "must be in (0, 1]");
  if (!(growth >= 1.0 && std::isfinite(growth))) fail("growth", growth, "must be >= 1 and finite");
  if (!(shrink > 0.0 && shrink < 1.0)) fail("shrink", shrink, "must be in (0, 1)");
  if (max_steps < 1) fail("max_steps", max_steps, "must be at least 1");
}

std::string to_string(ContinuationStatus s) {
  switch (s) {
    case ContinuationStatus::Reached: return "reached";
    case ContinuationStatus::Stalled: return "stalled";
    case ContinuationStatus::StepLimit: return "step_limit";
  }
  return "unknown";
}

ContinuationResult continuation(NewtonSolver& newton, ParameterizedSystem& system, Eigen::VectorXd& x,
                                const NewtonOptions& newton_options, const ContinuationOptions& options) {
  options.validate();
  const double span = options.target - options.start;
  const double dir = span > 0.0 ? 1.0 : -1.0;
  const double total = std::abs(span);
  ContinuationResult res;
  res.parameter = options.start;
  Eigen::VectorXd x_ok = x;  // solution at res.parameter
  double step = options.initial_step * total;
  const double min_step = options.min_step * total;
  const double max_step = options.max_step * total;
  bool stalled = false;
  while (res.parameter != options.target) {
    if (res.steps >= options.max_steps) break;
    const double remaining = std::abs(options.target - res.parameter);
    // Take the rest in one go if it is not much longer than the step (no sliver steps).
    const double next = (step >= 0.999 * remaining) ? options.target : res.parameter + dir * step;
    res.last_step = std::abs(next - res.parameter);
    system.set_parameter(next);
    x = x_ok;
    res.last = newton.solve(system, x, newton_options);
    ++res.steps;
    res.iterations += res.last.iterations;
    res.residual_evaluations += res.last.residual_evaluations;
    res.jacobian_evaluations += res.last.jacobian_evaluations;
    if (res.last.converged() && x.allFinite()) {
      ++res.accepted_steps;
      res.parameter = next;
      system.accept_step(x);
      x_ok = x;
      step = std::min(max_step, step * options.growth);
    } else {
      step *= options.shrink;
      if (step < min_step) {
        stalled = true;
        break;
      }
    }
  }
  x = x_ok;
  system.set_parameter(res.parameter);
  res.fraction = std::clamp((res.parameter - options.start) / span, 0.0, 1.0);
  char buf[200];
  if (res.parameter == options.target) {
    res.status = ContinuationStatus::Reached;
    std::snprintf(buf, sizeof buf, "reached parameter %.6g in %d Newton solves (%d converged)", res.parameter,
                  res.steps, res.accepted_steps);
    res.message = buf;
  } else {
    res.status = stalled ? ContinuationStatus::Stalled : ContinuationStatus::StepLimit;
    std::snprintf(buf, sizeof buf, "%s at parameter %.6g (%.1f %% of the way) after %d Newton solves (%d converged)",
                  stalled ? "stalled (step below minimum)" : "Newton solve limit reached", res.parameter,
                  100.0 * res.fraction, res.steps, res.accepted_steps);
    res.message = buf;
    res.message += "; last solve: " + res.last.message;
  }
  return res;
}

}  // namespace tdcr::bvp
