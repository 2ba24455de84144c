/// @file vc.hpp
/// @brief The VC model: a Cosserat rod with fully constrained tendons (paper Sections 5.1.1 and
/// 5.2.1, Eq. 2-3, 24-29, 34-41; Rucker & Webster 2011), solved by single shooting with KINSOL,
/// or by multiple shooting on long, soft robots.
///
/// **What it computes.** The backbone is a Cosserat rod (with shear and extension, or an
/// inextensible, unshearable Kirchhoff rod if `effects.shear_extension` is off). The tendons are
/// fully constrained: tendon k runs at the constant body-frame offset r_k from the backbone, so
/// its path is p_k = p + R r_k, and it applies to the backbone a continuous load. The model
/// returns the shape (disk frames at the disk arc lengths), the rod's internal force and moment,
/// and the tendon displacements at the base.
///
/// **Equations (all vectors of the state in the base frame).** State: p, R, n, m (the rod's own
/// internal force and moment, cosserat_rod.hpp). Strains: u = Kbt^-1 R^T m,
/// v = Kse^-1 R^T n + e_z (v = e_z without shear/extension), Kse = diag(GA, GA, EA),
/// Kbt = diag(EI, EI, GJ). A tendon with tension T_k > 0 through the current segment has body
/// tangent q_k = v + u x r_k (Eq. 24-25) and applies the distributed force
/// f_k = T_k d/ds(R q_k / |q_k|) (the magnitude of Eq. 28; it pulls the backbone towards the
/// centre of curvature) and the moment l_k = (R r_k) x f_k (Eq. 29). In the body frame,
/// f_k^b = (T_k / |q_k|) (u x q_k + P_k (v_s + u_s x r_k)), P_k = I - t_k t_k^T, which is
/// linear in (v_s, u_s); body-frame equilibrium with the constitutive law gives the symmetric
/// positive definite 6x6 system (3x3 without shear/extension)
///   [Kse + sum A_k,        -sum A_k [r_k]x          ] [v_s]   [-u x n_b - sum a_k - f_e^b        ]
///   [sum [r_k]x A_k,  Kbt - sum [r_k]x A_k [r_k]x  ] [u_s] = [-u x m_b - v x n_b - sum r_k x a_k ]
/// with A_k = T_k P_k / |q_k|, a_k = T_k (u x q_k) / |q_k|, n_b = R^T n, m_b = R^T m. Then
/// p' = R v, R' = R [u]x, n' = R (Kse v_s + u x n_b) (= -(sum f_k + f_e)), m' = R (Kbt u_s +
/// u x m_b) (= -p' x n - sum l_k); without shear/extension n' = -(R sum f_k^b + f_e).
/// f_e = rho A g is the backbone weight (only if the scene has gravity and backbone mass).
/// A segment without tensioned tendons uses the free-rod right-hand side (no linear solve).
///
/// **Point loads (Eq. 40-41).** Integrating base to tip, at the end of segment i every tendon
/// terminating there with T_k > 0 applies F_k = -T_k R t_k (towards the base; t_k with u, v just
/// proximal of the end) at p + R r_k: n(l+) = n(l-) - sum F_k, m(l+) = m(l-) - sum (R r_k) x F_k.
/// The weight m_d g of every disk j >= 1 acts at its backbone point: n(s_j+) = n(s_j-) - m_d g.
///
/// **Shooting problem.** Unknowns: n(0), m(0) (6, base frame). Residuals: n(L+) - F_tip and
/// m(L+) - M_tip, where the tip force and moment are given in the base frame and act at the
/// backbone centre of the tip. Residuals are scaled by a force scale
/// F_s = sum T + |F_tip| + |W| + 1e-3 N and a moment scale
/// M_s = sum T max|r_k| + (|F_tip| + |W|) L + |M_tip| + 1e-3 N * L, so every scaled residual is
/// O(1). KINSOL (dense, line search) solves it with a forward-difference Jacobian (6 extra shots;
/// relative step sqrt(eps) with RK4, sqrt(cvode_rtol) with CVODE whose output is only piecewise
/// smooth in the unknowns). By global equilibrium the solution lies within a scaled distance of
/// about sqrt(6) of the origin, so Newton steps are bounded to scaled length 1 (KINSOL
/// mxnewtstep): longer steps overshoot into coiled shapes. A failed cold start is retried once
/// from the other initial guess (VcInitialGuess), then, with `solver.continuation`, by a load
/// ramp.
///
/// **Multiple shooting (long, soft robots).** Single shooting integrates 0.6 m of a soft rod from
/// the base: the tip depends on n(0), m(0) like exp(L sqrt(N / EI)) (N the tension of the
/// backbone), and a change of m(0) by the moment scale bends the rod by M_s L / EI radians. On the
/// long soft robot under gravity of the hard-case suite (3 x 0.2 m, E = 1e9 Pa, steel, gravity
/// across: L^2 (|W| + |F_tip|) / EI = 869) single shooting converged, even from VCref's base
/// wrench and along a 50-step warm-started loading path, to coiled equilibria (tip y = -0.085 m
/// instead of the hanging -0.588 m): a genuine equilibrium, the wrong branch. Multiple shooting
/// removes the sensitivity: one interval per disk interval, unknowns = the 18 rod states (p, R
/// column-major, n, m) at every interval start (just distal of the disk's point loads),
/// residuals = p(0), R(0) - I, the tip wrench, and at every inner disk i the jump
/// y_i^+ - J_i(y_{i-1}^-) (J_i: the point loads of disk i); bvp::ShootingSystem gives the
/// block-banded finite-difference Jacobian, KLU solves it. A cold multiple-shooting solve does not
/// start from the straight robot (from there, too, Newton lands on other branches under large
/// loads) but loads the robot from rest (load continuation, first step threshold / tension
/// parameter), which follows the equilibrium connected to the unloaded robot.
///
/// **Which formulation (VcOptions::formulation, default Automatic).** The tension parameter
/// L^2 (|W| + |F_tip|) / EI (W: total weight, EI: bending stiffness, L: robot length) measures both
/// the sensitivity and the nonlinearity (the linear deflection in units of L); tendon tensions do
/// not count (fully constrained tendons compress the backbone without buckling it). Multiple
/// shooting is used when it exceeds VcOptions::multiple_shooting_threshold = 10. Measured (cold
/// solves vs fine loading paths): single shooting found the loaded-from-rest equilibrium up to 9.4
/// (paper robot, 4 N tip force) and lost it from 13 on (4 N tip force with 4 N compression; 8 N:
/// 0.12 m off; gravity on the soft robot at 3 %: 26). Multiple shooting costs ~30 ms on the paper
/// robot (n = 10) against 0.28 ms for single shooting, so the paper robot keeps single shooting
/// for every tendon load and tip forces below ~4 N.
///
/// **Kinks (VcOptions::kink_forces, default on; an addition to the paper's formulation).** Where
/// point loads make n or m jump (tendon terminations, disk weights), u and v jump, and every
/// tensioned tendon continuing past that disk changes direction: it pulls on the backbone with
/// T_k R (t_k+ - t_k-) at p + R r_k (the integral of f_k over the jump). This point load is
/// applied (fixed-point iteration, as t_k+ depends on the wrench after the jump). Without it the
/// robot's global force and moment balance fails whenever torsion or shear jumps at a segment
/// end; it changes nothing for tendon-only loads (t_k = e_z on both sides).
///
/// **Integration.** Segment by segment and disk interval by disk interval (the rod stops at every
/// disk to record its frame and apply disk weights), with RK4 (`solver.rk4_steps` steps per disk
/// interval) or CVODE (`solver.cvode_rtol`, `solver.cvode_atol`).
///
/// **Tendon displacements.** The fully constrained tendon length is the integral of |p_k'| =
/// |q_k| along every segment the tendon runs through (paper Eq. 56), integrated as extra states
/// in a final pass at the solution (with CVODE they are part of every shot, so the reported
/// shape is exactly the converged one). Displacement = straight length (arc length to its end
/// disk) - length, positive when pulled; with `Actuation::DisplacementConvention::PerSegment`
/// only the tendon's own segment counts.
///
/// **Units.** SI: m, N, N m, rad.
#pragma once

