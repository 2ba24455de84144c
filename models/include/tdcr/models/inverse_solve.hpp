/// @file inverse_solve.hpp
/// @brief Inverse solve: non-negative tendon tensions that put the tip at a target position (and
/// orientation), the minimum-norm tensions among those that do.
///
/// A damped Gauss-Newton (Levenberg-Marquardt) iteration over the tensions. Every step is a
/// non-negative least-squares problem on the model's tip Jacobian (Solution::tip_jacobian, from
/// SolverOptions::differential_kinematics) followed by a forward solve warm-started from the last
/// accepted one; once the target is reached, further steps lower |T| while keeping it reached
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
};

/// @brief Settings of the inverse iteration.
struct InverseOptions {
  int max_iterations = 100;         ///< Linearised steps tried (each one forward solve).
  double position_tolerance = 1e-9; ///< The target is reached when the tip is this close (m).
  double rotation_tolerance = 1e-8; ///< ... and its orientation this close (rad), if given.
  /// The minimum-norm iteration stops once a step changes no tension by more than this (N).
  double tension_tolerance = 1e-9;

  /// @brief Throws InputError (field `inverse.<name>`) on an iteration count below 1 or a
  /// tolerance that is not a positive finite number.
  void validate() const;
};

/// @brief Why an inverse solve ended.
enum class InverseStatus {
  Converged,      ///< Target reached within the tolerances (see InverseResult::minimum_norm).
  Unreachable,    ///< No step with T >= 0 gets closer: the answer is the closest pose found.
  MaxIterations,  ///< Iteration limit before the target was reached.
  ForwardFailed   ///< The forward solve at the start tensions failed.
};

/// @brief Text name ("converged", "unreachable", "max_iterations", "forward_failed").
std::string to_string(InverseStatus s);

/// @brief The answer of an inverse solve. A failure still carries the closest pose found.
struct InverseResult {
  InverseStatus status = InverseStatus::ForwardFailed;  ///< Why it ended.
  std::string message;          ///< One sentence of detail.
  /// The forward solve at `tensions` (with its tip Jacobian); empty disk_frames only if even
  /// the start failed.
  Solution solution;
  std::vector<double> tensions;  ///< The answer (N), global tendon order, all >= 0.
  double position_error = 0.0;   ///< |tip position - target position| (m).
  /// Angle between the tip and target orientations (rad); 0 without a rotation target.
  double rotation_error = 0.0;
  int iterations = 0;      ///< Linearised steps tried (forward solves after the first).
  int accepted_steps = 0;  ///< Steps that were kept.
  /// Converged only: true if the minimum-norm iteration ended (no step lowers |T| on the
  /// target any more), false if the iteration limit cut it short (the target is reached, the
  /// norm may not be minimal).
  bool minimum_norm = false;

  /// @brief True only for InverseStatus::Converged: the tolerances were met.
  bool converged() const { return status == InverseStatus::Converged; }
  /// @brief One line: "converged: |dp| = 3.2e-12 m, 9 iterations, |T| = 2.41 N".
  std::string brief_report() const;
};

/// @brief Non-negative tensions that put the tip of `model` at `target`.
///
/// Starts from the tensions of `start` (its loads stay as they are) and iterates damped
/// Gauss-Newton steps with T >= 0 on the tip Jacobian of each forward solve (`solver` with
/// differential kinematics on, warm-started). Once the target is reached, steps go on that
/// lower |T| while the target stays reached, until no tension changes by more than
/// InverseOptions::tension_tolerance: among the tensions that reach the target, a local minimum
/// of |T| (antagonistic pulls that only compress the backbone are released). Without
/// target.rotation only the position is sought. An unreachable target ends with the closest
/// pose found, status Unreachable (or MaxIterations) and its distance in position_error; a
/// result is Converged only if the tolerances were met.
///
/// Throws InputError on an invalid target or options, displacement input in `start` (the
/// iteration varies tensions), or whatever tdcr::solve throws for `start`.
InverseResult inverse_solve(const StaticModel& model, ModelWorkspace& workspace, const ModelInput& start,
                            const InverseTarget& target, const SolverOptions& solver = SolverOptions(),
                            const InverseOptions& options = InverseOptions());

}  // namespace tdcr
