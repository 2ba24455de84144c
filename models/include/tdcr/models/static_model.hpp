/// @file static_model.hpp
/// @brief The model interface, its workspaces, and the one solve function.
///
/// Pinocchio's split: a StaticModel is an immutable description built once from a Robot and its
/// Effects; a ModelWorkspace is the mutable memory of its solves (Newton and integrator memory,
/// Jacobian storage), made by the model and belonging to it; the actuation and the loads are the
/// per-call ModelInput. A trajectory uses one model and one workspace:
///
/// @code
/// auto model = tdcr::make_model(tdcr::ModelKind::VC, robot, effects);
/// auto ws = model->make_workspace();
/// tdcr::Solution previous;
/// for (const tdcr::ModelInput& input : trajectory) {
///   tdcr::Solution s = tdcr::solve(*model, *ws, input, options, previous.converged() ? &previous : nullptr);
///   previous = s;
/// }
/// @endcode
///
/// A Scene (robot, input, effects, model name, options) and `tdcr::solve(scene)` stay the front
/// door for one-shot solves and scene files.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include <Eigen/Core>

#include "tdcr/core/robot.hpp"
#include "tdcr/core/scene.hpp"
#include "tdcr/core/solution.hpp"
#include "tdcr/core/solver_options.hpp"

namespace tdcr {

/// @brief The models of the paper (Table 2). Names, capabilities and factories are in the
/// registry (model_registry.hpp).
enum class ModelKind {
  CC,     ///< Constant curvature per segment, kinematic (Eq. 8, 14-18; 20-23).
  CCsub,  ///< Constant curvature per subsegment with twist, static (Eq. 8, 30-33, 43-47).
  PRB,    ///< 3R pseudo-rigid body per subsegment with twist (Eq. 11-12, 48-54).
  VC,     ///< Cosserat rod, fully constrained tendons (Eq. 2-3, 24-29, 34-41).
  VCref   ///< Cosserat rod per subsegment, discrete disk forces (Eq. 30-33, 38-41, 44-47, 58).
};

/// @brief The registry name of a model ("cc", "ccsub", "prb", "vc", "vcref").
std::string to_string(ModelKind kind);
/// @brief The model of a registry name (case-insensitive). Throws InputError with field `model`.
ModelKind parse_model_kind(const std::string& name);

/// @brief What a model can take and compute.
struct ModelCapabilities {
  bool tension_input = true;        ///< Actuation by tendon tensions.
  bool displacement_input = false;  ///< Actuation by tendon displacements.
  bool external_loads = true;       ///< Tip wrench and gravity.
  bool backbone_wrench = false;     ///< Solutions carry internal force and moment samples.
  /// Tendons act on the backbone at the disks only, along straight chords between holes
  /// (Eq. 30-33); else along the backbone (fully constrained path, Eq. 24-29).
  bool tendon_forces_at_disks = false;
  /// Displacement input with statics: the tensions of the displacement-driven tendons are
  /// unknowns (solve/displacement_input.hpp); mixed input and elastic tendons. Else a model
  /// that takes displacements maps them kinematically (CC).
  bool displacement_statics = false;
  bool tendon_friction = false;  ///< Capstan tendon friction (Effects::tendon_friction).
  /// Tendon routings other than straight (helical, polynomial): CC's closed form represents
  /// straight routing only.
  bool curved_routing = true;
  /// The rod is integrated on SolverOptions' RK4 mesh (VC, VCref): the accuracy-driven mesh
  /// (`solver.tip_tolerance`) and the coarse loading path apply. Else the model has no mesh.
  bool rk4_mesh = false;
  /// The automatic stability rule asks the model's problem whether a cold direct answer under
  /// external loads is tested (ModelProblem::automatic_stability_under_loads). False
  /// where the answer is always no and asking would cost a bind (VC).
  bool stability_under_loads = true;
  /// Contact with the obstacles of ModelInput::environment (docs/contact.md); a model without it
  /// refuses a scene with obstacles.
  bool contact = false;
};

class StaticModel;
class ModelProblem;

namespace detail {
class DisplacementProblem;

/// The last warm-started solve of a workspace, for the secant predictor of the next warm start
/// (SolverOptions::extrapolate_warm_starts): its warm start's input and its own (each as one
/// vector: actuation values, tip force, tip moment, gravity), the model's warm guess its Newton
/// started from, and the answer. Kept by tdcr::solve().
struct SolveHistory {
  Eigen::VectorXd from, input, guess, unknowns;
  bool valid = false;  ///< A converged warm solve is held (anything else clears it).
};
}  // namespace detail

class ModelWorkspace;
class AnswerLinearisation;
namespace detail {
/// Displacement input (models/solve/displacement_input.hpp): the workspace's problem with the
/// driven tendons' tensions as unknowns, bound for `input` (started from `tension_start`, a
/// tension solve of the same model, if given).
ModelProblem& bind_displacement_problem(const StaticModel& model, ModelWorkspace& workspace, const ModelInput& input,
                                        const SolverOptions& options, const Solution* warm_start,
                                        const Solution* tension_start);
}  // namespace detail

/// @brief Mutable memory of one model's solves. Made by StaticModel::make_workspace(), it
/// belongs to that model: solving another model with it is an InputError, also after its model
/// was destroyed (never undefined behaviour).
class ModelWorkspace {
 public:
  virtual ~ModelWorkspace();
  ModelWorkspace(const ModelWorkspace&) = delete;
  ModelWorkspace& operator=(const ModelWorkspace&) = delete;
  /// @brief True if this workspace was made by `model` and that model still exists.
  bool belongs_to(const StaticModel& model) const;

