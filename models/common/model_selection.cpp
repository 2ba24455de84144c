#include "tdcr/models/model_selection.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "tdcr/core/error.hpp"
#include "tdcr/models/model_registry.hpp"

namespace tdcr {

namespace {

// The registry's expected error at n disks per segment: log-log interpolation between the
// measured disk counts 1, 2, 5, 10, and the tail law beyond.
double table_error(const ExpectedAccuracy& a, int n) {
  static const int kDisks[4] = {1, 2, 5, 10};
  if (n <= kDisks[0]) return a.percent_at[0];
  for (int i = 1; i < 4; ++i)
    if (n <= kDisks[i]) {
      if (a.percent_at[i - 1] <= 0.0 || a.percent_at[i] <= 0.0) return a.percent_at[i];
      const double x0 = std::log(kDisks[i - 1]), x1 = std::log(kDisks[i]);
      const double y0 = std::log(a.percent_at[i - 1]), y1 = std::log(a.percent_at[i]);
      return std::exp(y0 + (y1 - y0) * (std::log(n) - x0) / (x1 - x0));
    }
  return a.percent_at[3] * std::pow(10.0 / n, a.tail_exponent);
}

std::string percent(double fraction) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g %%", 100.0 * fraction);
  return b;
}

}  // namespace

double expected_model_error(ModelKind kind, int disks, bool loaded) {
  const ExpectedAccuracy& a = model_info(kind).accuracy;
  return table_error(a, disks) / 100.0 * (loaded ? a.loaded_factor : 1.0);
}

ModelChoice choose_model(const Scene& scene, double tolerance) {
  if (!(std::isfinite(tolerance) && tolerance > 0.0))
    throw InputError("accuracy", format_value(tolerance), "must be a positive fraction of the robot length");
  scene.validate();
  const SceneEffects e = scene.active_effects();
  const bool loaded = e.tip_wrench || e.gravity;
  int n = scene.robot.segments.front().disks;
  for (const Segment& s : scene.robot.segments) n = std::min(n, s.disks);
  const std::string features = std::string(loaded ? "external loads" : "no external load") + ", " +
                               std::to_string(n) + " disks per segment (fewest)";
  ModelChoice c;
  if (scene.actuation.kind == Actuation::Kind::Displacements) {
    if (loaded)
      throw InputError("model", "auto",
                       "no model takes tendon displacements together with external loads; give tensions");
    c.kind = ModelKind::CC;
    c.expected_error = expected_model_error(ModelKind::CC, n, false);
    c.reason = "tendon displacements: CC is the only kinematic model (" + features + ")";
    return c;
  }
  // Cheapest first (registry cost rank); the first model expected to meet the tolerance wins.
  std::vector<const ModelInfo*> order;
  for (const ModelInfo& m : model_registry()) order.push_back(&m);
  std::sort(order.begin(), order.end(), [](const ModelInfo* a, const ModelInfo* b) { return a->cost_rank < b->cost_rank; });
  for (const ModelInfo* info : order) {
    const ModelKind k = info->kind;
    if (k == ModelKind::VCref) continue;  // the reference: the fallback below
    if (k == ModelKind::PRB && loaded) continue;  // slower than VCref with loads (benchmarks)
    const double err = expected_model_error(k, n, loaded);
    if (err <= tolerance) {
      c.kind = k;
      c.expected_error = err;
      c.reason = features + ": " + to_string(k) + " is the cheapest model expected within " + percent(err) +
                 " of VCref, below the requested " + percent(tolerance);
      return c;
    }
  }
  c.kind = ModelKind::VCref;
  c.expected_error = 0.0;
  c.reason = features + ": no cheaper model is expected within the requested " + percent(tolerance) +
             " (VC " + percent(expected_model_error(ModelKind::VC, n, loaded)) + "), so the reference model VCref";
  return c;
}

Solution solve_auto(const Scene& scene, double tolerance, const Solution* warm_start) {
  const ModelChoice c = choose_model(scene, tolerance);
  const auto model = make_model(c.kind, scene);
  const auto ws = model->make_workspace();
  const Solution* warm =
      warm_start && warm_start->model_fingerprint == model->fingerprint() ? warm_start : nullptr;
  Solution sol = solve(*model, *ws, scene.input(), scene.solver, warm);
  sol.model_selection = "auto: " + c.reason;
  return sol;
}

}  // namespace tdcr
