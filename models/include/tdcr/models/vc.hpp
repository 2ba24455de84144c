/// @file vc.hpp
/// @brief The VC model: a Cosserat rod with fully constrained tendons (paper Sections 5.1.1 and
/// 5.2.1, Eq. 2-3, 24-29, 34-41; Rucker & Webster 2011).
///
/// **What it computes.** The backbone is the rod of cosserat_rod.hpp (a Kirchhoff rod without
/// Effects::shear_extension). Tendon k runs at the constant body-frame offset r_k, its path is
/// p + R r_k, and it loads every segment it runs through continuously (cosserat::rod_rhs). Point
/// loads act at the disks: tendon terminations F_k = -T_k R t_k at p + R r_k (Eq. 40-41), disk
/// weights, and the kink forces of VcOptions::kink_forces. The tip force and moment (base frame)
/// act at the tip's backbone point. Outputs: the disk frames, the rod's internal wrench n, m at
/// every disk (backbone samples), and the tendon displacements (Eq. 56): the straight length
/// minus the integral of |q_k| = |v + u x r_k|, positive when pulled (with
/// DisplacementConvention::PerSegment only the tendon's own segment counts).
///
/// **Two formulations of one boundary value problem, chosen per input.**
/// - Single shooting (the paper code's): unknowns n(0), m(0); residual the tip wrench after the
///   tip disk's point loads, scaled by the force and moment scales of physics::LoadCase. By
///   global equilibrium the solution lies within a scaled distance of about sqrt(6) of the
///   origin, so Newton steps are bounded to scaled length 1: longer ones overshoot into coiled
///   shapes. A failed cold start is retried once from the other VcInitialGuess.
/// - Multiple shooting: one interval per disk interval, unknowns the 18 rod states at every
///   interval start, residuals p(0), R(0) - I, the tip wrench and the state jump at every inner
///   disk (block-banded Jacobian, KLU). Single shooting integrates the whole rod from the base,
///   and its tip depends on n(0), m(0) like exp(L sqrt(N / EI)): on long, soft robots under large
///   external loads it converges to other (coiled) equilibria. Multiple shooting removes that
///   sensitivity, and a cold solve loads the robot from rest (continuation) so that it follows
///   the equilibrium connected to the unloaded robot.
///
/// VcFormulation::Automatic uses multiple shooting when the load parameter L^2 (|W| + |F_tip|)
/// / EI exceeds VcOptions::multiple_shooting_threshold; tendon tensions do not count (fully
/// constrained tendons compress the backbone without buckling it). The measurements behind the
/// threshold and the costs: docs/design-notes/vc.md.
///
/// **Integration.** Disk interval by disk interval (the rod stops at every disk for its frame and
/// point loads), with RK4 (SolverOptions::rk4_steps per interval) or CVODE. The tendon lengths
/// are extra states of a final pass at the solution (with CVODE, of every shot, so that the
/// reported shape is exactly the converged one).
///
/// **Units.** SI: m, N, N m, rad.
#pragma once

#include <memory>

#include "tdcr/models/static_model.hpp"

