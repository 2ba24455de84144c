/// @file model_problem.hpp
/// @brief The extension point of the models: what a model gives the solve driver for one solve.
///
/// A model's StaticModel::bind() sets its workspace up for one input and options and returns the
/// workspace's ModelProblem. The driver (tdcr::solve, models/solve/solve_driver.cpp) owns the
/// policy (which guess, direct solve or loading from rest, continuation, final residual check,
/// summary, timing); the problem owns the physics (the residual system with the load factor as
/// its parameter, the guesses, the outputs). A new model implements the pure virtual members
/// (system, newton, cold_guess, rest_state, warm_guess, extract); the others have defaults that
/// keep a model correct and only cost time or features (tests/test_model_extension.cpp).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "tdcr/bvp/continuation.hpp"
#include "tdcr/bvp/newton_solver.hpp"
#include "tdcr/core/solution.hpp"

namespace tdcr {

/// @brief How a cold solve starts.
struct ColdStart {
  /// Load the robot from rest (continuation from load factor 0) instead of a direct solve:
  /// under large external loads a direct solve can land on another equilibrium.
  bool from_rest = false;
  /// First load step whenever the robot is loaded from rest, also after a failed warm-started
  /// direct solve (0: the continuation default).
  double first_step = 0.0;
  std::string reason;       ///< Why, for the summary message.
  /// Bound on the corrector solves of a loading path of this problem (0: the path's own, at least
  /// 400): a path that is only a first attempt, with a fallback after it, is kept short.
  int max_path_steps = 0;
  /// The cold guess solves the continuous equations: it is the answer up to the mesh's own
  /// integration error (VC's base reaction of an unloaded robot whose tendons leave the base
  /// along the backbone: their pull at the clamped base, whatever the shape). Accuracy-driven RK4 then checks the guess on a fine mesh
  /// and estimates that mesh's error by one shot on the next coarser one, instead of solving on
  /// the first mesh and refining (docs/models.md, "Accuracy-driven integration").
  bool guess_is_answer = false;
};

/// @brief One bound solve of a model: the residual system at the bound input and what surrounds it.
class ModelProblem {
 public:
  virtual ~ModelProblem() = default;

