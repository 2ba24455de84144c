#include "tdcr/core/solver_options.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "tdcr/core/error.hpp"

namespace tdcr {

namespace {

// Every integrator, in the order of IntegratorKind; to_string() names them.
constexpr IntegratorKind kIntegrators[] = {IntegratorKind::AccuracyDrivenRK4, IntegratorKind::FixedStepRK4,
                                           IntegratorKind::Cvode};

/// "from 1e-15 to 0.01"
std::string range_text(double lo, double hi) { return "from " + format_value(lo) + " to " + format_value(hi); }

// Called on every solve: valid options build no string (`what` is only read to throw).

/// A number in [lo, hi]; InputError naming `solver.<name>`, the value and the range otherwise.
void check_range(const char* name, double v, double lo, double hi, const char* what) {
  if (!(v >= lo && v <= hi))  // false for NaN too
    throw InputError(std::string("solver.") + name, format_value(v), "must be " + range_text(lo, hi) + " (" + what + ")");
}

void check_count(const char* name, int v, int lo, int hi, const char* what) {
  if (v < lo || v > hi)
    throw InputError(std::string("solver.") + name, std::to_string(v),
                     "must be from " + std::to_string(lo) + " to " + std::to_string(hi) + " (" + what + ")");
}

}  // namespace

std::string fixed_mesh_only(IntegratorKind integrator) {
  return "sets the fixed RK4 mesh, used only with solver.integrator \"rk4_fixed\" (the integrator is \"" +
         to_string(integrator) + "\"; the default \"rk4\" refines its mesh until solver.tip_tolerance holds)";
}

void SolverOptions::validate() const {
  if (function_tolerance != 0.0)
    check_range("function_tolerance", function_tolerance, kMinFunctionTolerance, kMaxFunctionTolerance,
                "Newton's scaled residual tolerance; 0: tied to tip_tolerance");
  if (tip_tolerance != 0.0 && !(tip_tolerance >= kMinTipTolerance && tip_tolerance <= kMaxTipTolerance))
    check_range("tip_tolerance", tip_tolerance, kMinTipTolerance, kMaxTipTolerance,
                ("accuracy of the tip position in m; 0: " + format_value(kTipToleranceOverLength) +
                 " times the robot's length")
                    .c_str());
  check_range("step_tolerance", step_tolerance, kMinStepTolerance, kMaxStepTolerance, "Newton's scaled step tolerance");
  check_range("cvode_rtol", cvode_rtol, kMinCvodeRtol, kMaxCvodeRtol, "CVODE's relative tolerance");
  check_range("cvode_atol", cvode_atol, kMinCvodeAtol, kMaxCvodeAtol, "CVODE's absolute tolerance");
  check_count("max_iterations", max_iterations, 1, kMaxIterations, "Newton iterations per solve");
  check_count("max_continuation_steps", max_continuation_steps, 1, kMaxContinuationSteps,
              "Newton solves of a loading path");
  check_count("rk4_steps", rk4_steps, 1, kMaxRk4Steps, "RK4 steps per disk interval of the fixed mesh");
  // +infinity is allowed (C++ only; JSON has no infinity): exactly rk4_steps steps per interval.
  if (!(rk4_max_step >= kMinRk4MaxStep))
    throw InputError("solver.rk4_max_step", format_value(rk4_max_step),
                     "must be at least " + format_value(kMinRk4MaxStep) + " m (longest RK4 step of the fixed mesh)");
  // The fixed mesh's settings with another integrator would be ignored without a word.
  const SolverOptions defaults;
  if (integrator == IntegratorKind::AccuracyDrivenRK4) {
    if (rk4_steps != defaults.rk4_steps)
      throw InputError("solver.rk4_steps", std::to_string(rk4_steps), fixed_mesh_only(integrator));
    if (rk4_max_step != defaults.rk4_max_step)
      throw InputError("solver.rk4_max_step", format_value(rk4_max_step), fixed_mesh_only(integrator));
  }
}

SolverOptions SolverOptions::resolved(double robot_length) const {
  SolverOptions o = *this;
  if (o.tip_tolerance == 0.0)
    o.tip_tolerance = std::clamp(kTipToleranceOverLength * robot_length, kMinTipTolerance, kMaxTipTolerance);
  if (o.function_tolerance == 0.0)
    o.function_tolerance = std::clamp(kNewtonPerTipTolerance * o.tip_tolerance / robot_length,
                                      kMinTiedFunctionTolerance, kMaxFunctionTolerance);
  return o;
}

std::string to_string(IntegratorKind k) {
  switch (k) {
    case IntegratorKind::Cvode: return "cvode";
    case IntegratorKind::FixedStepRK4: return "rk4_fixed";
    default: return "rk4";
  }
}

const std::vector<std::string>& integrator_names() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> v;
    for (IntegratorKind k : kIntegrators) v.push_back(to_string(k));
    return v;
  }();
  return names;
}

IntegratorKind parse_integrator_kind(const std::string& name, const std::string& field) {
  for (IntegratorKind k : kIntegrators)
    if (name == to_string(k)) return k;
  std::string choices;
  for (const std::string& n : integrator_names()) choices += (choices.empty() ? "\"" : ", \"") + n + "\"";
  throw InputError(field, "\"" + name + "\"", "must be one of " + choices);
}

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
