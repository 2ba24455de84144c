/// @file arclength.hpp
/// @brief Pseudo-arclength continuation: follow the solution curve of F(x; lambda) = 0 from a
/// known solution at lambda = start towards lambda = target, through limit points (folds),
/// detecting folds and bifurcations on the way; optionally jump ("snap") to another branch
/// where the curve turns back before the target.
///
/// Numerics only. Beside natural-parameter continuation (continuation.hpp), which steps lambda
/// and therefore stalls at the first fold, this parameterises the curve by its (scaled)
/// arclength, so it walks around folds.
///
/// Scaled coordinates: every distance, step and tangent is measured in z = (D x, lambda / L),
/// where D = diag(system.unknown_scale()) and L = |target - start|, so that lambda moves by 1
/// from start to target and every unknown by O(1) over its typical magnitude.
///
/// Corrector: KINSOL Newton (NewtonSolver) on the bordered system of size n + 1,
///   G(x, lambda) = [ F(x; lambda) ; t^T (z - z_pred) ] = 0,
/// where t is the unit tangent at the last accepted point and z_pred = z + step t. Its
/// Jacobian is assembled from the inner system's own Jacobian when it has one (analytic dense
/// or sparse), otherwise from finite differences (grouped by the inner sparsity pattern if it
/// declares one); dF/dlambda is one forward difference in lambda; the border row is exact. A
/// system with a sparsity pattern gives a bordered pattern (its pattern plus a full last row and
/// column), so KLU applies to large systems. The tangent and the determinant used for
/// bifurcation detection come from a dense LU of the (n+1) x (n+1) augmented Jacobian, one per
/// accepted point: O(n^3), fine for the few hundred unknowns of tdcr's models.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "tdcr/bvp/continuation.hpp"
#include "tdcr/bvp/newton_solver.hpp"