#include <memory>

#include <Eigen/Core>

#include "tdcr/models/legacy_model.hpp"

namespace tdcr {

/// @brief Initial guess of the shooting unknowns n(0), m(0) for a cold solve.
enum class VcInitialGuess {
  /// The base reaction of the straight robot under the scene's loads:
  /// n(0) = F_tip + W - (sum T) e_z, m(0) = M_tip + (L e_z) x F_tip + weight moments +
  /// sum T_k (e_z x r_k). Exact when only tip-to-base tendons act on a one-segment robot at small
  /// bending; the default (fewer iterations than zeros on the paper's case study).
  Equilibrium,
  /// n(0) = m(0) = 0: the paper code's straight initial guess.
  Zero
};

/// @brief How the VC boundary value problem is discretised.
enum class VcFormulation {
  /// Single shooting unless the robot is long and soft for its loads (see VcModel::tension_parameter):
  /// multiple shooting when L^2 (|W| + |F_tip|) / EI > VcOptions::multiple_shooting_threshold.
  Automatic,
  /// Single shooting: 6 unknowns n(0), m(0) (the paper code's formulation).
  SingleShooting,
  /// Multiple shooting: one interval per disk interval, 18 unknowns (p, R, n, m) per interval.
  MultipleShooting
};

/// @brief Options of the VC model beyond the scene's SolverOptions.
struct VcOptions {
  VcInitialGuess initial_guess = VcInitialGuess::Equilibrium;  ///< Cold-start guess.
  /// Apply the point force of every tensioned tendon that passes a disk where point loads
  /// (tendon terminations, disk weights) make the strains jump: its fully constrained path has a
  /// kink there and pulls with T_k R (t_k+ - t_k-). Without it (the paper code's VC, Rucker &
  /// Webster 2011 apply only termination forces) the global force and moment balance of the robot
  /// is violated whenever torsion or shear jumps at a segment end (e.g. 1.5e-3 N of 10 N with
  /// tip loads on a 3-segment robot). Default on; off reproduces the paper code's formulation.
  bool kink_forces = true;
  VcFormulation formulation = VcFormulation::Automatic;  ///< Single or multiple shooting.
  /// Automatic formulation: multiple shooting when VcModel::tension_parameter() exceeds this.
  double multiple_shooting_threshold = 10.0;
};

/// @brief Mutable memory of VC solves: integrators, the KINSOL workspace and the shooting state.
/// Reuse it across solves of the same model (no allocation after the first solve).
class VcWorkspace final : public LegacyWorkspace {
 public:
  ~VcWorkspace() override;
  /// @brief Right-hand side evaluations of the rod ODE since construction (a cost measure).
  long rhs_evaluations() const;
  struct Impl;                  ///< Private (defined in models/vc).
  std::unique_ptr<Impl> impl;   ///< Private state.
};

/// @brief The VC model of one scene (model "vc"). Immutable; solve() is const.
class VcModel final : public LegacyStaticModel {
 public:
  /// @brief Validate the scene and decide once which effects are simulated.
  /// Throws InputError on an invalid scene or on a displacement actuation (VC is tension driven).
  explicit VcModel(const Scene& scene, VcOptions options = {});
  ~VcModel() override;
  ModelKind kind() const override { return ModelKind::VC; }
  const Scene& scene() const override { return scene_; }
  /// @brief A fresh VcWorkspace.
  std::unique_ptr<LegacyWorkspace> make_workspace() const override;
  /// @brief Solve by single or multiple shooting (uses_multiple_shooting()). `warm_start`: any
  /// previous Solution of a robot with the same disks. Single shooting starts from the base
  /// reaction of the previous shape under this scene's loads (n(0) = F_tip + W - sum T_k t_k(0),
  /// m(0) = M_tip + p_tip x F_tip + weight moments of the previous disk positions and backbone +
  /// sum T_k t_k(0) x r_k, t_k(0) from the previous base strains): exact up to the shape change,
  /// hence better than the previous n(0), m(0), which belong to other loads (bench_case_study
  /// warmstart: 2.0 Newton iterations warm vs 2.1 cold, was 2.9 warm). Multiple shooting starts
  /// from the previous unknowns (same size) or the previous disk states (backbone samples).
  /// With `solver.continuation`, a failed direct solve is retried by ramping tensions and loads
  /// (each step warm-started); a cold multiple-shooting solve always loads from rest.
  /// Never throws for a non-convergent solve: the summary says so (and frames, if the last
  /// iterate can be integrated, are those of the last iterate).
  Solution solve(LegacyWorkspace& workspace, const Solution* warm_start = nullptr) const override;

