/// @file legacy_model.hpp
/// @brief Transitional: the scene-bound model interface of tdcr 0.1, kept while the models move
/// to the StaticModel interface of static_model.hpp (a model built from a robot and its effects,
/// the input per call). Not part of the installed API once every model has moved.
#pragma once

#include <memory>

#include "tdcr/core/scene.hpp"
#include "tdcr/core/solution.hpp"
#include "tdcr/models/static_model.hpp"

namespace tdcr {

/// @brief Mutable memory of a scene-bound model's solves.
class LegacyWorkspace {
 public:
  virtual ~LegacyWorkspace() = default;
};

/// @brief A model bound to one whole scene (robot, actuation, loads, effects, options).
class LegacyStaticModel {
 public:
  virtual ~LegacyStaticModel() = default;
  /// @brief Which model this is.
  virtual ModelKind kind() const = 0;
  /// @brief The scene this model was built from (validated).
  virtual const Scene& scene() const = 0;
  /// @brief A fresh workspace for this model.
  virtual std::unique_ptr<LegacyWorkspace> make_workspace() const = 0;
  /// @brief Solve the scene; `warm_start` is a previous Solution of the same model and robot.
  virtual Solution solve(LegacyWorkspace& workspace, const Solution* warm_start = nullptr) const = 0;
};

}  // namespace tdcr