namespace tdcr::bvp {

/// @brief What arclength_continuation() does at a fold where lambda turns back before reaching
/// the target (the loading path meets a limit point).
enum class FoldAction {
  Continue,  ///< Follow the curve around the fold (onto the branch beyond it).
  /// Jump: solve F(x; lambda_fold + overshoot) = 0 by natural-parameter Newton from the fold
  /// state perturbed along the curve's tangent there (the null vector of dF/dx), with growing
  /// amplitude, first in the direction the path was moving, then the opposite one; the first
  /// converged solution is the landing point on another branch, from which the continuation goes
  /// on towards the target. This models a quasi-static snap-through: at the fold the state loses
  /// its equilibrium and moves to a distant one at (almost) the same load. The landing branch is
  /// the one nearest along the tangent, not proven stable (no stability test is made). If no
  /// attempt lands and the system can damp (ParameterizedSystem::set_damping), the state moves
  /// from the fold by overdamped motion at the landing parameter until it rests (see
  /// ArclengthOptions::damped_landing_steps): the landing is then where a real structure with
  /// viscous damping comes to rest, a stable equilibrium.
  Snap
};

/// @brief Step control and event handling of arclength_continuation(). Steps are in scaled
/// arclength (dimensionless, see the file comment): 1 is the length of a path that moves lambda
/// from start to target and nothing else. The parameter lambda has the units of whatever it
/// scales (for the models, a load factor from 0 to 1). Counts are Newton solves or iterations.
struct ArclengthOptions {
  double start = 0.0;           ///< Parameter at which the initial x is (about) a solution. Default 0.
  double target = 1.0;          ///< Parameter to reach (finite, != start). Default 1.
  double initial_step = 0.05;   ///< First step (scaled arclength). Default 0.05.
  double min_step = 1e-6;       ///< A failed step that would shrink below this stalls. Default 1e-6.
  double max_step = 0.25;       ///< Largest step (scaled arclength). Default 0.25.
  double growth = 1.5;          ///< Step factor after an easy corrector (>= 1). Default 1.5.
  double shrink = 0.5;          ///< Step factor after a rejected step, in (0, 1). Default 0.5.
  /// A corrector with at most this many Newton iterations is "easy" and grows the next step
  /// (>= 0). Default 4.
  int easy_iterations = 4;
  /// Largest angle (radians, in (0, pi]) between consecutive unit tangents; a step turning more
  /// is rejected (it may have jumped to another branch). A step whose corrector moves farther
  /// from the predictor than the step itself is rejected for the same reason. Default 1.
  double max_turn = 1.0;
  /// Most corrector solves of the path (accepted or not; >= 1), so total work is bounded. Event
  /// refinement, snaps and the final solve at the target have their own bounds below. Default
  /// 400.
  int max_steps = 400;
  /// Newton iteration limit of a corrector (>= 1; capped by the Newton options' own limit). A
  /// step too long for its corrector is rejected and shortened; near a singular point such a
  /// corrector can otherwise run 150 iterations before it fails (VC at a tendon's geometric
  /// limit). Default 30.
  int corrector_max_iterations = 30;
  /// Scaled residual (dimensionless) below which correctors freeze their Jacobian (NewtonOptions::
  /// freeze_jacobian_below; 0 or not above the function tolerance: exact Newton). A corrector
  /// starting below it reuses the last corrector's Jacobian. Soft robots under tip forces
  /// (bench_soft, docs/design-notes/arclength.md): PRB's median solve 86 -> 39 ms. Default 1e-3;
  /// the models layer sets 0 when its options forbid reusing Jacobians (no Jacobian history).
  double corrector_freeze_jacobian_below = 1e-3;
  /// Parameter window (fraction of |target - start|, >= 0): the path stops (stalled) when lambda
  /// leaves [start - window (target - start), target + window (target - start)] (for start <
  /// target; mirrored otherwise): a curve that turned back for good would otherwise run until
  /// max_steps. Default 1.
  double window = 1.0;
  /// Watch the sign of the augmented determinant for bifurcations. Default true.
  bool detect_bifurcations = true;
  /// Relative tolerance of event location, in (0, 1): events are located by regula falsi
  /// (Illinois) on their test function (the lambda component of the unit tangent for folds, the
  /// normalised determinant for bifurcations) until it is below this fraction of its value at
  /// the bracket's ends. For a fold, lambda is then accurate to about tolerance^2 / curvature.
  /// Default 1e-8.
  double event_tolerance = 1e-8;
  int max_refine_iterations = 40;  ///< Corrector solves per event refinement (>= 1). Default 40.
  FoldAction at_fold = FoldAction::Continue;  ///< See FoldAction. Default FoldAction::Continue.
  /// Snap: landing parameter lambda_fold + snap_overshoot (target - start) (capped at target);
  /// if no attempt lands there, 10, 100, ... times further, up to 0.1 (target - start). A
  /// fraction of |target - start|, in (0, 1). Default 1e-4.
  double snap_overshoot = 1e-4;
  /// Snap: first perturbation amplitude along the unit null vector (scaled units, > 0); doubled
  /// after every pair of failed attempts (one per direction), snap_tries times. Default 0.05.
  double snap_perturbation = 0.05;
  int snap_tries = 8;  ///< Snap: number of amplitudes tried (>= 1). Default 8.
  /// Snap: Newton iteration limit of each attempt (>= 1; capped by the Newton options' own
  /// limit); an attempt that starts in the basin of the vanished equilibrium only creeps, so cut
  /// it short. Default 30.
  int snap_max_iterations = 30;
  /// Snap: when no Newton attempt lands, at most this many implicit Euler steps (>= 0) of the
  /// overdamped motion (ParameterizedSystem::set_damping) from the fold state at the first
  /// landing parameter, each a Newton solve of corrector_max_iterations at most. The pseudo-time
  /// step starts at 1 / damped_landing_rate and follows the motion: multiplied by
  /// (target move) / (scaled move of the step), by 1/4 to 4 per step, and quartered after
  /// a failed step (the residual grows while the structure snaps, so it cannot steer the step).
  /// The target move starts at damped_landing_move and grows by 1.5 after each step whose Newton
  /// solve took at most 3 iterations, up to 16 damped_landing_move; it halves after one of more
  /// than 10 and is reset by a failed step. A failed step also asks fold_limit whether the motion
  /// has run into a limit of the system (it stops there). Once the pseudo-time step has grown
  /// past 1e6 the motion has come to rest and a natural Newton solve finishes; a landing that
  /// accept_landing rejects (a saddle, to which long implicit Euler steps are drawn) damps on
  /// with the pseudo-time step bounded, 4 times shorter after each rejection (at most 4). 0: no
  /// damped landing. Default 300.
  int damped_landing_steps = 300;
  /// Snap: first damping rate of the damped landing (scaled units: 1 / pseudo-time step; > 0).
  /// Default 1.
  double damped_landing_rate = 1.0;
  /// Snap: scaled move per step of the damped landing that keeps its pseudo-time step (> 0).
  /// Default 0.02.
  double damped_landing_move = 0.02;
  /// Snap: a test of the fold point (x, lambda), called before any snap is tried. A non-empty
  /// return names a limit of the system there (no other branch is sought: the run stalls at the
  /// fold with that reason, instead of spending up to 8 x 2 x 4 attempts of snap_max_iterations
  /// each). Empty function (default): every fold is snapped.
  std::function<std::string(const Eigen::VectorXd&, double)> fold_limit;
  /// Snap: a test of each landing (x, lambda) a snap attempt converged to. A non-empty return
  /// rejects it with that reason (e.g. "unstable": a Newton attempt converges to whichever root
  /// is nearest, which past a fold can be a saddle the structure would not stay at); the next
  /// attempt is tried, and a damped landing that comes to rest at a rejected point damps on from
  /// it. Empty function (default): every converged attempt lands.
  std::function<std::string(const Eigen::VectorXd&, double)> accept_landing;
  /// The scalar stored per path point (ArclengthPoint::value), from (x, lambda); empty
  /// (default): the 2-norm of x.
  std::function<double(const Eigen::VectorXd&, double)> output;
  /// Outputs stored per event (ArclengthEvent::output), from (x, lambda) at the event point,
  /// evaluated during the run while the unknowns keep the parameterisation of the path (before
  /// the final accept_step()); e.g. a position whose jump across a snap is wanted. Empty
  /// (default): none.
  std::function<Eigen::VectorXd(const Eigen::VectorXd&, double)> event_output;