namespace tdcr {

/// @brief Cold-start guess of single shooting's unknowns n(0), m(0).
enum class VcInitialGuess {
  /// The base reaction of the straight robot under the input's loads:
  /// n(0) = F_tip + W - (sum T) e_z, m(0) = M_tip + (L e_z) x F_tip + weight moments +
  /// sum T_k (e_z x r_k). Exact for tip-to-base tendons on a one-segment robot at small bending.
  Equilibrium,
  /// n(0) = m(0) = 0: the paper code's straight initial guess.
  Zero
};

/// @brief How the VC boundary value problem is discretised.
enum class VcFormulation {
  /// Multiple shooting when VcModel::load_parameter(input) > VcOptions::multiple_shooting_threshold,
  /// else single shooting (decided per input).
  Automatic,
  SingleShooting,   ///< 6 unknowns n(0), m(0).
  MultipleShooting  ///< 18 unknowns (p, R, n, m) per disk interval.
};

/// @brief Options of the VC model beyond the solver options of a call.
struct VcOptions {
  VcInitialGuess initial_guess = VcInitialGuess::Equilibrium;  ///< Single shooting's cold guess.
  /// Apply the point force T_k R (t_k+ - t_k-) of every tensioned tendon passing a disk where
  /// point loads make the strains (hence the tendon direction t_k) jump. Without it (the paper
  /// code's formulation, which applies termination forces only) the robot's global force and
  /// moment balance fails whenever torsion or shear jumps at a segment end; tendon-only loads
  /// are unaffected (t_k = e_z on both sides). Off if this or Effects::kink_forces is false.
  bool kink_forces = true;
  VcFormulation formulation = VcFormulation::Automatic;  ///< Single or multiple shooting.
  /// Automatic formulation: multiple shooting when the load parameter exceeds this (30: single
  /// shooting along the loading path stays on its branch up to at least 19.8, hard case 14 at 869
  /// coils; docs/design-notes/vc.md).
  double multiple_shooting_threshold = 30.0;
  /// Single shooting with RK4: Newton's Jacobian is the exact derivative of the discrete shot
  /// (dual numbers through every RK4 stage, disk load and kink) instead of forward differences
  /// by the solver (6 extra shots; CVODE always takes these). The same Newton iterations to
  /// within rounding; at present about 1.3x the cost of the differences (`bench_vc_loaded
  /// --quick`, docs/design-notes/vc.md), hence off by default.
  bool exact_jacobian = false;
  /// Warm-started single-shooting solves start from the previous solve's Jacobian (unless that
  /// solve took more than 3 iterations). Every single-shooting solve, cold or warm, is a modified
  /// Newton: a Jacobian serves up to 10 iterations, a fresh one when the residual stops falling
  /// fast enough; this option only decides whether the first one comes from the previous solve
  /// (and SolverOptions::reuse_jacobian = false turns it off for one solve).
  bool reuse_jacobian = true;
};

class VcModel;

/// @brief Mutable memory of one VcModel's solves (integrators, Newton memory, the bound loads).
/// Reuse it along a trajectory: no allocation once warm for a formulation.
class VcWorkspace final : public ModelWorkspace {
 public:
  /// @brief A workspace of `owner`.
  explicit VcWorkspace(const VcModel& owner);
  ~VcWorkspace() override;
  /// @brief Right-hand side evaluations of the rod ODE since construction (a cost measure).
  long rhs_evaluations() const;
  struct Impl;                          ///< Private (models/vc).
  Impl& impl() { return *impl_; }       ///< Private state.

 private:
  std::unique_ptr<Impl> impl_;
};

/// @brief The VC model of a robot (model "vc"): immutable, solved by tdcr::solve().
///
/// Warm starts (a previous Solution of this model): single shooting starts from the base
/// reaction of the previous shape under the new loads (the tip wrench about the previous tip,
/// the weights at the previous disk positions and backbone, the tendon pulls along the previous
/// base strains): exact up to the shape change. Multiple shooting starts from the previous
/// unknowns if they have its size, else from the previous backbone samples.
class VcModel final : public StaticModel {
 public:
  /// @brief Validates `robot` and `effects` (InputError naming the field).
  VcModel(const Robot& robot, const Effects& effects, VcOptions options = {});
  ~VcModel() override;
  ModelKind kind() const override { return ModelKind::VC; }
  /// @brief What VC takes (a rod on an RK4 mesh with backbone wrenches; its direct answers under loads are not tested);
  /// its registry row reads the same.
  static constexpr ModelCapabilities kCapabilities = [] {
    ModelCapabilities c;
    c.displacement_input = true;
    c.backbone_wrench = true;
    c.displacement_statics = true;
    c.tendon_friction = true;
    c.rk4_mesh = true;
    c.contact = true;
    c.stability_under_loads = false;
    return c;
  }();
  ModelCapabilities capabilities() const override { return kCapabilities; }
  /// @brief A fresh VcWorkspace.
  std::unique_ptr<ModelWorkspace> make_workspace() const override;
  /// @brief The options.
  const VcOptions& options() const { return options_; }
  /// @brief L^2 (|W| + |F_tip|) / EI (L: robot length, W: total weight of backbone and disks,
  /// EI: bending stiffness) of `input`: the linear deflection of its external loads in units of L.
  double load_parameter(const ModelInput& input) const;
  /// @brief True if `input` is solved by multiple shooting (VcOptions::formulation).
  bool uses_multiple_shooting(const ModelInput& input) const;

 private:
  ModelProblem& bind(ModelWorkspace& workspace, const ModelInput& input,
                             const SolverOptions& options) const override;
  bool multiple_shooting(double load_parameter) const;
  VcOptions options_;
};

}  // namespace tdcr
