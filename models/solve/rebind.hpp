// Private to models/: how the solve policy binds a model's workspace to another input.
#pragma once

#include <functional>

#include "tdcr/core/scene.hpp"
#include "tdcr/models/model_problem.hpp"

namespace tdcr::detail {

/// Binds the model's workspace to an input (StaticModel::bind) and returns its problem (the same
/// ModelProblem of the workspace). The input must stay alive while the problem is used (a problem
/// may keep a pointer to it).
using Rebind = std::function<ModelProblem&(const ModelInput&)>;

}  // namespace tdcr::detail