  /// @brief Throws InputError (field `arclength.<name>`) on inconsistent values: start ==
  /// target, non-finite values, steps not positive or min_step > initial_step > max_step,
  /// growth < 1, shrink outside (0, 1), max_turn outside (0, pi], counts < 1 (snap_max_iterations
  /// included), negative window, event_tolerance outside (0, 1), snap_overshoot outside (0, 1),
  /// snap_perturbation <= 0, damped_landing_steps < 0, damped_landing_rate or
  /// damped_landing_move <= 0.
  void validate() const;
};

/// @brief Kind of an event found on the path.
enum class ArclengthEventType {
  Fold,         ///< Limit point: the lambda component of the tangent changes sign.
  /// Simple bifurcation: the determinant of the augmented Jacobian [dF/d(x, lambda); t^T]
  /// changes sign. It does not at a fold (only det dF/dx does), so folds and bifurcations are
  /// told apart.
  Bifurcation,
  Snap          ///< FoldAction::Snap jumped from a fold to another branch.
};

/// @brief Text name of an event type ("fold", "bifurcation", "snap").
std::string to_string(ArclengthEventType t);

/// @brief An event on the path.
struct ArclengthEvent {
  ArclengthEventType type = ArclengthEventType::Fold;  ///< What happened.
  double lambda = 0.0;   ///< Parameter there (Snap: the landing parameter).
  int index = -1;        ///< ArclengthResult::path[index] is the event point (Snap: landing).
  /// Snap: |D (x_after - x_fold)|_2, the jump in scaled units. Fold, Bifurcation: 0.
  double jump = 0.0;
  /// Fold, Bifurcation: the test function converged to event_tolerance (false: best estimate
  /// within max_refine_iterations). Snap: true.
  bool refined = false;
  /// Snap: implicit Euler steps of the damped motion that landed it (ArclengthOptions::
  /// damped_landing_steps); 0: a Newton attempt landed. Fold, Bifurcation: 0.
  int damped_steps = 0;
  Eigen::VectorXd x;     ///< State at the event (Snap: after the jump).
  /// ArclengthOptions::event_output at the event point (empty without one). A Snap follows
  /// the Fold it jumps from, so the jump of the output is the difference of the two.
  Eigen::VectorXd output;
};

/// @brief A point of the path (accepted points, refined event points, snap landings, the
/// final point at the target).
struct ArclengthPoint {
  double lambda = 0.0;          ///< Parameter.
  double value = 0.0;           ///< ArclengthOptions::output(x, lambda), default |x|_2.
  double arclength = 0.0;       ///< Scaled arclength from the start (a snap adds nothing).
  double tangent_lambda = 0.0;  ///< Lambda component of the unit scaled tangent.
};

/// @brief Why arclength_continuation() stopped.
enum class ArclengthStatus {
  Reached,    ///< The target was reached: x solves F(x; target) = 0.
  Stalled,    ///< Steps shrank below min_step, the path left the window, or a snap or the
              ///< final solve failed (the message says which).
  StepLimit   ///< max_steps corrector solves were spent before the target was reached.
};

/// @brief Text name of a status ("reached", "stalled", "step_limit").
std::string to_string(ArclengthStatus s);

/// @brief Outcome of arclength_continuation().
struct ArclengthResult {
  ArclengthStatus status = ArclengthStatus::Stalled;  ///< Why it stopped.
  /// Parameter of the returned x (the target if reached, else the last accepted point).
  double parameter = 0.0;
  std::vector<ArclengthPoint> path;     ///< The path, in order.
  std::vector<ArclengthEvent> events;   ///< Folds, bifurcations and snaps, in path order.
  /// A limit of the system (ArclengthOptions::fold_limit, non-empty) that a snap's damped motion
  /// ran into: beyond the fold the state moves into it (the run then stalls at the fold).
  std::string limit;
  /// The run stalled at a fold whose snap found no landing (no Newton attempt landed and the
  /// damped motion was unavailable or did not come to rest) and ran into no limit.
  bool unlanded_snap = false;
  int steps = 0;             ///< Corrector solves of the path (accepted or not).
  int accepted_steps = 0;    ///< Accepted corrector solves.
  int newton_solves = 0;     ///< All Newton solves (path, refinements, snaps, start, target).
  /// Snap landings that converged but ArclengthOptions::accept_landing rejected.
  int rejected_landings = 0;
  int iterations = 0;        ///< Newton iterations summed over all solves.
  /// Residual evaluations of the inner system, finite-difference ones included.
  int residual_evaluations = 0;
  int jacobian_evaluations = 0;  ///< Jacobian evaluations (bordered and natural).
  double arclength = 0.0;    ///< Scaled arclength travelled.
  double last_step = 0.0;    ///< Last attempted step (scaled arclength).
  NewtonResult last;         ///< The last Newton solve.
  /// One line, e.g. "reached parameter 1 after 23 steps (21 accepted), 2 folds,
  /// 0 bifurcations, 0 snaps" or "stalled at parameter 0.38: <why>; last solve: <Newton>".
  std::string message;

