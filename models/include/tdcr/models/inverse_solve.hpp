/// @file inverse_solve.hpp
/// @brief Inverse solve: non-negative tendon tensions that put the tip at a target position (and
/// orientation), the tensions of least norm among those that do.
///
/// Phase 1 reaches the target by a bounded Levenberg-Marquardt iteration over the tensions (every
/// step a non-negative least-squares problem on the tip Jacobian, by central differences of
/// tight, warm-started forward solves), started again from other tensions where it ends at a
/// local minimum of the distance. Phase 2 minimises |T| on the target set by Newton steps in its
/// tangent space (the reduced Hessian of the Lagrangian by second differences), brought back onto
/// the target after every step, with the non-negative tensions as an active set. `minimum_norm`
/// is claimed only where the first- and second-order conditions of a local minimum hold
/// (docs/user-guide.md, "Inverse solve"):
///
/// @code
/// auto model = tdcr::make_model(tdcr::ModelKind::VC, scene);
/// auto ws = model->make_workspace();
/// tdcr::ModelInput start = scene.input();
/// start.actuation.values.assign(start.actuation.values.size(), 0.0);
/// tdcr::InverseTarget target;
/// target.position = tdcr::Vec3(0.0, 0.02, 0.095);
/// const tdcr::InverseResult r = tdcr::inverse_solve(*model, *ws, start, target, scene.solver);
/// if (r.converged()) use(r.tensions);
/// @endcode
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "tdcr/core/solution.hpp"
#include "tdcr/models/static_model.hpp"

namespace tdcr {

/// @brief Where the tip should be: a position and optionally an orientation, base frame.
struct InverseTarget {
  Vec3 position = Vec3::Zero();  ///< Tip position (m), base frame.
  /// Tip orientation as a rotation vector (rad, base frame: R = exp([rotation])); none: the
  /// orientation is free and only the position is sought.
  std::optional<Vec3> rotation;
  /// Weight of rotation errors against position errors in the least-squares steps (m per rad);
  /// 0 (default) is the robot's length. It matters only where both cannot be met together.
  double rotation_weight = 0.0;

  /// @brief Throws InputError naming the field (`target.position[i]`, `target.rotation[i]`,
  /// `target.rotation_weight`) and the value: a non-finite component, a negative or non-finite
  /// weight.
  void validate() const;

  /// @brief The rotation vector of a target orientation given as a rotation matrix (base frame).
  /// Throws InputError (field `target.rotation`, the matrix as its value) unless R is finite,
  /// orthonormal (|R^T R - I| <= kRotationMatrixTolerance, Frobenius) and det R = +1: a scaled
  /// matrix, a reflection or a matrix of ones is not read as some rotation.
  static Vec3 rotation_from_matrix(const Mat3& R);
  /// Largest |R^T R - I| (Frobenius) accepted by rotation_from_matrix.
  static constexpr double kRotationMatrixTolerance = 1e-9;
};

/// @brief Settings of the inverse iteration.
struct InverseOptions {
  /// Linearised steps tried in all (each one forward solve; the forward solves that difference
  /// the Jacobian are counted in InverseResult::forward_solves, not here).
  int max_iterations = 500;
  double position_tolerance = 1e-9; ///< The target is reached when the tip is this close (m).
  double rotation_tolerance = 1e-8; ///< ... and its orientation this close (rad), if given.
  /// The minimum-norm iteration ends once its Newton step, computed on a Jacobian by central
  /// differences, changes no tension by more than this (N): the answer is this close to a local
  /// minimum of |T| on the target. (Or, where no step lowers |T| measurably, once it is below the
  /// tensions' resolution on the target, InverseResult::tension_resolution.)
  double tension_tolerance = 1e-6;

