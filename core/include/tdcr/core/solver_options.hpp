/// @file solver_options.hpp
/// @brief Options for the numerical solution of a static model (Ceres-style: a plain struct
/// that can validate itself).
#pragma once

#include <string>
#include <vector>

namespace tdcr {

/// @brief Integrator for the Cosserat-rod ODEs (VC, VCref).
enum class IntegratorKind {
  AccuracyDrivenRK4,  ///< "rk4" (default): classical RK4 on a mesh refined until the estimated tip
                      ///< error is within SolverOptions::tip_tolerance; allocation free.
  FixedStepRK4,       ///< "rk4_fixed": classical RK4 on the mesh of rk4_steps and rk4_max_step.
  Cvode               ///< "cvode": SUNDIALS CVODE, Adams, error controlled: the reference integrator.
};

/// @brief True for both RK4 integrators (the accuracy-driven one solves on RK4 meshes too).
inline bool is_rk4(IntegratorKind k) { return k != IntegratorKind::Cvode; }

/// @brief Linear solver used inside KINSOL's Newton iteration.
enum class LinearSolverKind {
  Automatic,  ///< Dense LU up to bvp::NewtonOptions::dense_size_limit (200) unknowns; KLU
              ///< above if the system declares a sparsity pattern (VCref), dense otherwise.
  Dense,      ///< SUNDIALS dense LU.
  SparseKLU   ///< SUNDIALS KLU on a compressed-sparse-column Jacobian.
};

/// @brief When a solve decides the stability of its answer (SolverOptions::stability; scene key
/// `solver.stability`: `"auto"`, `true`, `false`).
enum class StabilityCheck {
  Automatic,  ///< Where it matters: an answer reached by a loading path (from rest, a snap, a warm
              ///< start's input path, a displacement solve's path), in every model; under external
              ///< loads every VCref answer. Not another direct or warm solve (under loads within the
              ///< direct-solve bounds it lands on the branch connected to rest).
  Always,     ///< Every converged answer.
  Never       ///< No answer (Solution::stability says "not checked").
};

/// @brief Numerical settings of a static solve.
struct SolverOptions {
  /// Accuracy of the answer's tip position (m): one option that moves both the integration mesh
  /// (VC and VCref with the default integrator "rk4": the mesh is refined until the Richardson
  /// estimate of the tip error is at most this) and Newton's tolerance (every model: unless
  /// function_tolerance is set, it is kNewtonPerTipTolerance times this over the robot's length).
  /// 0 (default): kTipToleranceOverLength times the robot's length, 1e-8 m on the paper robot
  /// (0.1 m), the paper code's own integration error at n >= 10. resolved() turns 0 into the
  /// value.
  double tip_tolerance = 0.0;
  /// Default tip tolerance over the robot's length (tip_tolerance 0).
  static constexpr double kTipToleranceOverLength = 1e-7;
  /// Newton's scaled residual tolerance per unit of tip tolerance over the robot's length
  /// (function_tolerance 0). On the 60 loaded cases of bench_loaded a residual tolerance of
  /// 1e-8 left CCsub's tip within 3.2e-9 m and PRB's within 4.5e-9 m of their tight references
  /// (0.1 m robot): a hundredth of tip_tolerance / length keeps Newton's share of the tip error
  /// near a twentieth of the tolerance, below the integration mesh's share.
  static constexpr double kNewtonPerTipTolerance = 1e-2;
  /// Smallest tied Newton tolerance: a tip tolerance far below what RK4 can reach must not take
  /// Newton to the rounding floor of the residual (near 1e-15, kMinFunctionTolerance), where
  /// solves fail; an explicit function_tolerance may still go there.
  static constexpr double kMinTiedFunctionTolerance = 1e-13;
  /// Newton stops when the scaled residual max-norm is below this (KINSOL fnormtol). 0 (default):
  /// tied to tip_tolerance (kNewtonPerTipTolerance tip_tolerance / robot length: 1e-9 on the
  /// paper robot); resolved() turns 0 into the value.
  double function_tolerance = 0.0;
  /// KINSOL scaled step tolerance.
  double step_tolerance = 1e-14;
  int max_iterations = 200;  ///< Newton iterations per solve.
  /// Integrator of the Cosserat-rod ODEs (VC, VCref; the other models integrate nothing).
  /// The default, accuracy-driven RK4, starts on a coarse mesh (kFirstMeshRk4Steps per disk
  /// interval, steps of at most kFirstMeshRk4MaxStep) and refines it (steps per interval doubled
  /// and the longest step halved, once or as often as the last estimate asks for) until the
  /// Richardson estimate of its tip position error, from the last two meshes, is at most
  /// tip_tolerance; each finer solve is warm-started from the coarser answer and its Jacobian. A
  /// warm-started solve (a trajectory's step) solves on the coarsest mesh that its warm start's
  /// estimate, scaled by RK4's fourth-order law, predicts within kPredictedToleranceShare of the
  /// tolerance, and keeps that prediction as its estimate (SolverSummary::tip_error_estimate_age)
  /// for at most kMaxEstimateAge consecutive warm solves while the tip moves less than
  /// kMaxPredictedTipMove of the robot's length per solve; otherwise it measures the estimate
  /// again (one Newton step on the neighbouring mesh) and refines if it is above the tolerance.
  /// SolverSummary::tip_error_estimate, rk4_refinements and the mesh report it; a solve that
  /// cannot meet the tolerance within kMaxRk4Halvings halvings of the first mesh is reported as
  /// not converged. The estimate is an estimate, not a bound: on the 60 loaded cases of
  /// bench_loaded it was 0.90-1.15 times the true tip error.
  IntegratorKind integrator = IntegratorKind::AccuracyDrivenRK4;
  /// Steps per disk interval of the accuracy-driven RK4's first mesh.
  static constexpr int kFirstMeshRk4Steps = 1;
  /// Longest step of the accuracy-driven RK4's first mesh (m).
  static constexpr double kFirstMeshRk4MaxStep = 8e-3;
  /// Most halvings of the first mesh's steps in an accuracy-driven RK4 solve: the finest mesh has
  /// 64 times its steps.
  static constexpr int kMaxRk4Halvings = 6;
  /// Accuracy-driven RK4, warm-started solves: a predicted tip error is used only up to this
  /// share of tip_tolerance (a factor 2 for the prediction's own error).
  static constexpr double kPredictedToleranceShare = 0.5;
  /// Accuracy-driven RK4, warm-started solves: most consecutive solves that predict their tip
  /// error from an earlier measured estimate; the next one measures it.
  static constexpr int kMaxEstimateAge = 8;
  /// Accuracy-driven RK4, warm-started solves: a solve whose tip moved more than this share of
  /// the robot's length from its warm start's measures its estimate.
  static constexpr double kMaxPredictedTipMove = 0.01;
  /// Fixed-mesh RK4 (integrator "rk4_fixed"): minimum RK4 steps per disk interval (one
  /// subsegment, length L_i / n_i), for VC and VCref alike; rk4_max_step may ask for more.
  int rk4_steps = 8;
  /// Fixed-mesh RK4: longest RK4 step (m); a disk interval longer than rk4_steps * rk4_max_step
  /// takes more steps. With 8 steps and 1 mm the VCref tip of the paper robot (configuration 8)
  /// is within 5e-8 m of CVODE at rtol 1e-12 for n = 1, 7e-9 m for n = 2 and 7e-10 m for n = 10.
  double rk4_max_step = 1e-3;
  double cvode_rtol = 1e-8;   ///< CVODE relative tolerance.
  double cvode_atol = 1e-10;  ///< CVODE absolute tolerance.
  /// Linear solver inside Newton (VC, VCref; CCsub and PRB always use dense LU, CC solves no
  /// system). SparseKLU on a system without a sparsity pattern (VC) factorises a dense pattern.
  LinearSolverKind linear_solver = LinearSolverKind::Automatic;
  /// Automatic load continuation: if a direct solve fails, every static model (CCsub, PRB, VC,
  /// VCref) solves again from the unloaded robot, raising a load factor on all tensions, the tip
  /// wrench and gravity from 0 to 1 in adaptive steps (bvp::continuation), each warm-started
  /// from the last converged one. The summary reports continuation_steps; the solve is reported
  /// converged only if the full load converged, otherwise the message gives the load fraction
  /// reached. On by default (set false to see direct failures); CC has no iteration and ignores it.
  bool continuation = true;
  /// Bound on continuation work: at most this many Newton solves (converged or failed steps).
  int max_continuation_steps = 64;
  /// VC and VCref with RK4, cold solves that follow the loading path from rest: follow it on a
  /// coarse mesh (kCoarsePathRk4Steps per disk interval, steps of at most kCoarsePathRk4MaxStep;
  /// each setting never finer than the requested one) and solve the answer on the requested mesh
  /// (rk4_steps, rk4_max_step) from its end, a
  /// warm-started Newton solve. The path only carries the solve to the loading branch; the
  /// answer has the requested mesh's accuracy. If the coarse path or the final solve fails, the
  /// whole path is followed again on the requested mesh. Path events (folds, snaps) are those of
  /// the coarse path. For integrator "rk4_fixed" only, and only when its mesh is finer than the
  /// coarse one (the accuracy-driven "rk4" starts coarser anyway; CVODE has no mesh).
  bool coarse_loading_path = true;
  /// RK4 steps per disk interval of a coarse loading path (coarse_loading_path).
  static constexpr int kCoarsePathRk4Steps = 2;
  /// Longest RK4 step of a coarse loading path (m; coarse_loading_path).
  static constexpr double kCoarsePathRk4MaxStep = 4e-3;
  /// Which converged answers get their stability decided (Solution::stability): VC by the
  /// conjugate-point test of the fixed-free rod, CCsub and PRB by the eigenvalues of the reduced
  /// stiffness, VCref by its reduced stiffness in the disk poses; CC reports "undetermined"
  /// (docs/models.md, "Stability"). With contacts: CCsub and PRB on the tangent space of the
  /// active rigid contacts, or with the compliant contacts' stiffness (docs/contact.md,
  /// "Stability with contact"); VC and VCref report "undetermined". Automatic by default (StabilityCheck::Automatic): answers
  /// reached by a loading path are tested, and under external loads the cold direct answers of
  /// VCref (+17 % on its median loaded solve, `bench_loaded`, 2026-11-27), CCsub and PRB (their
  /// sufficient test: 14 % and 22 %); warm steps that follow no path (a trajectory: the test would
  /// add 92 % to VCref's loaded step) and other direct solves are not (VC's test adds 65-100 %, over
  /// the 25 % budget). An untested Solution's stability says "not checked"
  /// (kStabilityNotChecked); true tests every answer.
  StabilityCheck stability = StabilityCheck::Automatic;
  /// Differential kinematics of every converged answer (Solution::tip_jacobian,
  /// Solution::tip_compliance) by the implicit function theorem on the converged system: no
  /// extra full solves (docs/models.md, "Differential kinematics").
  bool differential_kinematics = false;
  /// A warm-started solve may begin from the previous solve's Jacobian, where the model keeps it
  /// (CCsub, PRB, VC, VCref; modified Newton, a fresh Jacobian when the residual stops falling
  /// fast, and none after a slow solve): more, much cheaper iterations along a trajectory. The
  /// answer then depends on the workspace's last solve within function_tolerance. It also lets
  /// Newton freeze its Jacobian near the solution (bvp::NewtonOptions::freeze_jacobian_below):
  /// CCsub's cold direct solves and every continuation corrector. False: every solve starts with
  /// a fresh Jacobian and iterates exact Newton throughout (the displacement-input solve does
  /// this for its inner tension solves, whose differences must not carry that history).
  bool reuse_jacobian = true;
  /// A warm start from the workspace's last answer starts from the secant through its last two
  /// answers when the input moves on along (within 10 % of) the line of the last input step, by
  /// the same or up to twice its length: x1 + alpha (x1 - x0). Along a trajectory the guess is
  /// then second-order accurate and Newton saves about one iteration per step. If the direct
  /// solve from the prediction fails, it is retried from the previous answer itself. The answer
  /// then depends on the workspace's history within function_tolerance, as with reuse_jacobian.
  bool extrapolate_warm_starts = true;

