// Private to models/solve: which answers get their stability tested (SolverOptions::stability),
// the rule of the solve driver and of the solves it delegates to (rk4_refinement.cpp).
#pragma once

#include "tdcr/core/scene.hpp"
#include "tdcr/core/solution.hpp"

namespace tdcr::detail {

// External loads: a tip force or moment, or gravity.
inline bool externally_loaded(const Loads& loads) {
  return !loads.tip_force.isZero(0.0) || !loads.tip_moment.isZero(0.0) || !loads.gravity.isZero(0.0);
}

// Whether an answer reached by a loading path or not (`by_path`) is tested: the automatic rule
// tests the answers of loading paths (from rest, snaps, a warm start's input path) and, where
// the model's test is cheap (`loads_count`: ModelProblem::automatic_stability_under_loads, for a
// cold solve), of loaded scenes; not plain unloaded direct solves nor warm steps.
inline bool wants_stability(StabilityCheck check, const ModelInput& input, bool by_path, bool loads_count) {
  switch (check) {
    case StabilityCheck::Always: return true;
    case StabilityCheck::Never: return false;
    default: return by_path || (loads_count && externally_loaded(input.loads));
  }
}

// Whether a Solution's answer was reached along a path: continuation steps (the loading path
// from rest, a warm start's input path) or path events (folds, snaps).
inline bool reached_by_path(const Solution& sol) {
  return sol.summary.continuation_steps > 0 || !sol.path_events.empty();
}

// The rule resolved for a solve whose answer another solve's path reached (`by_path`): Always or
// Never, so that the solve from that answer (a direct warm solve) keeps the verdict's rule.
inline StabilityCheck resolved_stability(StabilityCheck check, const ModelInput& input, bool by_path,
                                         bool loads_count) {
  return wants_stability(check, input, by_path, loads_count) ? StabilityCheck::Always : StabilityCheck::Never;
}

}  // namespace tdcr::detail
