/// @file continuation.hpp
/// @brief Natural-parameter continuation: solve F(x; lambda) = 0 for lambda moving from a start
/// value, where the solution is known, to a target value, in adaptive steps, each Newton solve
/// warm-started from the last converged one.
///
/// Numerics only: what lambda scales (for the models: every load, i.e. tendon tensions, tip
/// wrench and gravity, so that the unloaded robot at lambda = 0 is an exact solution) is the
/// business of the ParameterizedSystem. This is the one continuation mechanism of tdcr; every
/// static model calls continuation() from its own solve() when a direct solve fails.
#pragma once

#include <string>

#include <Eigen/Core>

#include "tdcr/bvp/newton_solver.hpp"
#include "tdcr/bvp/residual_system.hpp"

namespace tdcr::bvp {

/// @brief A residual system F(x; lambda) = 0 with one scalar parameter lambda.
///
/// set_parameter() must change F only through lambda and must not allocate (it is called once
/// per continuation step). Size, sparsity and scales must not depend on lambda.
class ParameterizedSystem : public ResidualSystem {
 public:
  /// @brief Set the parameter of the following residual evaluations.
  virtual void set_parameter(double lambda) = 0;
  /// @brief Called after every converged step with its solution x (at the current parameter),
  /// before x is stored as the starting point of the next step. A system may re-parameterise
  /// its unknowns here, e.g. fold rotation increments into reference rotations and zero them
  /// (x must then describe the same state afterwards). Default: nothing.
  virtual void accept_step(Eigen::VectorXd& x) { (void)x; }
  /// @brief Pseudo-arclength continuation calls this at every accepted point x of a path (at the
  /// current parameter): a system whose unknowns are charts around references may re-centre
  /// them where they have drifted far (x must then describe the same state afterwards) and
  /// return true; the path then recomputes its tangent there in the new coordinates. Default:
  /// nothing (false).
  virtual bool recenter(Eigen::Ref<Eigen::VectorXd> x) {
    (void)x;
    return false;
  }
  /// @brief Viscous damping, for snap landings by overdamped motion (ArclengthOptions::
  /// damped_landing_steps). From this call on, the residual is
  ///   F(x) + rate D (q(x) - q(x_ref)),
  /// q the system's generalized coordinates (e.g. positions and rotations of bodies) in rows
  /// where F is the gradient of a potential in q ("elastic forces minus loads"), D a positive
  /// diagonal of the system's scales; other rows unchanged. Solving it is then one implicit
  /// Euler step, of pseudo-time 1 / rate, of the overdamped motion dq/dt = -D^-1 F: a motion
  /// that lowers the potential and comes to rest only at a stable equilibrium. The Jacobian the
  /// system provides must include the term. rate = 0 removes it. Returns false (and changes
  /// nothing) if the system cannot damp (default).
  virtual bool set_damping(const Eigen::Ref<const Eigen::VectorXd>& x_ref, double rate) {
    (void)x_ref;
    (void)rate;
    return false;
  }
};

/// @brief Step control of continuation(). Steps are fractions of |target - start|
/// (dimensionless); the parameter itself has the units of whatever it scales (for the models, a
/// load factor from 0 to 1).
struct ContinuationOptions {
  /// Parameter at which the initial x is a solution. Default 0.
  double start = 0.0;
  /// Parameter to reach (finite, != start). Default 1.
  double target = 1.0;
  /// First step, as a fraction of |target - start|, in (0, 1]. Default 0.25.
  double initial_step = 0.25;
  /// Smallest step, as a fraction of |target - start|, in (0, 1]: a failure at a step that
  /// would halve below this stops the continuation ("stalled"). Default 1/4096.
  double min_step = 1.0 / 4096.0;
  /// Largest step, as a fraction of |target - start|, in (0, 1]. Default 1.
  double max_step = 1.0;
  /// Step factor after a converged step (>= 1). Default 2.
  double growth = 2.0;
  /// Step factor after a failed step, in (0, 1). Default 0.5.
  double shrink = 0.5;
  /// Most Newton solves (converged or not; count, >= 1), so total work is bounded. Default 64.
  int max_steps = 64;

  /// @brief Throws InputError (field `continuation.<name>`) on inconsistent values: start ==
  /// target, non-finite values, steps outside (0, 1], growth < 1, shrink outside (0, 1),
  /// max_steps < 1.
  void validate() const;
};

/// @brief Why continuation() stopped.
enum class ContinuationStatus {
  Reached,    ///< The target parameter was reached: x solves F(x; target) = 0.
  Stalled,    ///< A step failed and the next one would be shorter than min_step.
  StepLimit   ///< max_steps Newton solves were spent before the target was reached.
};

/// @brief Text name of a continuation status ("reached", "stalled", "step_limit").
std::string to_string(ContinuationStatus s);

/// @brief Outcome of continuation().
struct ContinuationResult {
  ContinuationStatus status = ContinuationStatus::Stalled;  ///< Why it stopped.
  /// Last parameter at which a Newton solve converged (start if none did): x solves
  /// F(x; parameter) = 0 and the system's parameter is left at this value.
  double parameter = 0.0;
  /// Fraction of the way from start to target that was reached, (parameter - start) /
  /// (target - start), in [0, 1].
  double fraction = 0.0;
  int steps = 0;                 ///< Newton solves performed (converged or not).
  int accepted_steps = 0;        ///< Converged Newton solves.
  int iterations = 0;            ///< Newton iterations summed over all steps.
  int residual_evaluations = 0;  ///< Residual evaluations summed over all steps.
  int jacobian_evaluations = 0;  ///< Jacobian evaluations summed over all steps.
  double last_step = 0.0;        ///< Last attempted step (parameter units).
  /// The last Newton solve: the converged solve at the target if status == Reached, otherwise
  /// the last failed solve (its termination and message say why it failed).
  NewtonResult last;
  /// One line: "reached parameter 1 in 5 Newton solves (4 converged)" or "stalled at parameter
  /// 0.62 (62 % of the way) after 17 Newton solves: <last Newton message>".
  std::string message;

  /// @brief True if the target was reached (then x solves the system at the target).
  bool converged() const { return status == ContinuationStatus::Reached && last.converged(); }
};

/// @brief Natural-parameter continuation of `system` from options.start to options.target.
///
/// The step grows by `growth` after every converged Newton solve (up to max_step) and shrinks
/// by `shrink` after every failed one; a failed solve restarts from the last converged x. The
/// predictor is the last converged solution (zero order). Newton solves use `newton_options`
/// unchanged. Allocates two vectors of size system.size() per call (not per step).
///
/// @param newton Reusable Newton workspace.
/// @param system The parameterised system.
/// @param x In: a solution at options.start (not re-checked). Out: the solution at
///        result.parameter (the last converged step; the input x if no step converged).
/// @param newton_options Settings of every Newton solve (validated by NewtonSolver::solve).
/// @param options Step control (validated here: throws InputError on inconsistent values).
/// @return Work counters, the parameter reached and the last Newton result. The system's
///         parameter is left at result.parameter.
ContinuationResult continuation(NewtonSolver& newton, ParameterizedSystem& system, Eigen::VectorXd& x,
                                const NewtonOptions& newton_options,
                                const ContinuationOptions& options = ContinuationOptions());

}  // namespace tdcr::bvp