  /// @name Bounds of the numeric options
  /// validate() accepts each numeric option within these bounds (docs/scene-file.md lists them).
  /// Each is far outside what a solve needs; it rejects values that make a solve meaningless,
  /// fail always, or run for minutes (`rk4_steps` 1e8 did). Times below: `tdcr solve` of
  /// examples/paper_robot_vc.json ("vc") and examples/paper_robot_tip_force.json ("tip force")
  /// with the option at its bound, Release build, 2-core AMD EPYC, 2026-11-26.
  ///@{

  /// Most RK4 steps per disk interval (rk4_steps): RK4's error falls as h^4, so 4096 steps, 512
  /// times the default 8, would be 7e10 times more accurate than the default mesh, whose VCref
  /// tip on the paper robot is already within 7e-10 m of CVODE at n = 10 (rk4_max_step). At
  /// 4096: VC 0.11 s ("vc") and 0.84 s ("tip force"), VCref 0.43 s and 0.57 s.
  static constexpr int kMaxRk4Steps = 4096;
  /// Smallest longest RK4 step (m; rk4_max_step): 1 um, so that a 5 mm disk interval (the
  /// paper robot at n = 10) takes at most 5000 steps, as many as kMaxRk4Steps. At 1 um: VC
  /// 0.14 s ("vc") and 1.2 s ("tip force"), VCref 0.43 s and 0.43 s.
  static constexpr double kMinRk4MaxStep = 1e-6;
  /// Bounds of the Newton residual tolerance (function_tolerance, dimensionless: residuals are
  /// scaled to order 1). Near 1e-15 the residual is rounding noise: at 1e-15 VCref on "vc" ends
  /// as line_search_failed (VC converges), at 1e-16 both fail on "tip force" (KIN_STEP_LT_STPTOL
  /// with |F| = 5.6e-16 and 1.2e-15). Above 1e-2 an "equilibrium" leaves a percent of the
  /// scaled forces unbalanced.
  static constexpr double kMinFunctionTolerance = 1e-15;
  static constexpr double kMaxFunctionTolerance = 1e-2;  ///< @copydoc kMinFunctionTolerance
  /// Bounds of the scaled step tolerance (step_tolerance): a step stop counts as converged only
  /// if function_tolerance holds too, so a small value cannot make a wrong answer or a hang
  /// (max_iterations ends it); a relative step below 1e-16 changes no digit of a double, and
  /// 1e-20 leaves room for unknowns scaled far from 1. Above 1e-2 Newton would stop on a
  /// percent-sized step.
  static constexpr double kMinStepTolerance = 1e-20;
  static constexpr double kMaxStepTolerance = 1e-2;  ///< @copydoc kMinStepTolerance
  /// Bounds of CVODE's relative tolerance (cvode_rtol): CVODE gives up near the unit roundoff
  /// (2.2e-16): at 1e-16 every solve of "tip force" fails at 0 % of the load (the residual
  /// cannot be evaluated); 1e-15 still converges, 1e-14 keeps a decade from it. At 1e-14 with
  /// cvode_atol 1e-20: VC 0.03 s, VCref 0.12 s ("tip force"). Above 1e-2 it is no integration.
  static constexpr double kMinCvodeRtol = 1e-14;
  static constexpr double kMaxCvodeRtol = 1e-2;  ///< @copydoc kMinCvodeRtol
  /// Bounds of CVODE's absolute tolerance (cvode_atol, in state units: m, N, N m and rotation
  /// entries, of order 1e-3 to 1 on a laboratory robot): below 1e-20 no component is resolved
  /// better (rtol governs), above 1e-2 a centimetre or a hundredth of a newton is ignored.
  static constexpr double kMinCvodeAtol = 1e-20;
  static constexpr double kMaxCvodeAtol = 1e-2;  ///< @copydoc kMinCvodeAtol
  /// Bounds of the tip tolerance (m; tip_tolerance when not 0): the
  /// smallest estimate reached on "tip force" from rk4_steps 1, rk4_max_step 8e-3 is 7.0e-15 m
  /// (VC) and 7.2e-15 m (VCref), after two refinements, in under 2 ms. A tolerance below what is
  /// reachable is harmless: the solve ends after kMaxRk4Halvings halvings as not converged and
  /// says so (test_rk4_tolerance asks for 1e-18 m to see this). Below 1e-18 m, under a tenth of
  /// the spacing of doubles at 0.1 m (1.4e-17 m), no value means anything else. Above 1 cm every
  /// mesh passes.
  static constexpr double kMinTipTolerance = 1e-18;
  static constexpr double kMaxTipTolerance = 1e-2;  ///< @copydoc kMinTipTolerance
  /// Most Newton iterations per solve (max_iterations): 5 times the default 200; a Newton solve
  /// that has not converged in 1000 iterations will not.
  static constexpr int kMaxIterations = 1000;
  /// Most continuation steps (max_continuation_steps): about 16 times the default 64. With both
  /// bounds, the longest failing solves found ("vc" with a helical tendon of 1e6 turns, or disks
  /// of 1e9 kg under gravity) end within 3 s: VC 1000 continuation steps, 5264 iterations, 3.0 s;
  /// PRB 1000 steps, 1.6 s.
  static constexpr int kMaxContinuationSteps = 1000;
  ///@}

