// Private to models/: the Cosserat rod dynamics of VC and VCref behind the shared
// DynamicsIntegrator interface (tdcr/models/dynamics.hpp). Each time step is VC's static
// boundary value problem with the time derivatives replaced by an implicit formula (BDF-alpha
// or implicit midpoint, Till, Aloi and Rucker, IJRR 2019), solved by single shooting with KINSOL
// and warm-started from the last step. docs/dynamics-cosserat.md has the equations as
// implemented and the measurements.
#pragma once

#include <limits>
#include <memory>
#include <string>

#include "tdcr/models/dynamics.hpp"
#include "tdcr/models/static_model.hpp"

namespace tdcr {

class VcModel;

namespace vc {

/// @brief Discretisation settings of the Cosserat dynamics beyond DynamicsSettings.
///
/// The spatial mesh is fixed for a whole simulation: the time history lives at the RK4
/// evaluation points (4 per RK4 step, plus both sides of every disk), so it cannot move.
struct CosseratDynamicsOptions {
  /// RK4 steps per disk interval (at least), >= 1. 2 on the paper robot at n = 10 (5 mm
  /// intervals): 20 intervals x 2 steps x 4 stages = 160 evaluation points, the "200 grid
  /// points" of Till et al.'s benchmark; docs/dynamics-cosserat.md measures its accuracy.
  int rk4_steps = 2;
  /// Longest RK4 step (m), > 0; infinity: exactly rk4_steps per interval.
  double rk4_max_step = std::numeric_limits<double>::infinity();
  /// Newton's tolerance on the tip wrench residual, scaled by the force and moment scales of
  /// the input (as VC's statics), > 0.
  double function_tolerance = 1e-10;
  /// Most Newton iterations per time step, >= 1.
  int max_iterations = 50;
  /// VC's formulation of a step. Single shooting's tip depends on the base wrench like
  /// exp(L (rho A c0^2 / EI)^(1/4)) (L the robot's length, c0 ~ 2 / dt the step's time
  /// coefficient): short steps of large motions make its Newton lose its way. Multiple shooting
  /// (one interval per disk interval) is slower per step but keeps that factor near 1. VCref
  /// always uses multiple shooting.
  enum class Shooting {
    Automatic,  ///< Multiple when L (rho A c0^2 / EI)^(1/4) > automatic_threshold, else single.
    Single,
    Multiple
  };
  Shooting shooting = Shooting::Automatic;  ///< See Shooting.
  /// Shooting::Automatic: the exponent above which VC shoots multiply (8: e^8 = 3000; single
  /// shooting carried the paper robot's 8 mm swing at 6.9 and lost it at 9.8,
  /// docs/dynamics-cosserat.md), > 0.
  double automatic_threshold = 8.0;

  /// @brief Throws InputError naming `rk4_steps`, `rk4_max_step`, `function_tolerance`,
  /// `max_iterations` or `automatic_threshold` when out of range.
  void validate() const;
};

/// @brief The Cosserat integrators' common face: the input of a step can be given directly
/// (tests and benchmarks drive it without a Timeline).
class CosseratDynamics : public DynamicsIntegrator {
 public:
  /// @brief Advance one time step to `t_next` with `input` the input of the step's equations:
  /// at t_next for BDF-alpha, at the step's midpoint for ImplicitMidpoint.
  virtual SimulationStep advance_with_input(double t_next, const ModelInput& input) = 0;
  // advance(t_next, timeline): advance_with_input with the timeline's input at t_next
  // (BDF-alpha) or at the step's midpoint (ImplicitMidpoint).
  /// @brief The current time (s): 0 after initialize().
  virtual double time() const = 0;
  /// @brief Newton residual evaluations (shots) since construction: a cost measure.
  virtual long shots() const = 0;
  /// @brief Evaluation points of the fixed mesh (history slots along the rod).
  virtual int mesh_points() const = 0;
  /// @brief The last Newton solve's message (KINSOL flag, iterations, residual).
  virtual const std::string& last_message() const = 0;
};

/// @brief The VC dynamics of `model`: `settings` validated here, `dt` the time step (s, > 0).
/// Displacement input (all tendons or mixed) makes the driven tendons' tensions unknowns of every
/// step (the statics' DisplacementProblem on the step's shooting, slack by complementarity;
/// docs/dynamics-cosserat.md); the kind of input is fixed at initialize. Throws InputError naming
/// the field: a robot without mass (`robot.backbone.density`), a step whose input changes between
/// tensions and displacements (`actuation.kind`), tendon friction (`effects.tendon_friction`), or a
/// bad setting (`dynamics.<key>`, `dt`).
std::unique_ptr<CosseratDynamics> make_vc_dynamics(const VcModel& model, const DynamicsSettings& settings, double dt,
                                                   const CosseratDynamicsOptions& options = {});

/// @brief The VCref dynamics of `model` (a VCref model, else InputError naming `model`; it lives
/// here, not in models/vcref/, because it is VC's machinery and the layers forbid a model folder
/// to include a sibling's): its free rods between the disks with the chords' disk
/// wrenches (Eq. 30-33, Eq. 58 per effects.disk_normal_force), by multiple shooting; the
/// errors of make_vc_dynamics.
std::unique_ptr<CosseratDynamics> make_vcref_dynamics(const StaticModel& model, const DynamicsSettings& settings,
                                                      double dt, const CosseratDynamicsOptions& options = {});

/// @brief DynamicsSettings::validate and the time step's check (`dt`, > 0), for integrators built
/// without tdcr::make_dynamics_integrator (tests, benchmarks).
void check_settings(const DynamicsSettings& settings, double dt);

}  // namespace vc

/// @brief The Cosserat integrator of `model` (VC or VCref; another model: InputError naming
/// `model`), with the default CosseratDynamicsOptions.
std::unique_ptr<DynamicsIntegrator> make_cosserat_dynamics_integrator(const StaticModel& model,
                                                                      const DynamicsSettings& settings, double dt);

}  // namespace tdcr