 protected:
  /// @brief A workspace of `owner`.
  explicit ModelWorkspace(const StaticModel& owner);

 private:
  friend Solution solve(const StaticModel&, ModelWorkspace&, const ModelInput&, const SolverOptions&,
                        const Solution*);
  friend ModelProblem& detail::bind_displacement_problem(const StaticModel&, ModelWorkspace&,
                                                                 const ModelInput&, const SolverOptions&,
                                                                 const Solution*, const Solution*);
  // Made on the first displacement-input solve.
  detail::DisplacementProblem& displacement_problem();
  std::weak_ptr<const int> owner_;
  detail::SolveHistory history_;
  std::unique_ptr<detail::DisplacementProblem> displacement_;
};

/// @brief An immutable model of a robot with the effects it simulates.
///
/// What a model adds to the robot is decided once, in its constructor (validated; throws
/// InputError naming the field and value). Solving goes through tdcr::solve(), which owns the
/// policy (guess, direct solve, loading from rest, continuation, final residual check, summary,
/// timing); a model supplies its residual system, guesses and outputs (ModelProblem, model_problem.hpp).
class StaticModel {
 public:
  virtual ~StaticModel();
  StaticModel(const StaticModel&) = delete;
  StaticModel& operator=(const StaticModel&) = delete;

  /// @brief Which model this is.
  virtual ModelKind kind() const = 0;
  /// @brief The registry name ("vc", ...).
  std::string name() const { return to_string(kind()); }
  /// @brief What this model takes and how the solve policy treats it (its registry row holds the
  /// same: each model class keeps them in one `kCapabilities`).
  virtual ModelCapabilities capabilities() const = 0;
  /// @brief The robot (validated).
  const Robot& robot() const { return robot_; }
  /// @brief The effects it simulates.
  const Effects& effects() const { return effects_; }
  /// @brief The robot's disks and tendon routing.
  const TendonRouting& routing() const { return routing_; }
  /// @brief Identity of (kind, robot, effects): stamped on every Solution, checked on warm starts.
  std::uint64_t fingerprint() const { return fingerprint_; }
  /// @brief A fresh workspace of this model.
  virtual std::unique_ptr<ModelWorkspace> make_workspace() const = 0;
  /// @brief Throws InputError naming the field and value if this model cannot take `input`
  /// (e.g. CC refuses external loads, the static models refuse displacements). The input
  /// itself is validated against the robot before (ModelInput::validate).
  virtual void check_input(const ModelInput& input) const;

