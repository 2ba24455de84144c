// The scene front door: from a Scene (model name or "auto", robot, effects, input, options) to a
// built model and its solve. The CLI's solve and inverse commands, Python's solve_scene and
// tdcr::solve(scene) all enter here, so "auto" is read, chosen and reported in one place.
#include <algorithm>
#include <cctype>

#include "tdcr/models/model_registry.hpp"
#include "tdcr/models/model_selection.hpp"

namespace tdcr {

namespace {
bool names_auto(const std::string& name) {
  std::string lower = name;
  std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
  return lower == "auto";
}
}  // namespace

SceneModel make_scene_model(const Scene& scene, double tolerance) {
  scene.validate();
  SceneModel out;
  out.automatic = names_auto(scene.model);
  if (out.automatic) {
    out.choice = choose_model(scene, tolerance);
  } else {
    out.choice.kind = parse_model_kind(scene.model);
  }
  out.model = make_model(out.choice.kind, scene);
  out.model->check_input(scene.input());
  return out;
}

void validate_scene(const Scene& scene) { make_scene_model(scene); }

Solution solve_scene(const Scene& scene, double tolerance, const Solution* warm_start) {
  const SceneModel m = make_scene_model(scene, tolerance);
  const auto workspace = m.model->make_workspace();
  // An automatic choice may differ from the warm start's model: then the warm start is not used.
  const Solution* warm = warm_start;
  if (m.automatic && warm && warm->model_fingerprint != m.model->fingerprint()) warm = nullptr;
  Solution sol = solve(*m.model, *workspace, scene.input(), scene.solver, warm);
  sol.model_selection = m.selection();
  return sol;
}

Solution solve(const Scene& scene, const Solution* warm_start) { return solve_scene(scene, 0.01, warm_start); }

Solution solve_auto(const Scene& scene, double tolerance, const Solution* warm_start) {
  Scene automatic = scene;
  automatic.model = "auto";
  return solve_scene(automatic, tolerance, warm_start);
}

}  // namespace tdcr
