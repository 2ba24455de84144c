/// @file vcref.hpp
/// @brief The VCref model (paper Section 6.2, Table 2; Gao et al. 2017): a Cosserat rod between
/// every pair of consecutive disks, tendons as straight chords between disk holes that apply
/// discrete forces at the disks, solved by multiple shooting. It is tdcr's reference model.
///
/// **Physics.** Disks j = 0..N (0 = base disk at the base frame, N = tip disk). Every interval
/// (disk j-1 -> disk j) is a free Cosserat rod (cosserat::FreeRod, Eq. 2-3, 34-39; shear and
/// extension per Effects::shear_extension; backbone weight under gravity). At disk j the tendons
/// apply tendon::disk_wrench (Eq. 30-33, Eq. 58 per Effects::disk_normal_force), plus the disk
/// weight, plus the tip wrench at j = N. Disk equilibrium (Eq. 40-41):
///   n(s_j-) = n(s_j+) + F_j,   m(s_j-) = m(s_j+) + M_j,   n(s_N+) = m(s_N+) = 0.
///
/// **Formulation.** bvp::ShootingSystem with one interval per subsegment. Unknowns: (n_0, m_0)
/// just distal of the base (the base pose is known), and per disk j = 1..N-1 the pose and the
/// wrench just distal of it, x_j = (p_j, w_j, n_j, m_j) with R_j = Rbar_j exp(w_j): the
/// reference Rbar_j (from the guess, rebased after every accepted step) keeps w small for bends
/// of any angle. 6 + 12 (N - 1) unknowns. Residuals: the tip equilibrium (6), and per disk the
/// pose continuity (p_j - p^-, vee(skew(R^-^T R_j))) and the disk equilibrium (12), where the
/// tendon wrench reads the poses of disks j-1, j, j+1. The Jacobian is block tridiagonal
/// (forward differences; without gravity the free rod's flow commutes with translations and
/// rotations of the whole start, so only the start wrench's 6 unknowns need an integration each;
/// with gravity the rotations take 3 more; the tendon wrenches, whose chords turn on the scale of
/// the disk spacing L / N, enter through their exact derivatives in the disk poses, so that the
/// differences' steps follow the unknowns' scales and the Jacobian's accuracy does not fall with
/// N; with tendon friction they are differenced in full); KLU above 18
/// unknowns (whatever NewtonOptions::dense_size_limit says), so the cost grows linearly with N. Its pattern
/// follows the input: disk j's equilibrium reads disk j+1's pose only where a tensioned tendon
/// passes disk j; a workspace keeps the patterns of its last two such sets and rebuilds one only
/// when the set changes (the model's pattern, every routed tendon, needs no build).
///
/// **Scaling.** Positions by 1/L, rotations by 1, forces by 1/F_s, moments by 1/(F_s L)
/// (L robot length, F_s = physics::LoadCase::force_scale()), residuals and unknowns alike.
///
/// **Cold start.** The constant-curvature arcs of the tendon moments (VcrefOptions). A soft robot
/// under large external loads has several equilibria and a direct solve can land on one that is
/// not reached by loading the robot from rest; so a cold solve loads from rest (with
/// SolverOptions::continuation) when P = load_parameter() > VcrefOptions::load_threshold or
/// P_c = compression_parameter() > VcrefOptions::compression_threshold, the first load step
/// min(threshold / parameter). Tensions do not count: the tendon chords follow the disks. A warm
/// start always solves directly first. Measurements behind the thresholds:
/// docs/design-notes/vcref.md.
///
/// **Outputs.** disk_frames: base, every disk, tip last (its rotation projected onto SO(3)).
/// backbone: sample 0 = base with (n_0, m_0); sample j >= 1 = disk j with n(s_j-), m(s_j-).
/// tendon_displacements: from the chord lengths (tendon::chord_displacements). unknowns: x as
/// above; a warm start takes them with the previous disk rotations as Rbar.
///
/// Input: tendon tensions. Integrator: SolverOptions::integrator (RK4 or CVODE).
#pragma once

#include <memory>

#include "tdcr/bvp/residual_system.hpp"
#include "tdcr/core/robot.hpp"
#include "tdcr/models/static_model.hpp"

