/// @file solution.hpp
/// @brief The result of a solve: shape, diagnostics and a Ceres-like summary. A failed solve is
/// never reported as converged.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "tdcr/core/scene.hpp"
#include "tdcr/core/types.hpp"

namespace tdcr {

/// @brief Why a solve ended.
enum class TerminationType {
  Converged,           ///< Residual below tolerance; the answer is an equilibrium.
  NoConvergence,       ///< The nonlinear solver stopped without reaching the tolerance.
  MaxIterations,       ///< Iteration limit reached.
  LineSearchFailed,    ///< Line search could not reduce the residual.
  LinearSolverFailed,  ///< Singular or failed Jacobian factorisation.
  IntegrationFailed,   ///< The ODE integrator failed (too much work, step too small).
  NonFiniteResidual,   ///< NaN or Inf in the residual.
  /// The actuation asks for more than the tendon geometry allows (a tendon would have to cross
  /// the backbone): a physical limit, not a numerical failure; the message names the tendon.
  Infeasible,
  NotSolved            ///< No solve was attempted (default state).
};

/// @brief Text name of a termination type ("converged", "max_iterations", ...).
std::string to_string(TerminationType t);

/// @brief Diagnostics of a solve, in the spirit of ceres::Solver::Summary.
struct SolverSummary {
  TerminationType termination = TerminationType::NotSolved;  ///< Why the solve ended.
  std::string message;           ///< Human-readable reason (KINSOL's flag and text, etc.).
  int solver_flag = 0;           ///< Raw return flag of the nonlinear solver (KINSOL).
  int iterations = 0;            ///< Nonlinear iterations (summed over continuation steps).
  int residual_evaluations = 0;  ///< Residual evaluations (excluding Jacobian ones).
  int jacobian_evaluations = 0;  ///< Jacobian evaluations.
  double residual_norm = 0.0;    ///< Final scaled residual max-norm (dimensionless).
  /// The Newton tolerance the solve used (SolverOptions::function_tolerance, resolved: 0 there is
  /// tied to the tip tolerance); converged means residual_norm at most this.
  double function_tolerance = 0.0;
  /// The tip tolerance the solve used (m; SolverOptions::tip_tolerance, resolved for the robot).
  double tip_tolerance = 0.0;
  double physical_residual = 0.0;///< Final unscaled residual 2-norm (mixed N, N m, m).
  int unknowns = 0;              ///< Size of the nonlinear system.
  int continuation_steps = 0;    ///< Load steps used by continuation (0: direct solve).
  std::string linear_solver;     ///< "dense", "klu", "system" (the model's own Newton steps), or "none" (closed form).
  std::string integrator;        ///< "rk4", "cvode", or "none".
  /// Accuracy-driven RK4 (integrator "rk4", SolverOptions::tip_tolerance): Richardson estimate of
  /// the tip position error of the answer (m), from its mesh and the next coarser one; NaN otherwise.
  double tip_error_estimate = std::numeric_limits<double>::quiet_NaN();
  int rk4_refinements = 0;       ///< Accuracy-driven RK4: solves on refined meshes (0 otherwise).
  /// Accuracy-driven RK4: halvings of the first mesh's steps in the answer's mesh (it has 2^this
  /// times the first mesh's steps; 0 otherwise). A warm start from this answer starts on the
  /// coarsest mesh its estimate predicts to meet half the tolerance.
  int rk4_halvings = 0;
  /// Accuracy-driven RK4: 0 if this solve measured tip_error_estimate (Richardson, two meshes);
  /// k > 0 if it is predicted from the estimate measured k warm-started solves earlier, scaled to
  /// this mesh by RK4's fourth-order law (SolverOptions::integrator says when a warm solve
  /// predicts instead of measuring).
  int tip_error_estimate_age = 0;
  double solve_time_s = 0.0;     ///< Wall time of the solve (s).

