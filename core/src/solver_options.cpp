#include "tdcr/core/solver_options.hpp"

#include <cmath>
#include <string>

#include "tdcr/core/error.hpp"

namespace tdcr {

namespace {

/// "from 1e-15 to 0.01"
std::string range_text(double lo, double hi) { return "from " + format_value(lo) + " to " + format_value(hi); }

/// A number in [lo, hi]; InputError naming `solver.<name>`, the value and the range otherwise.
void check_range(const char* name, double v, double lo, double hi, const std::string& what) {
  if (!(v >= lo && v <= hi))  // false for NaN too
    throw InputError(std::string("solver.") + name, format_value(v), "must be " + range_text(lo, hi) + " (" + what + ")");
}

void check_count(const char* name, int v, int lo, int hi, const std::string& what) {
  if (v < lo || v > hi)
    throw InputError(std::string("solver.") + name, std::to_string(v),
                     "must be from " + std::to_string(lo) + " to " + std::to_string(hi) + " (" + what + ")");
}

}  // namespace

void SolverOptions::validate() const {
  using S = SolverOptions;
  check_range("function_tolerance", function_tolerance, kMinFunctionTolerance, kMaxFunctionTolerance,
              "Newton's scaled residual tolerance");
  check_range("step_tolerance", step_tolerance, kMinStepTolerance, kMaxStepTolerance, "Newton's scaled step tolerance");
  check_range("cvode_rtol", cvode_rtol, kMinCvodeRtol, kMaxCvodeRtol, "CVODE's relative tolerance");
  check_range("cvode_atol", cvode_atol, kMinCvodeAtol, kMaxCvodeAtol, "CVODE's absolute tolerance");
  check_count("max_iterations", max_iterations, 1, kMaxIterations, "Newton iterations per solve");
  check_count("max_continuation_steps", max_continuation_steps, 1, kMaxContinuationSteps,
              "Newton solves of a loading path");
  if (!(std::isfinite(rk4_tip_tolerance) &&
        (rk4_tip_tolerance == 0.0 || (rk4_tip_tolerance >= kMinRk4TipTolerance && rk4_tip_tolerance <= kMaxRk4TipTolerance))))
    throw InputError("solver.rk4_tip_tolerance", format_value(rk4_tip_tolerance),
                     "must be 0 (off: fixed RK4 steps) or " + range_text(kMinRk4TipTolerance, kMaxRk4TipTolerance) +
                         " m (accuracy-driven RK4)");
  // An accuracy-driven solve refines the first mesh up to 2^kMaxRk4Halvings times: its finest
  // mesh must be valid too.
  const bool refined = rk4_tip_tolerance > 0.0;
  const int factor = refined ? 1 << S::kMaxRk4Halvings : 1;
  const std::string with_refinement =
      refined ? "; with rk4_tip_tolerance the finest mesh has " + std::to_string(factor) + " times the steps" : "";
  check_count("rk4_steps", rk4_steps, 1, kMaxRk4Steps / factor, "RK4 steps per disk interval" + with_refinement);
  // +infinity is allowed (C++ only; JSON has no infinity): exactly rk4_steps steps per interval.
  if (!(rk4_max_step >= kMinRk4MaxStep * factor))
    throw InputError("solver.rk4_max_step", format_value(rk4_max_step),
                     "must be at least " + format_value(kMinRk4MaxStep * factor) + " m (longest RK4 step" +
                         with_refinement + ")");
}

std::string to_string(IntegratorKind k) { return k == IntegratorKind::Cvode ? "cvode" : "rk4"; }

std::string to_string(LinearSolverKind k) {
  switch (k) {
    case LinearSolverKind::Dense: return "dense";
    case LinearSolverKind::SparseKLU: return "klu";
    default: return "auto";
  }
}

std::string to_string(StabilityCheck k) {
  switch (k) {
    case StabilityCheck::Always: return "always";
    case StabilityCheck::Never: return "never";
    default: return "auto";
  }
}

}  // namespace tdcr
