/// @file vcref.hpp
/// @brief The VCref model (paper Section 6.2, Table 2; Gao et al. 2017): a Cosserat rod between
/// every pair of consecutive disks, tendons as straight chords between disk holes that apply
/// discrete forces at the disks, solved by multiple shooting. It is tdcr's reference model.
///
/// **Physics.** Disks are numbered j = 0..N (0 = base disk, fixed at the base frame; N = tip
/// disk). Every interval (disk j-1 -> disk j, one subsegment) is a free Cosserat rod
/// (cosserat::FreeRod: paper Eq. 2-3, 34-39, with shear and extension unless
/// `effects.shear_extension` is false, and the distributed backbone weight rho A g when
/// gravity is on). At every disk j the tendons apply the discrete wrench of
/// tendon::disk_wrench (Eq. 30-33), with the frictionless-disk condition Eq. 58 on pass-through
/// tendons when `effects.disk_normal_force == Removed` (terminating tendons always pull with their
/// full force, which reproduces the paper code's rule at the last disk of a segment and at the
/// tip). A disk's weight disk_mass * g acts at its centre; the tip force and moment (base frame)
/// act at the last disk. Disk equilibrium (Eq. 40-41):
///   n(s_j-) = n(s_j+) + F_j,   m(s_j-) = m(s_j+) + M_j,
/// where n, m are the rod's internal force and moment (base frame), F_j, M_j the tendon wrench
/// (moment about the disk centre) plus the disk weight, plus the tip wrench at j = N, where
/// n(s_N+) = m(s_N+) = 0.
///
/// **Formulation (multiple shooting, one shooting interval per subsegment).** Unknowns:
/// x_0 = (n_0, m_0), the internal wrench just distal of the base disk (the base pose is known),
/// and for every disk j = 1..N-1: x_j = (p_j, w_j, n_j, m_j), the disk pose and the internal
/// wrench just distal of it, with R_j = Rbar_j exp(w_j). Rbar_j is a fixed reference rotation
/// taken from the initial guess (the guessed disk rotations of a cold solve, the previous solution's disk
/// rotation for a warm start): w stays a small correction, away from the rotation-vector
/// singularity at |w| = 2 pi, for bends of any angle. 6 + 12 (N - 1) unknowns.
/// Residuals: interval j is integrated from disk j-1's state to s_j, giving the end state
/// (p^-, R^-, n^-, m^-). For j = 1..N-1: pose continuity p_j - p^- (3) and
/// vee(skew(R^-^T R_j)) (3; equals the rotation vector of the mismatch to first order and
/// vanishes exactly when R_j is the orthonormal polar factor of the integrated R^-), and disk
/// equilibrium n^- - n_j - F_j (3), m^- - m_j - M_j (3), where the tendon wrench uses the poses
/// of disks j-1, j, j+1 (disk N's pose is the integrated end of the last interval). Tip:
/// n^- - F_N - F_tip (3), m^- - M_N - M_tip (3). The Jacobian is block tridiagonal; it is
/// assembled in compressed sparse column form (bvp::SparsityPattern) by forward differences that
/// re-integrate only the intervals a perturbed unknown starts (position perturbations need no
/// integration: the free rod is translation invariant), about 9 integrations of every interval
/// per Jacobian. KINSOL solves the system with dense LU for small systems and KLU above
/// NewtonOptions::dense_size_limit unknowns (LinearSolverKind::Automatic), so the cost grows
/// linearly with the number of disks.
///
/// **Scaling.** Residuals: positions by 1/L (L = robot length), rotations by 1, forces by
/// 1/F_s with F_s = sum of tensions + |F_tip| + |M_tip|/L + total weight + 1e-3 N, moments by
/// 1/(F_s L). Unknowns alike.
///
/// **Initial guess.** Cold solves start from the constant-curvature arcs of the tendon moments
/// (VcrefOptions; the straight robot on request), warm starts from a previous Solution.
///
/// **Large external loads: cold solves load the robot from rest.** A soft robot under a large
/// tip force or its weight has several equilibria. A direct Newton solve from the cold guess can
/// converge, with a residual far below tolerance, to an equilibrium that is not the one reached
/// by loading the robot from rest. Two dimensionless loads, decided once in the constructor:
///   P   = L^2 (|W| + |F_tip|) / EI                     (load_parameter()),
///   P_c = L^2 max(0, -e_z . (F_tip + W)) / EI         (compression_parameter()),
/// L robot length, W total weight of backbone and disks, EI bending stiffness, e_z the base
/// axis (P_c: compression of the straight robot; a cantilever with a tip load buckles at
/// pi^2 / 4 = 2.47). If P > VcrefOptions::load_threshold (2) or P_c >
/// VcrefOptions::compression_threshold (2), a cold solve does no direct solve: it loads the robot
/// from rest by load continuation (every load scaled by lambda from 0, the first step
/// min(threshold / parameter), at most the continuation's default 0.25), each step warm-started.
/// Only with SolverOptions::continuation (off: the direct solve, as before). A warm start always
/// solves directly first (falling back on loading from rest if it fails). Tensions do not count:
/// the tendon chords are attached to the disks, so they can buckle the backbone only between
/// two disks, at ~pi^2 EI / h^2 (h disk spacing; 1.7 kN = 300 T_M on the paper robot); 4 x 30 T_M
/// leave the cold solve on the loading path (tests).
/// Measured (cold direct solve vs a 100-200-step warm-started loading path, tip
/// difference > 1e-4 m = "another branch"; the wrong answers are 0.04-0.92 m away):
///  - paper robot (n = 10), transverse tip forces 0.5-8 N in x or y, configurations 1, 2, 6
///    (P up to 19): all right; opposing tendons (T2, T4 at -y vs +y force, the case study's
///    configurations 6, 11): right up to P = 5.2, wrong from 5.9 (F = 2.5 N); T2 alone at 3 T_M
///    (270 deg) against +y: right at P = 3, wrong at 4;
///  - tip force (2, 0, -2) N (P = 6.7, P_c = 4.7): wrong for configurations 1, 2, 8, 16 (0.15-0.16
///    m off); x 0.5 (P = 3.3, P_c = 2.4): right; pure compression -e_z with a 1 mN imperfection:
///    right at P_c = 2.36, wrong from 2.59 (just past Euler buckling);
///  - case study scenario 2 (0.5 N planar or transverse, 16 configurations): f = 0.1 (P = 11.8):
///    7 of 32 wrong; f = 0.178 (P = 6.6): 1 of 32 (configuration 11 planar); f >= 0.316 (P <= 3.7):
///    all right;
///  - long soft robot under gravity (hard case 14): right up to 0.025 g (P = 21.7; from 13 on only
///    because the direct solve failed and continuation took over), wrong from 0.03 g (P = 26):
///    0.92 m off.
/// The thresholds keep a margin of 2 below the lowest wrong transverse case (4) and sit below
/// Euler's load for compression. With the rule every case above agrees with the loading path,
/// except: near-perfect columns beyond Euler's load (pure compression with a 1 mN imperfection,
/// or 0.5 T_M of tension against P_c = 4-5), where the continuation's coarse steps jump across
/// the bifurcation to the other (near-straight or mirrored) branch; and loading paths with a
/// fold (snap-through: tendons at 2-3 T_M against P = 4-5), where the fine path fails as well and
/// the solve reports non-convergence. Scenario 2 with the rule: all 288 solves on the loading
/// path (8 wrong before), median cold solve per stiffness 3-15 ms (before 4-30 ms: failed direct
/// solves cost more than loading from rest). Cost: 3-9 continuation steps (paper robot ~6 ms instead
/// of ~2 ms; hard case 14 at full gravity 84 ms); the paper case study without tip force and
/// scenario 2 for f >= 1 (P <= 1.2) keep the direct solve.
///
/// **Outputs.** disk_frames: base, every disk, tip last (the interior disk poses are the solved
/// unknowns; the tip pose is the end of the last interval, its rotation projected onto SO(3)).
/// backbone: one sample per disk: sample 0 is the base with (n_0, m_0) just distal of the base;
/// sample j >= 1 is disk j with the rod's internal wrench just proximal of the disk, n(s_j-),
/// m(s_j-). tendon_displacements: from the chord lengths between the holes of consecutive disks
/// (tendon::chord_displacements with the actuation's convention). unknowns: x as above; a warm
/// start takes the poses and wrenches from the previous unknowns and its disk rotations as Rbar.
///
/// Input: tendon tensions (Actuation::Kind::Tensions). Integrator: SolverOptions::integrator
/// (RK4 with rk4_steps steps per interval, or CVODE).
#pragma once

