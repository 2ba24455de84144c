/// @file ccsub.hpp
/// @brief The CCsub model: constant curvature per subsegment with twist (paper Sections 3.1,
/// 5.2.2; Eq. 8, 30-33, 43-47; Yuan et al. 2019), tension input, partially constrained tendons.
///
/// Kinematics. Subsegment j (between disks j-1 and j, length l_j) is a circular arc followed by
/// a twist eps_j about its end tangent. In the frame of disk j-1 the arc has the curvature vector
/// u_j = (u_x, u_y, 0) (rad/m): its end frame is the SE(3) exponential of (u_j l_j, e_z l_j)
/// (equal to Eq. 5 and 8 with kappa = |u|, phi = atan2(-u_x, u_y), the bending direction
/// (cos phi, sin phi) being u x e_z / |u|), post-multiplied by R_z(eps_j). So
/// R_j = R_{j-1} exp([u_j l_j]) R_z(eps_j), which is Rz(phi) Ry(kappa l) Rz(eps - phi) of the
/// paper. The exponential is regular at u = 0: the straight robot needs no offset.
///
/// Unknowns, three per subsegment and dimensionless: x_j = (l_j u_x, l_j u_y, eps_j) (rad).
///
/// Statics. The tendons apply at every disk the discrete forces of Eq. 30-33 (straight tendon
/// pieces between holes), with Eq. 58 (frictionless disks: the force component along the disk
/// normal removed at disks a tendon only passes) when effects.disk_normal_force is Removed. M_j,
/// the moment about O_{j-1} of everything distal of disk j-1 (tendon forces at disks >= j, tip
/// force and moment, gravity), follows recursively from the tip (Eq. 44-47). The constitutive
/// law (Eq. 43) is compared in the frame of disk j-1, as the paper's code does:
///
///     EI u_j + (GJ eps_j / l_j) z_j = M_j,
///
/// where the bending moment EI u_j is perpendicular to z_{j-1} and z_j, and the torsion moment
/// acts along the end tangent z_j. Projected on z_j this is St Venant's twist GJ eps_j / l_j =
/// M_j . z_j. A pure tip moment M (no tension) therefore gives exactly an arc of curvature
/// M / EI. The residual is scaled by l_j / EI (moments in units of the bending stiffness of one
/// subsegment), so every residual is an angle: O(1) for any robot.
///
/// Loads: tip force and moment (base frame) at the tip disk centre; gravity (base frame): the
/// weight of every disk at its centre, and the backbone weight rho A g l_j of subsegment j at
/// the exact centroid of its arc (the distributed weight integrated along the arc). No shear; with
/// effects.shear_extension (the default) each subsegment shortens by the tensions of the tendons
/// through it over EA (CC's axial strain per subsegment, docs/models.md), without it it is
/// inextensible (the paper's CCsub).
///
/// Solver (lumped_model.hpp): Newton on the 3J residuals of the loaded subsegments (recursive)
/// or on these and the pose and balance residuals of every disk (banded), from the straight
/// robot; the load factor scales every load for continuation.
#pragma once

#include "tdcr/models/lumped_model.hpp"

namespace tdcr {

/// @brief The CCsub model of a robot (tension input). Solution::unknowns holds
/// x_j = (l_j u_x, l_j u_y, eps_j) for all N subsegments (3N values).
class CcsubModel final : public LumpedModel {
 public:
  /// @brief Validates robot and effects (InputError).
  CcsubModel(const Robot& robot, const Effects& effects,
             LumpedFormulation formulation = LumpedFormulation::Automatic);
  ModelKind kind() const override { return ModelKind::CCsub; }
};

}  // namespace tdcr