  /// @brief True if the target was reached (then x solves the system at the target).
  bool converged() const { return status == ArclengthStatus::Reached && last.converged(); }
  /// @brief Number of events of one type.
  int count(ArclengthEventType type) const;
};

/// @brief Pseudo-arclength continuation of `system` from options.start to options.target.
///
/// Starts with a natural Newton solve at start from x (so x need only be close). Each step:
/// tangent predictor (solve [dF/dz; t_prev^T] t = e_{n+1}, normalise), bordered corrector,
/// acceptance tests (converged, turn <= max_turn, corrector distance <= step), then event
/// tests against the previous point. When the predictor would pass the target, the step is cut
/// to land the predictor on it and a natural Newton solve at exactly lambda = target finishes;
/// when a corrector (or a refined fold) passes it, a natural Newton solve at the target from
/// the linear interpolation between the two points finishes. A fold whose lambda passes the
/// target counts as passing it (the path meets the target before turning back).
///
/// system.set_parameter() is called before every residual evaluation of the bordered system
/// (lambda is one of its unknowns), so it must be cheap and must not allocate.
/// system.accept_step() is called once, on the returned x (the path compares unknowns across
/// points, so they must keep one parameterisation meanwhile).
///
/// Allocates per call (bordered system, LU, a few vectors), not per step, apart from the path
/// and event lists and the messages of the Newton results.
///
/// @param newton Reusable Newton workspace (rebuilt when switching between the bordered and
///        the natural system, i.e. at the start, at snaps and at the end).
/// @param system The parameterised system (its Jacobian, sparsity and scales are used).
/// @param x In: a solution, or a good guess, at options.start. Out: the solution at
///        result.parameter.
/// @param newton_options Settings of every Newton solve.
/// @param options Validated here (throws InputError).
/// @return The result; the system's parameter is left at result.parameter.
ArclengthResult arclength_continuation(NewtonSolver& newton, ParameterizedSystem& system,
                                       Eigen::VectorXd& x, const NewtonOptions& newton_options,
                                       const ArclengthOptions& options = ArclengthOptions());

}  // namespace tdcr::bvp