  /// @brief True only if termination is Converged: the returned shape is an equilibrium within
  /// the solver tolerance.
  bool converged() const { return termination == TerminationType::Converged; }
  /// @brief One line: "converged: 7 iterations, |F| = 3.1e-13, 1.2 ms (dense, rk4)".
  std::string brief_report() const;
};

/// @brief Whether an equilibrium is stable.
enum class StabilityStatus {
  Stable,       ///< Every small perturbation is resisted (positive reduced stiffness).
  Unstable,     ///< Some perturbation lowers the potential: the robot would leave this shape.
  Undetermined  ///< Not decided (not computed, or too close to call).
};

/// @brief Text name ("stable", "unstable", "undetermined").
std::string to_string(StabilityStatus s);

/// @brief The stability of a converged answer.
struct Stability {
  StabilityStatus status = StabilityStatus::Undetermined;  ///< The verdict.
  /// Smallest eigenvalue of the scaled reduced stiffness (dimensionless; > 0 stable, < 0
  /// unstable); NaN when not computed.
  double margin = std::numeric_limits<double>::quiet_NaN();
  /// How it was decided; kStabilityNotChecked where SolverOptions::stability (or its automatic
  /// rule) did not ask for the test; empty: not computed (e.g. a default-constructed Solution).
  std::string method;
};

/// @brief Stability::method of an answer whose stability was not tested
/// (SolverOptions::stability).
inline constexpr const char* kStabilityNotChecked = "not checked";

/// @brief An event on the loading path from the unloaded robot to the answer.
struct PathEvent {
  /// @brief What happened.
  enum class Type {
    Fold,         ///< A limit point: the load cannot grow further on this branch.
    Bifurcation,  ///< Branches cross (a symmetry breaks).
    Snap          ///< The robot jumped to another branch past a fold.
  };
  Type type = Type::Fold;     ///< The kind of event.
  double load_fraction = 0.0; ///< Load factor where it happened (0 = unloaded, 1 = full input).
  double tip_jump = 0.0;      ///< Snap: distance the tip jumped (m); else 0.
  std::string note;           ///< One line of detail.
};

/// @brief Text name of a path event type ("fold", "bifurcation", "snap").
std::string to_string(PathEvent::Type t);

/// @brief A converged shape a real robot cannot take (e.g. a tendon chord through the backbone,
/// neighbouring disks interpenetrating).
struct GeometryWarning {
  std::string what;  ///< One line: what cannot be built, with its numbers.
  int tendon = -1;   ///< Tendon concerned (global index), or -1.
  int disk = -1;     ///< Disk concerned (0 = base), or -1.
  double value = 0.0;  ///< The offending quantity (see `what`).
};

/// @brief A sample of the backbone: arc length, frame, internal force and moment.
struct BackboneSample {
  double s = 0.0;                ///< Arc length (m).
  Frame frame;                   ///< Material frame at s.
  Vec3 n = Vec3::Zero();         ///< Internal force (N), base frame.
  Vec3 m = Vec3::Zero();         ///< Internal moment (N m), base frame.
};

/// @brief A contact of the robot with an obstacle in an answer (docs/contact.md): where the
/// obstacle pushes, how hard, and what of the robot it touches.
struct Contact {
  double s = 0.0;               ///< Arc length of the touching disk (m).
  Vec3 point = Vec3::Zero();    ///< Contact point on the robot's surface (m, base frame).
  Vec3 normal = Vec3::UnitZ();  ///< Unit direction of the force on the robot (base frame).
  double force = 0.0;           ///< Magnitude of the normal force (N), >= 0.
  double gap = 0.0;             ///< Distance to the obstacle (m); <= 0 in contact (compliant: the penetration).
  bool disk = false;            ///< True: a disk's rim touches; false: the backbone's surface.
  int disk_index = 0;           ///< The disk (1-based disk list; the backbone at that disk's centre).
  int obstacle = 0;             ///< Index in Environment::obstacles.
};

/// @brief The answer of a model for one scene.
struct Solution {
  std::string model;                      ///< Model name ("cc", "vc", ...).
  /// Identity of the model that produced it (kind, robot, effects; StaticModel::fingerprint()):
  /// a warm start is accepted only from a Solution of the same model.
  std::uint64_t model_fingerprint = 0;
  SolverSummary summary;                  ///< Status and diagnostics.
  std::vector<Frame> disk_frames;         ///< Base disk (index 0), every disk, tip last.
  std::vector<double> tendon_displacements;  ///< Per tendon (m), positive when pulled, at base.
  std::vector<double> tensions;           ///< Tendon tensions used or implied (N), if known.
  /// With tendon friction (Effects::tendon_friction on): per tendon, the tension (N) where it
  /// ends (last chord; VC: end point), the base tension times the capstan factor; else empty.
  std::vector<double> tendon_end_tensions;
  /// Displacement input (CCsub, PRB, VC, VCref): per tendon, true if it is slack (commanded
  /// below the pull of its path at zero tension, so T = 0). Empty for tension input and CC.
  std::vector<bool> tendon_slack;
  /// The external loads of the input this answer is for (with `tensions`: where a warm start
  /// from this Solution begins its input path).
  Loads loads;
  std::vector<BackboneSample> backbone;   ///< Dense backbone samples (VC, VCref), may be empty.
  Eigen::VectorXd unknowns;               ///< The model's solved unknowns (for warm starts).
  /// Why this model was used when the scene asked for "auto" (model_selection.hpp); empty else.
  std::string model_selection;
  Stability stability;                    ///< Stability of the answer (if tested: SolverOptions::stability).
  std::vector<PathEvent> path_events;     ///< Folds, bifurcations, snaps met on the way.
  std::vector<GeometryWarning> geometry_warnings;  ///< Shapes a real robot cannot take.
  std::vector<Contact> contacts;          ///< Contacts with obstacles that carry force (CCsub, PRB, VC, VCref).
  /// d(tip pose) / d(Actuation::values), 6 x m (SolverOptions::differential_kinematics; empty
  /// otherwise or if it could not be computed). Rows 0-2: tip position (m per unit of the value,
  /// base frame); rows 3-5: rotation vector w of the tip rotation increment in the base frame,
  /// R(v + dv) = exp([w]) R(v) (rad per unit). Columns in global tendon order.
  Eigen::MatrixXd tip_jacobian;
  /// d(tip pose) / d(tip wrench), 6 x 6: columns tip force x, y, z (N), tip moment x, y, z (N m),
  /// base frame; rows as tip_jacobian. Empty for CC (no statics of external loads).
  Eigen::MatrixXd tip_compliance;

  /// @brief Shorthand for summary.converged().
  bool converged() const { return summary.converged(); }
  /// @brief Tip frame (last disk frame). Requires a non-empty disk_frames.
  const Frame& tip() const { return disk_frames.back(); }
};

}  // namespace tdcr