#include <memory>

#include "tdcr/bvp/residual_system.hpp"
#include "tdcr/core/robot.hpp"
#include "tdcr/models/legacy_model.hpp"

namespace tdcr {

/// @brief Model-specific settings of VCref (beyond the scene's SolverOptions).
struct VcrefOptions {
  /// @brief Initial guess of a cold solve (no warm start).
  enum class InitialGuess {
    /// Disk poses on the constant-curvature arcs of the tendon moments, u = sum_k T_k
    /// (e_z x r_k) / EI over the tendons running through each segment (the CC model's statics,
    /// paper Eq. 8), wrenches from the disk equilibria on that shape. Default: on the paper's
    /// 16 configurations at n = 10 it needs 28 Newton iterations in total against 131 and never
    /// fails where the straight guess fails twice (configurations 6 and 11).
    ConstantCurvature,
    /// The straight robot (as the paper's code), with the straight robot's static wrenches.
    Straight
  };
  InitialGuess initial_guess = InitialGuess::ConstantCurvature;  ///< See InitialGuess.
  /// Cold solves load the robot from rest when VcrefModel::load_parameter() exceeds this (see
  /// the file comment, "Large external loads"). Infinity: never for this reason.
  double load_threshold = 2.0;
  /// Cold solves load the robot from rest when VcrefModel::compression_parameter() exceeds this
  /// (Euler buckling of a cantilever under a tip load: pi^2 / 4 = 2.47). Infinity: never.
  double compression_threshold = 2.0;
};

/// @brief The VCref model of one scene: immutable, built from a validated tension-driven scene.
/// All mutable memory of a solve (integrator, Newton solver with its KLU factorisation, the
/// end states of the intervals, Jacobian scratch) lives in the workspace from make_workspace(),
/// which can be reused across solves.
class VcrefModel final : public LegacyStaticModel {
 public:
  /// @brief Validate the scene and decide once which effects to evaluate (active tendons with
  /// nonzero tension, tip wrench, backbone and disk weights). Throws InputError if the scene is
  /// invalid or its actuation is not given as tensions.
  explicit VcrefModel(const Scene& scene, const VcrefOptions& options = VcrefOptions());
  ModelKind kind() const override { return ModelKind::VCref; }
  const Scene& scene() const override { return scene_; }
  std::unique_ptr<LegacyWorkspace> make_workspace() const override;
  /// @brief Solve by multiple shooting. `warm_start`: a previous VCref Solution of a robot with
  /// the same disks (its unknowns and disk rotations are the initial guess); otherwise (or if
  /// the sizes do not match) VcrefOptions::initial_guess. With SolverOptions::continuation, a
  /// cold solve under large external loads (loads_from_rest()) loads the robot from rest instead of
  /// solving directly, and a failed direct solve is retried by ramping the tensions and loads
  /// from rest. Never throws for a non-convergent solve.
  Solution solve(LegacyWorkspace& workspace, const Solution* warm_start = nullptr) const override;