  /// The residual system F(x; lambda) = 0, lambda the load factor scaling every load (tensions,
  /// tip wrench, weights; lambda = 1 is the bound input, lambda = 0 the unloaded robot). Null for
  /// a closed-form model: then extract() computes the whole answer and its summary.
  virtual bvp::ParameterizedSystem* system() = 0;
  /// The Newton solver memory of the workspace (reused across solves).
  virtual bvp::NewtonSolver& newton() = 0;
  /// Model-specific Newton settings on top of the options (e.g. a bounded step).
  virtual void adjust(bvp::NewtonOptions& options) const { (void)options; }
  /// Newton settings for a warm-started solve, after adjust() (e.g. Jacobian reuse).
  /// `same_input`: the warm start is an answer of this very input (a re-solve on a refined RK4
  /// mesh, SolverOptions::tip_tolerance): the last Jacobian is then worth reusing however many
  /// iterations the last solve took.
  virtual void adjust_warm(bvp::NewtonOptions& options, bool same_input) const {
    (void)options;
    (void)same_input;
  }
  /// Cold direct solves: exact Newton down to this scaled residual, then modified Newton from
  /// its last Jacobian (bvp::NewtonOptions::freeze_jacobian_below); 0: exact Newton throughout.
  /// Only for unknowns without a chart or gauge that a stale Jacobian could wander along.
  virtual double cold_freeze_jacobian_below() const { return 0.0; }
  /// The cold-start rule for the bound input.
  virtual ColdStart cold_start() const { return {}; }
  /// Whether a sign change of the Jacobian's determinant along a loading path (without a fold)
  /// is a bifurcation of the equilibria (ArclengthOptions::detect_bifurcations). False for
  /// unknowns with a chart whose determinant changes sign where the shape does nothing special.
  virtual bool determinant_marks_bifurcations() const { return true; }
  /// Cold guess at load factor 1 (system parameter already 1).
  virtual void cold_guess(Eigen::VectorXd& x) = 0;
  /// A second cold guess tried once after the first failed (false: none).
  virtual bool alternative_guess(Eigen::VectorXd& x) { (void)x; return false; }
  /// The exact solution at load factor 0 (the unloaded robot); the system parameter is 0.
  virtual void rest_state(Eigen::VectorXd& x) = 0;
  /// Guess from a previous Solution of the same model (checked by the driver); false if it
  /// cannot be used (e.g. it did not converge to finite unknowns).
  virtual bool warm_guess(const Solution& previous, Eigen::VectorXd& x) = 0;
  /// The residual at the returned unknowns, for the driver's final check (system parameter 1).
  /// A model whose output pass also yields the residual (VC's single shooting: one shot that
  /// records the frames) overrides it, so that extract() reuses that pass.
  virtual bool final_residual(const Eigen::VectorXd& x, Eigen::Ref<Eigen::VectorXd> f) {
    return system()->residual(x, f);
  }
  /// Outputs at the returned unknowns x: frames, backbone samples, tendon displacements, the
  /// tensions used. Called right after the driver evaluated final_residual(x) at load factor 1
  /// (`evaluated`: it succeeded), so a problem may reuse the state of that evaluation.
  /// May downgrade a converged summary (e.g. a final pass that fails to integrate).
  virtual void extract(const Eigen::VectorXd& x, bool evaluated, Solution& solution) = 0;
  /// The stability of the equilibrium x at load factor `load_factor` (the system's parameter):
  /// of the converged answer (1, called after extract(), only for a converged solve) and of a
  /// snap's landing on the loading path (path_following.cpp). Leaves the system's parameter at
  /// `load_factor`. Default: not computed (Undetermined).
  virtual Stability stability(const Eigen::VectorXd& x, double load_factor) {
    (void)x;
    (void)load_factor;
    return Stability{};
  }
  /// The stability test of a direct answer under external loads that the automatic rule
  /// (StabilityCheck::Automatic) asks for: the same verdict as stability(), possibly reached by a
  /// cheaper sufficient test first (CCsub, PRB: lumped_stability.cpp). Default: stability().
  virtual Stability direct_stability(const Eigen::VectorXd& x, double load_factor) {
    return stability(x, load_factor);
  }
  /// Whether the automatic stability rule (SolverOptions::stability, StabilityCheck::Automatic)
  /// tests this problem's answers for their external loads alone, without a loading path: where
  /// the test adds at most 25 % to the median loaded cold solve of bench_loaded (VCref: +17 %;
  /// CCsub and PRB: 14 % and 22 % with their sufficient test, direct_stability, from Newton's last
  /// Jacobian where it is near the answer). Default false; VC's conjugate-point test adds 65 % of
  /// the instructions (80-100 % of the median wall time), so its answers are tested when a path reached them (or when asked); docs/models.md,
  /// "Stability".
  virtual bool automatic_stability_under_loads() const { return false; }
  /// Called when loading from rest stopped short of full load, after extract() at x, the
  /// equilibrium at the load factor reached (the system's parameter): true and a one-line reason
  /// if the stop is a physical limit (a tendon with curvature x offset >= threshold, see
  /// physics/geometry_check.hpp) rather than a numerical failure. Also called at a fold of the
  /// loading path, after extract() there, to tell a tendon-limit fold (no snap is tried) from a
  /// snap. Default: no model-specific test (the driver still checks the extracted disk frames).
  virtual bool infeasibility(const Eigen::VectorXd& x, double threshold, std::string& why) {
    (void)x;
    (void)threshold;
    (void)why;
    return false;
  }
  /// The tip frame (base frame) at unknowns x at the system's current parameter and the bound
  /// input: for the tip jump of a snap (path following) and differential kinematics. Default:
  /// one final_residual() and extract() into a scratch Solution (its last disk frame), i.e. a
  /// full output pass; never called on a hot path.
  virtual bool tip_pose(const Eigen::VectorXd& x, Frame& tip) {
    Eigen::VectorXd f(x.size());
    Solution scratch;
    const bool evaluated = system() ? final_residual(x, f) : true;
    extract(x, evaluated, scratch);
    if (!evaluated || scratch.disk_frames.empty()) return false;
    tip = scratch.disk_frames.back();
    return tip.p.allFinite() && tip.R.allFinite();
  }
  /// Displacement input (displacement_input.hpp): tendon index[i] pulls with T[i] (N) at every
  /// load factor from now on until the next bind (its tension is an unknown of the solve, not a
  /// load that continuation scales). The problem must have been bound with these tendons
  /// tensioned (what the bind derives from which tendons act, e.g. active subsegments or the
  /// Jacobian pattern, then includes them; their bound values only set scales). False if the
  /// model cannot take it (then it takes no displacement input).
  virtual bool set_driven_tensions(const std::vector<int>& index, const Eigen::VectorXd& T) {
    (void)index;
    (void)T;
    return false;
  }
  /// The pull of every tendon (global order; Solution::tendon_displacements in the bound
  /// input's displacement convention, without an elastic tendon's stretch) at unknowns x and the
  /// system's current parameter. Default: final_residual() and extract() into a scratch
  /// Solution, a full output pass; models override it with what the pulls need (the disk frames).
  virtual bool tendon_pulls(const Eigen::VectorXd& x, Eigen::VectorXd& d) {
    Eigen::VectorXd f(x.size());
    Solution scratch;
    const bool evaluated = system() ? final_residual(x, f) : true;
    if (!evaluated) return false;
    extract(x, evaluated, scratch);
    d = Eigen::Map<const Eigen::VectorXd>(scratch.tendon_displacements.data(),
                                          static_cast<Eigen::Index>(scratch.tendon_displacements.size()));
    return d.size() > 0 && d.allFinite();
  }
  /// What complete() did.
  enum class Completion {
    Done,          ///< x is the answer (converged or not: the summary says).
    FollowAgain    ///< The problem changed its equations and asks for the whole solve again (cold).
  };
  /// After the driver's solve converged at unknowns x (system parameter 1): the problem may go
  /// on from x with problems of its own, e.g. displacement input takes the tendons' homotopy
  /// compliance to zero and moves tendons between slack and taut by complementarity, each a
  /// Newton solve from the last answer (its Newton solver, `options`). x and `summary` (its work
  /// added, its status and message) are the result. FollowAgain: the new equations could not be
  /// solved from x; the driver then solves them cold, by its own rule (at most a few times).
  /// Default: nothing, Done.
  virtual Completion complete(Eigen::VectorXd& x, const bvp::NewtonOptions& options, SolverSummary& summary) {
    (void)x;
    (void)options;
    (void)summary;
    return Completion::Done;
  }
  /// True and the reason if the bound input asks for what no shape of the robot gives (a pull of
  /// an inextensible tendon not shorter than its free length): the driver then returns the rest
  /// state as an infeasible answer without solving. Default: false.
  virtual bool impossible_input(std::string& why) const {
    (void)why;
    return false;
  }
  /// The tip position of tip_pose().
  bool tip_position(const Eigen::VectorXd& x, Vec3& tip) {
    Frame f;
    if (!tip_pose(x, f)) return false;
    tip = f.p;
    return true;
  }
  /// False if the unknowns x are singular coordinates of the shape, so that the answer's
  /// derivative cannot be taken through them (differential_kinematics.hpp leaves it out).
  virtual bool differentiable(const Eigen::VectorXd& x) const {
    (void)x;
    return true;
  }
  /// An upper bound of the backbone curvature (1/m) of the last extract(), if the model knows
  /// one without examining the frames (CC: its arcs); negative: unknown. Lets the geometry check
  /// skip shapes too gentle to show a finding.
  virtual double max_curvature() const { return -1.0; }
  /// The integrator's name for the summary ("rk4", "cvode", "none").
  virtual std::string integrator_name() const { return "none"; }
  /// For a loading path whose snap found no landing because this formulation's system cannot
  /// damp (bvp::ParameterizedSystem::set_damping): another formulation of the same model, bound
  /// to the same input, whose system can (VC: multiple shooting for single shooting); the path
  /// is then followed again in it (path_following.cpp). nullptr: none.
  virtual ModelProblem* damping_formulation() { return nullptr; }
  /// This formulation's unknowns x of the equilibrium whose unknowns in damping_formulation()
  /// are y (called only where damping_formulation() is not null).
  virtual void from_damping_formulation(const Eigen::VectorXd& y, Eigen::VectorXd& x) { x = y; }
};

}  // namespace tdcr

namespace tdcr::detail {
// The models' own spelling.
using ModelProblem = tdcr::ModelProblem;
using ColdStart = tdcr::ColdStart;
}  // namespace tdcr::detail