  /// @brief Throws InputError (field `solver.<name>`, the value, and the allowed range) on a
  /// numeric option outside its bounds above, or not finite (rk4_max_step may be +infinity:
  /// exactly rk4_steps steps per interval). tip_tolerance and function_tolerance may be 0 (tied
  /// to the robot, see resolved()).
  void validate() const;

  /// @brief These options with tip_tolerance and function_tolerance made concrete for a robot of
  /// total length `robot_length` (m): 0 is replaced by the default tied to the length (tip
  /// tolerance) and to the tip tolerance (function tolerance). Idempotent; the solve entry calls it.
  SolverOptions resolved(double robot_length) const;
};

/// @brief Name of an integrator as used in scene files ("rk4", "rk4_fixed", "cvode").
std::string to_string(IntegratorKind k);
/// @brief The integrator named `name`: one of integrator_names(), as to_string() writes them. The
/// one parser of integrator names (scene files, the CLI's `--integrator`, Python).
/// @param name The name, e.g. "cvode".
/// @param field Where it was given, for the error: `solver.integrator`, `--integrator`, ...
/// @throws InputError naming `field` and the quoted `name`, listing the accepted names.
IntegratorKind parse_integrator_kind(const std::string& name, const std::string& field);
/// @brief The integrator names parse_integrator_kind() accepts, in the order of IntegratorKind.
const std::vector<std::string>& integrator_names();
/// @brief Why a fixed-mesh setting (rk4_steps, rk4_max_step) is refused with `integrator`.
std::string fixed_mesh_only(IntegratorKind integrator);
/// @brief Name of a linear solver as used in scene files ("auto", "dense", "klu").
std::string to_string(LinearSolverKind k);
/// @brief Name of a stability rule ("auto", "always", "never"; scene files write `"auto"`, `true`,
/// `false`).
std::string to_string(StabilityCheck k);

}  // namespace tdcr
