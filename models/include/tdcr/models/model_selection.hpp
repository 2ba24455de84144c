/// @file model_selection.hpp
/// @brief `--model auto`: choose the cheapest model expected to meet a requested accuracy.
///
/// The choice uses the scene's features (tension or displacement input, external loads, disk
/// count) and the accuracy-time table measured by the benchmarks (bench_case_study, see
/// docs/benchmarks.md): the mean tip error of each model against the reference model VCref as a
/// function of the disks per segment n, without and with external loads. In order of cost:
/// CC (closed form, microseconds), VC (single shooting), VCref (the reference). PRB is more
/// accurate than VC at small n without loads, but slower than VCref with loads.
#pragma once

#include <memory>
#include <string>

#include "tdcr/models/static_model.hpp"

namespace tdcr {

/// @brief The model chosen for a scene and why.
struct ModelChoice {
  ModelKind kind = ModelKind::VCref;  ///< The chosen model.
  double expected_error = 0.0;        ///< Expected tip position error, fraction of the length.
  std::string reason;                 ///< One sentence: the scene features and the numbers used.
};

/// @brief Expected mean tip position error against VCref (fraction of the robot length) of
/// `kind` for a robot with `disks` disks per segment (the smallest count over the segments),
/// measured on the paper's case study; `loaded` selects the table with tip forces.
/// VCref itself returns 0.
double expected_model_error(ModelKind kind, int disks, bool loaded);

/// @brief Choose the cheapest model expected to meet `tolerance` (tip position error as a
/// fraction of the robot length, default 1 %). Throws InputError when no model can take the scene
/// (tendon displacements together with external loads).
ModelChoice choose_model(const Scene& scene, double tolerance = 0.01);

/// @brief A scene's model, built once: the scene's front door (the CLI's solve and inverse, Python's
/// solve_scene and tdcr::solve(scene) go through it).
struct SceneModel {
  std::unique_ptr<StaticModel> model;  ///< The model, built from the scene's robot and effects.
  /// The model chosen: its kind always; for "auto" also the expected error and the reason.
  ModelChoice choice;
  bool automatic = false;  ///< The scene asked for "auto" (in any case).
  /// "auto: <reason>" for an automatic choice, else empty (Solution::model_selection).
  std::string selection() const { return automatic ? "auto: " + choice.reason : std::string(); }
};

/// @brief The front door: validates the scene (Scene::validate; the model name, a registry name
/// or "auto" in any case; StaticModel::check_input of the scene's input), chooses the model for
/// "auto" at `tolerance` (choose_model) and builds it. Throws InputError naming the field and
/// value.
SceneModel make_scene_model(const Scene& scene, double tolerance = 0.01);

/// @brief Solve a scene through the front door with a fresh workspace: the scene's model (for
/// "auto" the one chosen at `tolerance`; a warm start of another model is then ignored), its input
/// and solver options; Solution::model_selection records an automatic choice and its reason.
Solution solve_scene(const Scene& scene, double tolerance = 0.01, const Solution* warm_start = nullptr);

/// @brief Choose a model (choose_model), build it and solve; the Solution's model_selection
/// records the choice and its reason.
Solution solve_auto(const Scene& scene, double tolerance = 0.01, const Solution* warm_start = nullptr);

}  // namespace tdcr