 protected:
  /// @brief Validates `robot` and `effects` (InputError) and derives the routing.
  StaticModel(const Robot& robot, const Effects& effects);
  /// @brief The token ModelWorkspace holds to tell its owner (expires with the model).
  const std::shared_ptr<const int>& ownership_token() const { return token_; }

 private:
  friend class ModelWorkspace;
  friend class AnswerLinearisation;  // binds two models' problems to linearise across them
  friend Solution solve(const StaticModel&, ModelWorkspace&, const ModelInput&, const SolverOptions&,
                        const Solution*);
  friend ModelProblem& detail::bind_displacement_problem(const StaticModel&, ModelWorkspace&,
                                                                 const ModelInput&, const SolverOptions&,
                                                                 const Solution*, const Solution*);
  /// @brief Bind the workspace to one input and options: the problem the solve driver works on.
  /// `workspace` belongs to this model (checked by the caller).
  virtual ModelProblem& bind(ModelWorkspace& workspace, const ModelInput& input,
                                     const SolverOptions& options) const = 0;

  Robot robot_;
  Effects effects_;
  TendonRouting routing_;
  std::uint64_t fingerprint_ = 0;
  std::shared_ptr<const int> token_;
};

/// @brief Solve `model` for one input.
///
/// The answer for a cold solve (no warm start) follows the model's cold-start rule (a direct
/// Newton solve from its cold guess, or loading the robot from rest under large external loads);
/// a warm start begins from `warm_start`, a previous Solution of the same model (same kind,
/// robot and effects; anything else is an InputError). With SolverOptions::continuation a
/// failed direct solve is retried by load continuation. The returned Solution is converged only
/// if the residual at its unknowns, evaluated again at full load, is below
/// SolverOptions::function_tolerance; otherwise its summary says why (never an exception for a
/// non-convergent solve).
///
/// Throws InputError on invalid input or options, on a workspace of another model, on a warm
/// start of another model.
Solution solve(const StaticModel& model, ModelWorkspace& workspace, const ModelInput& input,
               const SolverOptions& options = SolverOptions(), const Solution* warm_start = nullptr);

/// @brief `previous`, a converged Solution of a model of the same kind as `model` but possibly of
/// another robot or other effects (a parameter study, a calibration: the robot changes slightly
/// between solves), stamped as a warm start of `model`: tdcr::solve(model, ..., &result) starts
/// from its unknowns (a model whose unknowns do not fit them starts cold). Throws InputError
/// (field `warm_start`) if `previous` is of another model kind or did not converge.
Solution warm_start_from_other_robot(const StaticModel& model, const Solution& previous);

/// @brief Build the model `kind` of a robot with the given effects (InputError on bad input).
std::unique_ptr<StaticModel> make_model(ModelKind kind, const Robot& robot, const Effects& effects = Effects());
/// @brief Build the model `kind` of a scene's robot and effects (the scene's input is not used).
std::unique_ptr<StaticModel> make_model(ModelKind kind, const Scene& scene);

/// @brief Scene::validate plus the model name (a registry name or "auto") and, for a named
/// model, StaticModel::check_input. Throws InputError naming the field and value.
void validate_scene(const Scene& scene);

/// @brief One-shot front door: build the scene's model (scene.model; "auto" chooses with
/// solve_auto at 1 % accuracy, model_selection.hpp) with a fresh workspace and solve the scene's
/// input with its solver options.
Solution solve(const Scene& scene, const Solution* warm_start = nullptr);

}  // namespace tdcr
