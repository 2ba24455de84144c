/// @file verification.hpp
/// @brief Independent verification of a solved shape: global equilibrium of the whole robot,
/// checked outside the Newton solver from the Solution alone.
///
/// Free body: the backbone from just above the base (s = 0+) to the tip, every disk 1..N, and
/// the tendon pieces inside the robot. Its loads are the tip force and moment, the weights
/// (disks, backbone), the rod's internal wrench at the base cut (it acts as -n(0), -m(0) on the
/// free body) and the tendons' pull at the base cut, -T_k d_k applied at the base hole r_k,
/// with d_k the tendon's direction there. Their sum, forces and moments about the base origin,
/// must vanish for every model whose tendon forces are internal (a tendon in equilibrium with
/// constant tension: its loads on the backbone telescope to the pull at the base). With tendon
/// friction the friction forces are internal too, and the pull is the tension past the base
/// hole: T_k exp(s mu_k theta_k), theta_k the turn from the base axis into d_k.
///
/// Which models it applies to is read from the model registry (model_registry.hpp):
/// - Models whose Solutions carry the backbone wrench (capability backbone_wrench), with tendons
///   along the backbone (VC: Cosserat rod, continuous tendons): d_k is the tendon tangent at
///   s = 0, (v + u x r_k) / |v + u x r_k| with u, v from n(0), m(0) (Eq. 24-29). Exact up to the
///   ODE integration error.
/// - Those with tendon forces at the disks (capability tendon_forces_at_disks; VCref: Cosserat
///   rod per subsegment, discrete disk forces): d_k is the chord from the base hole to the
///   disk-1 hole (Eq. 30-33). With the frictionless-disk condition (Eq. 58,
///   effects.disk_normal_force = removed) the model drops the component of every pass-through
///   tendon force along the disk normal: the tendons are then not in equilibrium, and the
///   dropped forces are the model's own departure from global equilibrium. They are computed
///   from the disk frames, reported separately (eq58_force, eq58_moment) and accounted for, so
///   the imbalance is again zero up to integration error.
/// - Models without backbone wrench (CC, CCsub, PRB): the Solution carries no internal wrench at
///   the base, so evaluated = false with a reason; these models are checked by re-evaluating
///   their own residual at the returned unknowns (the solve driver's final check, reported in
///   the summary).
///
/// The backbone weight rho A g (per unit reference arc length) is integrated over the backbone
/// samples with the cubic Hermite rule, int p ds ~ h (p0 + p1) / 2 + h^2 (t0 - t1) / 12 with
/// tangents t = R v: fourth order in the sample spacing h.
#pragma once

#include <string>

#include "tdcr/core/scene.hpp"
#include "tdcr/core/solution.hpp"
#include "tdcr/core/types.hpp"
#include "tdcr/models/static_model.hpp"

namespace tdcr {

/// @brief Result of verify_equilibrium(). Forces in N, moments in N m about the base origin,
/// all in the base frame.
struct EquilibriumCheck {
  bool evaluated = false;      ///< False if the check does not apply (see reason).
  std::string reason;          ///< Why it was not evaluated (empty if evaluated).
  Vec3 force = Vec3::Zero();   ///< Sum of all forces on the free body (N): zero at equilibrium.
  Vec3 moment = Vec3::Zero();  ///< Sum of all moments about the base origin (N m).
  /// Scale to judge |force| against (N): the larger of the sum of the magnitudes of the force
  /// terms and (that of the moment terms) / L, L the robot length.
  double force_scale = 0.0;
  /// Scale to judge |moment| against (N m): the larger of the sum of the magnitudes of the
  /// moment terms and (that of the force terms) * L.
  double moment_scale = 0.0;
  Vec3 eq58_force = Vec3::Zero();   ///< Forces dropped by Eq. 58 (VCref), included above (N).
  Vec3 eq58_moment = Vec3::Zero();  ///< Their moment about the base origin (N m).

  /// @brief max(|force| / force_scale, |moment| / moment_scale); infinity if not evaluated.
  double relative_error() const;
};

/// @brief Global equilibrium of a solved robot (see file comment): the imbalance of all loads
/// on the robot, computed from the solution's disk frames and backbone samples (sample 0: the
/// rod's internal force n and moment m at s = 0+, base frame) and the input's tensions, tip
/// wrench and gravity acting on the model's robot. Never throws for a failed or odd solution: it
/// reports evaluated = false with a reason (a Solution of another model, no frames, no base
/// sample, a model without backbone wrench, non-finite values).
EquilibriumCheck verify_equilibrium(const StaticModel& model, const ModelInput& input, const Solution& solution);

/// @brief The same for a scene: the model named by `solution.model`, of the scene's robot and
/// effects, under the scene's input (no model is built).
EquilibriumCheck verify_equilibrium(const Scene& scene, const Solution& solution);

}  // namespace tdcr