  /// @brief The cold-start guess of (n(0), m(0)) selected by `guess` (base frame, N and N m).
  Eigen::Matrix<double, 6, 1> initial_guess(VcInitialGuess guess) const;
  /// @brief One shot: integrate from the base with unknowns x = (n(0), m(0)) and return the
  /// unscaled tip residual (n(L+) - F_tip, m(L+) - M_tip) in `residual`. False if the
  /// integration failed. For tests and diagnostics.
  bool shoot(VcWorkspace& workspace, const Eigen::Matrix<double, 6, 1>& x,
             Eigen::Matrix<double, 6, 1>& residual) const;
  /// @brief Residual scale factors (1/F_s for the force rows, 1/M_s for the moment rows).
  Eigen::Matrix<double, 6, 1> residual_scale() const;
  /// @brief The dimensionless load L^2 (|W| + |F_tip|) / EI (L: robot length, W: total weight
  /// of backbone and disks, F_tip: tip force, EI: bending stiffness) that decides the automatic
  /// formulation (see the file comment).
  double tension_parameter() const;
  /// @brief True if solve() uses multiple shooting (decided once, in the constructor).
  bool uses_multiple_shooting() const;

  struct Impl;  ///< Private (defined in models/vc).

 private:
  Solution solve_multiple(VcWorkspace& workspace, const Solution* warm_start) const;
  bool warm_reaction(const Solution& previous, Eigen::Matrix<double, 6, 1>& x) const;
  Scene scene_;
  VcOptions options_;
  std::shared_ptr<const Impl> impl_;
};

}  // namespace tdcr