  /// @brief The dimensionless external load L^2 (|W| + |F_tip|) / EI (L: robot length, W: total
  /// weight of backbone and disks, F_tip: tip force, EI: bending stiffness; tensions do not
  /// count). Decides, with compression_parameter(), whether a cold solve loads from rest.
  double load_parameter() const;
  /// @brief The axial compression of the straight robot by its external loads,
  /// L^2 max(0, -e_z . (F_tip + W)) / EI (e_z: the base axis); Euler buckling of the cantilever
  /// under a tip force at pi^2 / 4.
  double compression_parameter() const;
  /// @brief True if a cold solve (no warm start) loads the robot from rest (decided once in the
  /// constructor: load_parameter() > VcrefOptions::load_threshold or compression_parameter() >
  /// VcrefOptions::compression_threshold; only with SolverOptions::continuation).
  bool loads_from_rest() const;
  /// @brief Number of unknowns (and residuals): 6 + 12 (N - 1), N = total disks.
  int unknowns() const;
  /// @brief Structural nonzeros of the block-tridiagonal Jacobian (grows linearly with N).
  int jacobian_nonzeros() const;

  /// @brief Diagnostics: the assembled sparse Jacobian against central differences of the
  /// residual (bvp::check_jacobian), at the initial guess of `at` (a previous Solution, as for a
  /// warm start) or the cold initial guess, each unknown x_i moved by
  /// perturbation * sin(1 + i) * (typical magnitude of x_i) so the check can leave the guess.
  bvp::JacobianCheck check_jacobian(LegacyWorkspace& workspace, const Solution* at = nullptr,
                                    double perturbation = 0.0) const;

  /// @brief Internal data shared with the workspace (implementation detail).
  struct Data;

 private:
  Scene scene_;
  VcrefOptions options_;
  std::shared_ptr<const Data> data_;
};

}  // namespace tdcr
