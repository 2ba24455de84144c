// Private to models/solve: the secant predictor of warm starts
// (SolverOptions::extrapolate_warm_starts; docs/models.md, "Trajectories: secant predictor and
// Jacobian reuse"), which the solve driver applies with the workspace's SolveHistory.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "tdcr/core/scene.hpp"
#include "tdcr/models/static_model.hpp"

namespace tdcr::detail {

// An input as one vector: actuation values, tip force, tip moment, gravity.
void input_vector(const std::vector<double>& values, const Loads& loads, Eigen::VectorXd& u);

// The model's warm guess x plus the last solve's Newton correction, scaled by how far the input u
// moves on along the last step's line; true if x was changed (the rule: secant_predictor.cpp).
bool extrapolate(const SolveHistory& h, const Eigen::VectorXd& from, const Eigen::VectorXd& u, Eigen::VectorXd& x);

}  // namespace tdcr::detail
