/// @file dynamics.hpp
/// (The scene keys `dynamics` and `timeline`, DynamicsSettings and Timeline, are plain data in
/// tdcr/core/scene.hpp, so that core reads them.)
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

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "tdcr/core/scene.hpp"
#include "tdcr/core/solution.hpp"
#include "tdcr/core/solver_options.hpp"
#include "tdcr/core/types.hpp"

namespace tdcr {

class StaticModel;

/// @brief The state of a moving robot reported at one output time.
struct SimulationStep {
  double t = 0.0;                    ///< s.
  Frame tip;                         ///< Tip frame (base frame).
  TerminationType status = TerminationType::NotSolved;  ///< The step's solve.
  int iterations = 0;                ///< Nonlinear iterations (Cosserat) or CVODE steps (lumped).
  /// The step's last residual (Cosserat: the boundary-value residual; lumped: CVODE's weighted
  /// local error estimate of the last internal step, below 1 when accepted).
  double residual = 0.0;
  double kinetic_energy = 0.0;       ///< J.
  double potential_energy = 0.0;     ///< J: elastic energy plus the potential of conservative loads.
  /// N, per tendon (global order): the tensions of the step, given (tension input) or solved
  /// (displacement input; exactly 0 for a slack tendon).
  std::vector<double> tensions;
  /// m, per tendon: the pulls of the tendon paths (Solution::tendon_displacements; the Cosserat
  /// models, and CCsub and PRB under displacement input with the elastic stretch added as the
  /// statics report it; empty where the integrator does not compute them).
  std::vector<double> tendon_displacements;
  /// s: the times within the step at which a displacement-driven elastic tendon went slack or
  /// taut (the lumped dynamics stop and restart CVODE there; empty otherwise).
  std::vector<double> tendon_events;
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
  /// @brief The potential energy (J) of the current state under the current input, as
  /// SimulationStep::potential_energy: after initialize(), that of the start at rest.
  virtual double potential_energy() = 0;
  /// @brief Whether timeline entries may give tendons by displacement (their tensions then are
  /// unknowns of every step). simulate() refuses such a timeline otherwise, naming
  /// `timeline[i].actuation`.
  virtual bool takes_displacement_input() const { return false; }
  /// @brief Throws InputError naming the field if this integrator cannot take `timeline`'s
  /// displacement-driven tendons (the lumped dynamics: an inextensible one, naming
  /// `robot.segments[i].tendons[k].stiffness`). simulate() calls it where
  /// takes_displacement_input() is true.
  virtual void check_displacement_input(const Timeline& timeline) const { (void)timeline; }
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
/// `robot.backbone.density` if the robot has no mass). `solver` sets the accuracy (the lumped
/// models: CVODE's tolerances, see docs/dynamics.md).
std::unique_ptr<DynamicsIntegrator> make_dynamics_integrator(const StaticModel& model,
                                                             const DynamicsSettings& settings,
                                                             double dt, const SolverOptions& solver = SolverOptions{});

/// @brief The result of a simulation: one step per output time, t = 0 first.
struct SimulationResult {
  std::vector<SimulationStep> steps;  ///< One per output time, t = 0 first (up to a failed step).
  bool completed = false;  ///< Every step converged up to `duration`.
  std::string message;     ///< Why it stopped early, with the time, residual and iterations.
};

/// @brief What `simulate` shows an observer after every reported step: the step and the shape
/// it reports (at t = 0 the static answer; then DynamicsIntegrator::shape()). The shapes are
/// made only for an observer: a simulation without one pays nothing for them.
using SimulationObserver = std::function<void(const SimulationStep& step, const Solution& shape)>;

/// @brief Simulate `model` from rest on the static answer of the timeline's first input
/// (solved with `solver`), to `options.duration`; `observer`, if given, sees every reported step
/// with its shape (Python's `tdcr.simulate(..., shapes=True)` keeps the disk positions).
SimulationResult simulate(const StaticModel& model, const DynamicsSettings& settings,
                          const Timeline& timeline, const SimulationOptions& options,
                          const SolverOptions& solver, const SimulationObserver& observer = {});

}  // namespace tdcr
