/// @file dynamics.hpp
/// @brief Robots that move: the time integration of a static model's equations of motion.
///
/// A DynamicsIntegrator advances one model's state (shape and velocity) in time under a
/// time-varying ModelInput. It starts from a static answer (the equilibrium of the first input,
/// at rest) and is advanced output step by output step; each model family supplies its own:
/// - CCsub and PRB (models/lumped/): the joint-space equations of motion M(q) q'' + D q' = Q(q, t)
///   (mass matrix from the backbone and the disks, the statics' springs and tendon forces as Q,
///   Kelvin-Voigt damping), integrated by CVODE (BDF) with the models' Jacobians;
/// - VC and VCref (models/vc/, models/vcref/): the Cosserat rod with its time derivatives
///   replaced by an implicit formula (BDF-alpha, Till, Aloi and Rucker, IJRR 2019), so that each
///   time step is a boundary-value problem solved by shooting with KINSOL, warm-started from the
///   last step.
///
/// `simulate` is the loop over the output times that every front end (the CLI's `tdcr simulate`,
/// Python's `tdcr.simulate`) calls.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "tdcr/core/scene.hpp"
#include "tdcr/core/solution.hpp"
#include "tdcr/core/solver_options.hpp"
#include "tdcr/core/types.hpp"

namespace tdcr {

class StaticModel;

/// @brief The implicit time scheme of the Cosserat models (the lumped models use CVODE's BDF).
enum class TimeScheme {
  BdfAlpha,        ///< BDF-alpha (Till et al. 2019): alpha in [-0.5, 0]; alpha = 0 is BDF2.
  ImplicitMidpoint ///< Second order, conserves energy without damping (a check, not a default).
};

/// @brief Scene-file key `dynamics`: what the equations of motion add to the statics.
/// Mass comes from the robot (`robot.backbone.density` / `mass_per_length`, the disks'
/// `disk_mass`); a dynamic scene without mass is an input error.
struct DynamicsSettings {
  /// Kelvin-Voigt damping of bending and torsion, as a retardation time tau_bt (s): the damping
  /// moment is tau_bt K_bt du/dt. 0: undamped.
  double bending_damping_time = 0.0;
  /// Kelvin-Voigt damping of shear and extension, tau_se (s): tau_se K_se dv/dt. 0: undamped.
  double shear_damping_time = 0.0;
  /// Quadratic air drag per unit length, f = -air_drag |v| v (N s^2 / m^3). 0: none.
  double air_drag = 0.0;
  TimeScheme scheme = TimeScheme::BdfAlpha;  ///< Cosserat models only.
  double alpha = -0.2;                       ///< BDF-alpha parameter, in [-0.5, 0].

  /// @brief Throws InputError naming the field (`dynamics.<key>`) and value: a negative or
  /// non-finite damping time or drag, alpha outside [-0.5, 0].
  void validate() const;
};

/// @brief One entry of a scene's `timeline`: the input from time t on. Inputs between entries
/// are interpolated linearly (tensions or displacements, loads); an entry without actuation or
/// loads keeps the previous entry's.
struct TimelineEntry {
  double t = 0.0;        ///< s, strictly increasing along the timeline.
  ModelInput input;      ///< The actuation and loads at t.
};

/// @brief Scene-file key `timeline`.
struct Timeline {
  std::vector<TimelineEntry> entries;
  /// @brief The input at time t: linear between entries, the first before the first entry, the
  /// last after the last.
  ModelInput at(double t) const;
  /// @brief Throws InputError naming `timeline[i].t` (not increasing, not finite) or an input of
  /// the wrong length for `robot` (`timeline[i].actuation.values`).
  void validate(const Robot& robot) const;
};

/// @brief The state of a moving robot reported at one output time.
struct SimulationStep {
  double t = 0.0;                    ///< s.
  Frame tip;                         ///< Tip frame (base frame).
  TerminationType status = TerminationType::NotSolved;  ///< The step's solve.
  int iterations = 0;                ///< Nonlinear iterations (Cosserat) or CVODE steps (lumped).
  double kinetic_energy = 0.0;       ///< J.
  double potential_energy = 0.0;     ///< J: elastic energy plus the potential of conservative loads.
};

/// @brief A model's time integrator: made for one model, one time step, one settings.
class DynamicsIntegrator {
 public:
  virtual ~DynamicsIntegrator() = default;
  /// @brief Start at rest on the static answer `at_rest` (converged) of `input`.
  virtual void initialize(const Solution& at_rest, const ModelInput& input) = 0;
  /// @brief Advance to `t_next` (> the current time) with the input `input(t)` of the timeline.
  /// Returns the step's report; a step that fails has a status other than Converged.
  virtual SimulationStep advance(double t_next, const Timeline& timeline) = 0;
  /// @brief The current shape as a Solution (disk frames; for the Cosserat models, backbone samples).
  virtual Solution shape() const = 0;
};

/// @brief Options of `simulate`.
struct SimulationOptions {
  double duration = 1.0;     ///< s, > 0.
  double dt = 1.0 / 60.0;    ///< Output step (and the Cosserat models' time step), s, > 0.
  /// @brief Throws InputError naming `duration` or `dt` (non-positive, non-finite, or more than
  /// 10^7 steps).
  void validate() const;
};

/// @brief The integrator of `model` (InputError naming `model` if the model has no dynamics, or
/// `robot.backbone.density` if the robot has no mass).
std::unique_ptr<DynamicsIntegrator> make_dynamics_integrator(const StaticModel& model,
                                                             const DynamicsSettings& settings,
                                                             double dt);

/// @brief The result of a simulation: one step per output time, t = 0 first.
struct SimulationResult {
  std::vector<SimulationStep> steps;
  bool completed = false;  ///< Every step converged up to `duration`.
  std::string message;     ///< Why it stopped early, with the time, residual and iterations.
};

/// @brief Simulate `model` from rest on the static answer of the timeline's first input
/// (solved with `solver`), to `options.duration`.
SimulationResult simulate(const StaticModel& model, const DynamicsSettings& settings,
                          const Timeline& timeline, const SimulationOptions& options,
                          const SolverOptions& solver);

}  // namespace tdcr
