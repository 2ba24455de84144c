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

// The reference model: its expected error against itself is zero at every disk count.
bool is_reference(const ModelInfo& m) {
  for (double p : m.accuracy.percent_at)
    if (p != 0.0) return false;
  return true;
}

// The models that can take an input of this kind (and loads), cheapest first for the scene.
// Mixed input (`statics`) needs a model with displacement statics; tendon friction a model that
// simulates it.
std::vector<const ModelInfo*> candidates(bool displacements, bool statics, bool loaded, bool friction) {
  std::vector<const ModelInfo*> v;
  for (const ModelInfo& m : model_registry()) {
    const ModelCapabilities& c = m.capabilities;
    if ((displacements ? c.displacement_input : c.tension_input) && (!statics || c.displacement_statics) &&
        (!loaded || c.external_loads) && (!friction || c.tendon_friction) && m.cost_rank >= 0)
      v.push_back(&m);
  }
  auto rank = [loaded](const ModelInfo* m) { return loaded && m->loaded_cost_rank >= 0 ? m->loaded_cost_rank : m->cost_rank; };
  std::stable_sort(v.begin(), v.end(), [&](const ModelInfo* a, const ModelInfo* b) { return rank(a) < rank(b); });
  return v;
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
  const bool displacements = scene.actuation.kind == Actuation::Kind::Displacements;
  bool elastic = false;  // elastic tendons under displacement input need statics too
  for (const Segment& seg : scene.robot.segments)
    for (const TendonSpec& t : seg.tendons) elastic = elastic || t.stiffness.has_value();
  std::vector<const ModelInfo*> order =
      candidates(displacements, scene.actuation.mixed() || (displacements && elastic), loaded, e.tendon_friction);
  // Curved routing (helical, polynomial) needs a model that represents it (not CC's closed form).
  for (const Segment& s : scene.robot.segments)
    for (const TendonSpec& t : s.tendons)
      if (t.routing.type != TendonRoutingSpec::Type::Straight)
        order.erase(std::remove_if(order.begin(), order.end(),
                                   [](const ModelInfo* m) { return !m->capabilities.curved_routing; }),
                    order.end());
  // Obstacles need a model with contact; of those, the most accurate one the tolerance allows
  // (no accuracy table with contact yet: the free-space one is used).
  if (e.contact) {
    order.erase(std::remove_if(order.begin(), order.end(), [](const ModelInfo* m) { return !m->capabilities.contact; }),
                order.end());
    if (!order.empty() && !displacements) {
      const ModelInfo* best = order.back();
      for (const ModelInfo* info : order)
        if (expected_model_error(info->kind, n, loaded) <= tolerance) {
          best = info;
          break;
        }
      c.kind = best->kind;
      c.expected_error = expected_model_error(c.kind, n, loaded);
      c.reason = features + ", obstacles: " + to_string(c.kind) + " (the models with contact: CCsub, PRB, VC, VCref), expected within " +
                 percent(c.expected_error) + " of VCref in free space";
      return c;
    }
  }
  if (order.empty())
    throw InputError("model", "auto", "no model takes this scene");
  if (displacements) {
    // The cheapest model that takes displacements (there is no accuracy table for them).
    c.kind = order.front()->kind;
    c.expected_error = expected_model_error(c.kind, n, false);
    c.reason = "tendon displacements: " + to_string(c.kind) + " is the " +
               (order.size() == 1 ? "only model that takes them" : "cheapest model that takes them") + " (" + features +
               ")";
    return c;
  }
  // Cheapest first (registry cost rank); the first model expected to meet the tolerance wins,
  // the reference model (zero expected error) at the latest.
  for (const ModelInfo* info : order) {
    const ModelKind k = info->kind;
    const double err = expected_model_error(k, n, loaded);
    if (!(err <= tolerance)) continue;
    c.kind = k;
    c.expected_error = err;
    if (!is_reference(*info)) {
      c.reason = features + ": " + to_string(k) + " is the cheapest model expected within " + percent(err) +
                 " of VCref, below the requested " + percent(tolerance);
      return c;
    }
    const ModelInfo& cheapest = *order.front();
    c.reason = features + ": no cheaper model is expected within the requested " + percent(tolerance) + " (" +
               to_string(cheapest.kind) + " " + percent(expected_model_error(cheapest.kind, n, loaded)) +
               "), so the reference model " + to_string(k);
    return c;
  }
  throw InputError("accuracy", format_value(tolerance), "no model is expected to meet it");
}

}  // namespace tdcr