namespace tdcr {

/// @brief Model-specific settings of VCref (beyond the per-call SolverOptions).
struct VcrefOptions {
  /// @brief Initial guess of a cold solve (no warm start).
  enum class InitialGuess {
    /// Disk poses on the constant-curvature arcs of the tendon moments, u = sum_k T_k
    /// (e_z x r_k) / EI per segment (paper Eq. 8), wrenches from the disk equilibria on that
    /// shape. Default: fewer Newton iterations and more robust than Straight.
    ConstantCurvature,
    /// The straight robot (as the paper's code), with the straight robot's static wrenches.
    Straight
  };
  InitialGuess initial_guess = InitialGuess::ConstantCurvature;  ///< See InitialGuess.
  /// With ConstantCurvature: fixed-point passes after the arcs (0..20), as CCsub's cold guess:
  /// each disk interval bent into the arc of the moment at its proximal disk, the disk
  /// equilibria redone on that shape, while the passes contract. They add the external loads'
  /// bending: on the 60 loaded cases of bench_loaded 4.7 -> 2.75 Newton iterations on average,
  /// and under loads where the arcs alone lead a direct solve to another equilibrium
  /// (tests/test_model_vcref_loads.cpp) the direct solve lands on the loading path's. 0: the
  /// arcs alone.
  int guess_passes = 3;
  /// Cold solves load the robot from rest when load_parameter() exceeds this. Infinity: never.
  double load_threshold = 2.0;
  /// Cold solves load the robot from rest when compression_parameter() exceeds this (Euler
  /// buckling of a cantilever under a tip load: pi^2 / 4 = 2.47). Infinity: never.
  double compression_threshold = 2.0;
  /// Warm-started solves start from the previous solve's Jacobian (modified Newton, a fresh
  /// Jacobian only when the residual stops falling fast enough): more, much cheaper iterations
  /// (a trajectory about 1.8x faster). A solve's answer then depends on the workspace's last
  /// solve within the Newton tolerance; SolverOptions::reuse_jacobian false turns it off for
  /// every model (the displacement-input solve does so for its inner tension solves).
  bool reuse_jacobian = true;
};

/// @brief The VCref model of a robot with its effects: immutable (disks, Jacobian structure,
/// section stiffness decided once). Tensions and loads come per call (tdcr::solve); all mutable
/// memory of a solve lives in the workspace from make_workspace().
class VcrefModel final : public StaticModel {
 public:
  /// @brief Throws InputError on an invalid robot or effects or non-positive thresholds.
  VcrefModel(const Robot& robot, const Effects& effects, const VcrefOptions& options = VcrefOptions());
  ~VcrefModel() override;
  ModelKind kind() const override { return ModelKind::VCref; }
  /// @brief What VCref takes (every capability);
  /// its registry row reads the same.
  static constexpr ModelCapabilities kCapabilities = [] {
    ModelCapabilities c;
    c.displacement_input = true;
    c.backbone_wrench = true;
    c.tendon_forces_at_disks = true;
    c.displacement_statics = true;
    c.tendon_friction = true;
    c.rk4_mesh = true;
    c.contact = true;
    return c;
  }();
  ModelCapabilities capabilities() const override { return kCapabilities; }
  std::unique_ptr<ModelWorkspace> make_workspace() const override;
  /// @brief The model-specific settings it was built with.
  const VcrefOptions& options() const { return options_; }

  /// @brief P = L^2 (|W| + |F_tip|) / EI of `input` (InputError if it does not fit the robot).
  double load_parameter(const ModelInput& input) const;
  /// @brief P_c = L^2 max(0, -e_z . (F_tip + W)) / EI of `input`.
  double compression_parameter(const ModelInput& input) const;
  /// @brief True if a cold solve of `input` loads the robot from rest (see the file comment).
  bool loads_from_rest(const ModelInput& input) const;
  /// @brief Number of unknowns (and residuals): 6 + 12 (N - 1), N = total disks.
  int unknowns() const;
  /// @brief Structural nonzeros of the block-tridiagonal Jacobian with every routed tendon
  /// tensioned (grows linearly with N).
  int jacobian_nonzeros() const;
  /// @brief Structural nonzeros of the Jacobian a solve of `input` uses: a disk's equilibrium
  /// reads the next disk's pose only if a tensioned tendon passes through it (InputError if
  /// `input` does not fit the robot).
  int jacobian_nonzeros(const ModelInput& input) const;

  /// @brief Diagnostics: the assembled sparse Jacobian against central differences
  /// (bvp::check_jacobian) for `input`, at the guess from `at` (a previous Solution, as for a
  /// warm start) or the cold guess, each unknown x_i moved by perturbation * sin(1 + i) *
  /// (typical magnitude of x_i) so the check can leave the guess.
  bvp::JacobianCheck check_jacobian(ModelWorkspace& workspace, const ModelInput& input,
                                    const SolverOptions& options = SolverOptions(), const Solution* at = nullptr,
                                    double perturbation = 0.0) const;

  /// @brief Internal data shared with the workspace (implementation detail).
  struct Data;

 private:
  ModelProblem& bind(ModelWorkspace& workspace, const ModelInput& input,
                             const SolverOptions& options) const override;
  VcrefOptions options_;
  std::shared_ptr<const Data> data_;
};

}  // namespace tdcr
