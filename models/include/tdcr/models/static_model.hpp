/// @file static_model.hpp
/// @brief The interface every model implements, and the dispatcher from a scene to a model.
///
/// Pinocchio-style split: a model object is an immutable description built once from a Scene
/// (validated, with the effects it must simulate decided up front); a ModelWorkspace holds the
/// mutable memory of a solve (integrator and Newton solver memory, Jacobian storage) and can be
/// reused across solves. A solve is a plain function of (model, workspace, options, warm start).
#pragma once

#include <memory>
#include <string>

#include "tdcr/core/scene.hpp"
#include "tdcr/core/solution.hpp"

namespace tdcr {

/// @brief The models of the paper (Table 2).
enum class ModelKind {
  CC,     ///< Constant curvature per segment, kinematic (Eq. 8, 14-18; 20-23).
  CCsub,  ///< Constant curvature per subsegment with twist, static (Eq. 8, 30-33, 43-47).
  PRB,    ///< 3R pseudo-rigid body per subsegment with twist (Eq. 11-12, 48-54).
  VC,     ///< Cosserat rod, fully constrained tendons (Eq. 2-3, 24-29, 34-41).
  VCref   ///< Cosserat rod per subsegment, discrete disk forces (Eq. 30-33, 38-41, 44-47, 58).
};

/// @brief Parse "cc", "ccsub", "prb", "vc", "vcref" (case-insensitive). Throws InputError with
/// field `model` otherwise.
ModelKind parse_model_kind(const std::string& name);
/// @brief Lower-case model name.
std::string to_string(ModelKind kind);

/// @brief Mutable memory of a model's solves; reuse it across solves of the same model.
class ModelWorkspace {
 public:
  virtual ~ModelWorkspace() = default;
};

/// @brief An immutable model of one scene's robot, actuation, loads and effects.
class StaticModel {
 public:
  virtual ~StaticModel() = default;
  /// @brief Which model this is.
  virtual ModelKind kind() const = 0;
  /// @brief The scene this model was built from (validated).
  virtual const Scene& scene() const = 0;
  /// @brief A fresh workspace for this model.
  virtual std::unique_ptr<ModelWorkspace> make_workspace() const = 0;
  /// @brief Solve the model. `warm_start`, if given, is a previous Solution of the same model and
  /// robot (e.g. the previous configuration of a trajectory); otherwise the model's cold-start
  /// guess is used (CCsub, PRB: the straight robot; VC: VcInitialGuess; VCref:
  /// VcrefOptions::InitialGuess; CC needs none). Never throws for a non-convergent solve: the
  /// Solution's summary says so.
  virtual Solution solve(ModelWorkspace& workspace, const Solution* warm_start = nullptr) const = 0;
};

/// @brief Build the model `kind` for `scene` (validated first; throws InputError on bad input).
std::unique_ptr<StaticModel> make_model(ModelKind kind, const Scene& scene);

/// @brief One-shot convenience: build the scene's model (scene.model: one of the five names, or
/// "auto", which chooses with solve_auto at 1 % accuracy, model_selection.hpp) with a fresh
/// workspace and solve it. Load
/// continuation, when SolverOptions::continuation is on, is part of every model's solve().
Solution solve(const Scene& scene, const Solution* warm_start = nullptr);

}  // namespace tdcr
