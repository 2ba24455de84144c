#include "tdcr/core/solution.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "tdcr/core/error.hpp"

namespace tdcr {

std::string format_value(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  // Prefer the shortest representation that round-trips.
  for (int p = 1; p <= 17; ++p) {
    char b2[32];
    std::snprintf(b2, sizeof b2, "%.*g", p, v);
    if (std::strtod(b2, nullptr) == v) return b2;
  }
  return buf;
}

std::string to_string(TerminationType t) {
  switch (t) {
    case TerminationType::Converged: return "converged";
    case TerminationType::NoConvergence: return "no_convergence";
    case TerminationType::MaxIterations: return "max_iterations";
    case TerminationType::LineSearchFailed: return "line_search_failed";
    case TerminationType::LinearSolverFailed: return "linear_solver_failed";
    case TerminationType::IntegrationFailed: return "integration_failed";
    case TerminationType::NonFiniteResidual: return "non_finite_residual";
    case TerminationType::Infeasible: return "infeasible";
    case TerminationType::NotSolved: return "not_solved";
  }
  return "unknown";
}

std::string SolverSummary::brief_report() const {
  char buf[256];
  std::snprintf(buf, sizeof buf, "%s: %d iterations, |F| = %.3g, %.4g ms (%s, %s)%s%s",
                to_string(termination).c_str(), iterations, residual_norm, solve_time_s * 1e3,
                linear_solver.empty() ? "none" : linear_solver.c_str(),
                integrator.empty() ? "none" : integrator.c_str(),
                continuation_steps > 0 ? ", continuation steps " : "",
                continuation_steps > 0 ? std::to_string(continuation_steps).c_str() : "");
  std::string s = buf;
  if (!converged() && !message.empty()) s += " -- " + message;
  return s;
}

std::string to_string(StabilityStatus s) {
  switch (s) {
    case StabilityStatus::Stable: return "stable";
    case StabilityStatus::Unstable: return "unstable";
    case StabilityStatus::Undetermined: return "undetermined";
  }
  return "undetermined";
}

std::string to_string(PathEvent::Type t) {
  switch (t) {
    case PathEvent::Type::Fold: return "fold";
    case PathEvent::Type::Bifurcation: return "bifurcation";
    case PathEvent::Type::Snap: return "snap";
  }
  return "fold";
}

}  // namespace tdcr
