/// @file prb.hpp
/// @brief The extended 3R pseudo-rigid-body (PRB) model with twist (paper Sections 3.2.2,
/// 5.2.3; Eq. 11-12, 30-33, 44-54, Table 1; Su 2009, Huang et al. 2019, extended by the paper
/// with a twist per subsegment), tension input, partially constrained tendons.
///
/// Kinematics (Eq. 11-12). Subsegment j (between disks j-1 and j, length l_j) is 4 rigid links
/// of lengths gamma_i l_j (i = 0..3, effects.prb.gamma; default Table 1 normalised by its sum
/// 0.999) joined by 3 revolute joints of angles theta_1..3 (rad), all bending in the plane
/// rotated by phi about the local z axis of disk j-1; the first link is tangent to z_{j-1}.
/// The end frame is Rz(phi) T_0 T_1 T_2 T_3 Rz(-phi) Rz(eps): Eq. 12 post-multiplied by the
/// twist eps about the end tangent.
///
/// Unknowns, five per subsegment (rad): x_j = (theta_1, theta_2, theta_3, phi, eps).
///
/// Statics. Tendon forces at every disk from Eq. 30-33 with Eq. 58 when
/// effects.disk_normal_force is Removed; the distal wrench recursion of Eq. 44-47 (shared with
/// CCsub). Residuals of subsegment j, all scaled by l_j / EI (dimensionless, O(1)):
///  - joints q = 1..3, spring law Eq. 48-51: K_theta_q theta_q = (l/EI) M_{j,q} . y_phi, with
///    M_{j,q} the moment about joint q of everything distal of it, y_phi the joint axis;
///  - bending plane, Eq. 52-53: with M_j the moment about O_{j-1} of everything distal of disk
///    j-1 and M_j* its part in the plane of disk j-1 (the paper's code removes the z_{j-1}
///    component), Eq. 52 asks M_j* parallel to y_phi. The paper's code writes it as
///    n . M* - |M*| = 0, which is one-sided and has zero slope at its root (Newton converges
///    only linearly, if at all). tdcr uses the two-sided, smooth equivalent
///    (l/EI) M_j . x_phi = 0 with x_phi = (cos phi, sin phi, 0) in disk j-1's frame, the in-plane
///    direction perpendicular to the joint axis. Its second root (phi + pi, all theta negated)
///    is the very same shape (Rz(pi) Ry(-t) Rz(-pi) = Ry(t)), so the branch is immaterial for
///    the result; the straight initial guess picks phi from the moment at the straight state, so
///    that the joint angles come out positive like the paper's. Where M_j* vanishes (a straight,
///    unloaded or symmetrically loaded subsegment) phi is undetermined and Newton's phi step is
///    a ratio of rounding errors. A gauge term eta a0^2 / (a0^2 + t^2) sin(phi - phi_0) is added
///    (t = (l/EI) |M*|, eta = a0 = 1e-6, phi_0 the initial phi): it pins phi where the in-plane
///    moment vanishes and fades out where the moment defines the plane (below 1e-12 for
///    t >= 1e-3, i.e. whenever the subsegment bends by more than ~1e-3 rad). It changes the shape
///    by at most ~eta l / K_theta (the joint angles vanish with t). phi's finite-difference step
///    is 1.5e-4 rad so that the Jacobian resolves the gauge above rounding noise;
///  - twist, Eq. 54: (GJ/EI) eps = (l/EI) M_j . z_j.
///
/// Loads: tip force and moment (base frame) at the tip disk centre; gravity (base frame): disk
/// weights at disk centres and the backbone weight of each rigid link at its midpoint (the exact
/// weight distribution of the rigid-link body). No shear; with effects.shear_extension (the default)
/// every link of a subsegment shortens by the tensions of the tendons through it over EA, without
/// it the links are rigid (the paper's PRB).
///
/// Solver (lumped_model.hpp): Newton on the 5J residuals of the loaded subsegments (recursive;
/// steps bounded to about one radian of joint angle) or on these and the pose and balance
/// residuals of every disk (banded), from the straight guess (bending planes along the moment
/// at the straight state); the load factor scales every load for continuation.
#pragma once

#include <vector>

#include "tdcr/models/lumped_model.hpp"

namespace tdcr {

/// @brief The PRB model of a robot (tension input). Solution::unknowns holds
/// x_j = (theta_1, theta_2, theta_3, phi, eps) for all N subsegments (5N values).
class PrbModel final : public LumpedModel {
 public:
  /// @brief Validates robot and effects (InputError; the PRB parameters must be positive and
  /// finite, Effects::validate).
  PrbModel(const Robot& robot, const Effects& effects,
             LumpedFormulation formulation = LumpedFormulation::Automatic);
  ModelKind kind() const override { return ModelKind::PRB; }

  /// @brief Joint centres and link ends of the rigid-link body, base frame: for every
  /// subsegment its 3 joint centres followed by the disk centre that ends it (4N points), for
  /// plotting the 3R shape. `x` as Solution::unknowns (5N values), `input` the tension input it
  /// answers (its tensions shorten the links with effects.shear_extension; for a displacement
  /// solve's answer pass its Solution::tensions as tensions).
  std::vector<Vec3> joint_points(const Eigen::VectorXd& x, const ModelInput& input) const;
};

}  // namespace tdcr