  /// @brief Throws InputError (field `inverse.<name>`) on an iteration count below 1 or a
  /// tolerance that is not a positive finite number.
  void validate() const;
};

/// @brief Why an inverse solve ended.
enum class InverseStatus {
  Converged,      ///< Target reached within the tolerances (see InverseResult::minimum_norm).
  Unreachable,    ///< No step with T >= 0 gets closer: the answer is the closest pose found.
  MaxIterations,  ///< Iteration limit before the target was reached.
  ForwardFailed   ///< The forward solve at the start tensions (or the final one, cold, at the answer) failed.
};

/// @brief Text name ("converged", "unreachable", "max_iterations", "forward_failed").
std::string to_string(InverseStatus s);

/// @brief The answer of an inverse solve. A failure still carries the closest pose found.
struct InverseResult {
  InverseStatus status = InverseStatus::ForwardFailed;  ///< Why it ended.
  std::string message;          ///< One sentence of detail.
  /// The forward solve at `tensions` (converged: from the straight robot along the loading path,
  /// `solver` with its function tolerance capped at 1e-12, differential kinematics and stability
  /// as `solver` asks); empty disk_frames only if even the start failed.
  Solution solution;
  std::vector<double> tensions;  ///< The answer (N), global tendon order, all >= 0.
  double position_error = 0.0;   ///< |tip position - target position| (m).
  /// Angle between the tip and target orientations (rad); 0 without a rotation target.
  double rotation_error = 0.0;
  int iterations = 0;      ///< Linearised steps tried (see InverseOptions::max_iterations).
  int accepted_steps = 0;  ///< Steps that were kept.
  int forward_solves = 0;  ///< All forward solves, those that difference the Jacobian included.
  /// Converged only: true if `tensions` are verified to be a local minimum of |T| among the
  /// non-negative tensions that reach the target: on a tip Jacobian by central differences of
  /// forward solves, the Newton step of the minimum-norm problem moves no tension by more than
  /// InverseOptions::tension_tolerance (first order, KKT: T = J^T lambda on the pulling tendons,
  /// J^T lambda at most that on the slack ones), and the reduced Hessian of the Lagrangian in the
  /// tangent space of the target is positive definite (second order); or, where no step lowers
  /// |T| measurably, the step is below tension_resolution (`message` then says so). False if that
  /// was not verified (`message` says why). A local minimum: another may have a smaller norm.
  bool minimum_norm = false;
  /// Converged only: the largest tension change (N) of the last Newton step of the minimum-norm
  /// problem, on the verifying Jacobian (0 where no tension can move on the target); with a
  /// positive definite reduced Hessian, about the distance to the local minimum.
  double optimality = 0.0;
  /// Converged only: the tensions' resolution on the target (N), position_tolerance (or the
  /// weighted rotation tolerance) over the smallest singular value of the Jacobian on the pulling
  /// tendons: tensions this far apart in the least controllable direction both meet the target.
  double tension_resolution = 0.0;

  /// @brief True only for InverseStatus::Converged: the tolerances were met.
  bool converged() const { return status == InverseStatus::Converged; }
  /// @brief One line: "converged: |dp| = 3.2e-12 m, 9 iterations, |T| = 2.41 N".
  std::string brief_report() const;
};

/// @brief Non-negative tensions that put the tip of `model` at `target`.
///
/// Starts from the tensions of `start` (its loads stay as they are). The forward solves use
/// `solver` with a function tolerance of at most 1e-12 (1e-14 for the Jacobian's differences and
/// phase 2), warm-started and reusing the workspace's Newton Jacobian, without secant prediction,
/// differential kinematics or stability analysis; a step that loads a part of the robot that no
/// tendon loads at its warm start is solved cold. Phase 1 reaches the target (bounded
/// Levenberg-Marquardt with a gain-ratio test; other starts where it ends at a local minimum of
/// the distance or stalls); phase 2 lowers |T| on the target (Newton steps in its tangent space,
/// active set on T >= 0) to a local minimum, verified as described at
/// InverseResult::minimum_norm (antagonistic pulls that only compress the backbone are released).
/// Without target.rotation only the position is sought. The answer is then solved again cold,
/// from the straight robot (the loading path tdcr::solve takes): `solution` is that solve, and a
/// result is Converged only if its tip meets the tolerances (a target met only on another
/// equilibrium branch restarts phase 1 from the cold answer, at most twice). An unreachable
/// target ends with the closest pose found, status Unreachable (no step with T >= 0 gets closer
/// from any start: a local minimum of the distance) or MaxIterations, and its distance in
/// position_error.
///
/// Throws InputError on an invalid target or options, displacement input in `start` (the
/// iteration varies tensions), or whatever tdcr::solve throws for `start`.
InverseResult inverse_solve(const StaticModel& model, ModelWorkspace& workspace, const ModelInput& start,
                            const InverseTarget& target, const SolverOptions& solver = SolverOptions(),
                            const InverseOptions& options = InverseOptions());

}  // namespace tdcr
