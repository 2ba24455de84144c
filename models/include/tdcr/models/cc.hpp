/// @file cc.hpp
/// @brief The constant-curvature (CC) model: one circular arc per segment (paper Eq. 8, 14-18;
/// Webster & Jones 2010), from tendon displacements (kinematic) or from tensions (statics of
/// fully constrained tendons without external load: Camarillo et al. 2008).
///
/// Displacement input, fully constrained tendons (Eq. 15 generalised to any tendon position):
/// a segment of length l with curvature vector kappa = kappa (cos phi, sin phi) in its base disk
/// frame shortens tendon k at r_k by l (kappa . r_k). That is linear in kappa, so m >= 2 tendons
/// give kappa exactly (two non-collinear tendons) or in the least-squares sense (m tendons, or
/// collinear ones: minimum-norm). Partially constrained tendons (Eq. 20): the chord between two
/// disks is 2 (R - d_k) sin(theta / 2n); solved by Gauss-Newton on the two components of kappa
/// from the fully constrained answer. With the AtBase convention a tendon's displacement is the
/// sum over every segment it runs through; proximal segments are solved first and their share is
/// removed before a distal segment is solved (Jones & Walker 2006).
///
/// Tension input: with fully constrained tendons and no external load the Cosserat rod is a
/// circular arc per segment: u = sum_k T_k (e_z x r_k) / EI over the tendons running through the
/// segment, and (with shear/extension) an axial strain v_z = 1 - sum_k T_k / EA.
///
/// The straight configuration (kappa = 0) is regular: frames come from the SE(3) exponential with
/// series expansions, no division by kappa.
#pragma once

#include <memory>
#include <vector>

#include <Eigen/Core>

#include "tdcr/models/static_model.hpp"

namespace tdcr {

/// @brief Arc parameters of one segment.
struct CcArc {
  Vec3 u = Vec3::Zero();             ///< Curvature vector in the segment's base frame (rad/m).
  Vec3 v = Vec3(0.0, 0.0, 1.0);      ///< Strain (axial stretch) in the segment's base frame.
  double curvature() const { return u.head<2>().norm(); }      ///< kappa (1/m).
  double bending_plane() const;                                ///< phi (rad), atan2 convention.
};

/// @brief The CC model of a robot. Closed form: a solve performs no iteration for fully
/// constrained tendons; the partially constrained variant runs a 2-unknown Gauss-Newton per
/// segment. Solution::unknowns holds the curvature vector u of every segment (3 per segment).
class CcModel final : public StaticModel {
 public:
  /// @brief Validates robot and effects (InputError) and factorises each segment's
  /// displacement-to-curvature map once.
  CcModel(const Robot& robot, const Effects& effects);
  ModelKind kind() const override { return ModelKind::CC; }
  /// @brief What CC takes (closed form: tensions or displacements, no external load, straight routing);
  /// its registry row reads the same.
  static constexpr ModelCapabilities kCapabilities = [] {
    ModelCapabilities c;
    c.displacement_input = true;
    c.external_loads = false;
    c.curved_routing = false;
    return c;
  }();
  ModelCapabilities capabilities() const override { return kCapabilities; }
  std::unique_ptr<ModelWorkspace> make_workspace() const override;
  /// @brief StaticModel::check_input (no external loads: CC has no statics of them), and for
  /// displacement input every segment needs at least 2 tendons
  /// (field `robot.segments[i].tendons`).
  void check_input(const ModelInput& input) const override;

  /// @brief Arc parameters of every segment for an input (the core of a solve; the input is
  /// checked by tdcr::solve, not here). `misfit` receives the least-squares residual of the
  /// displacement fit (m), 0 if exact.
  std::vector<CcArc> arcs(const ModelInput& input, double* misfit = nullptr) const;
  /// @brief The same into `out` (resized to the segment count; no allocation once it has it).
  void arcs(const ModelInput& input, std::vector<CcArc>& out, double* misfit = nullptr) const;

 private:
  ModelProblem& bind(ModelWorkspace& workspace, const ModelInput& input,
                             const SolverOptions& options) const override;
  /// Per segment: the least-squares (minimum-norm) map from the segment's own displacements to
  /// its curvature vector, factorised once here so that a solve does no decomposition.
  std::vector<Eigen::Matrix<double, 2, Eigen::Dynamic>> displacement_to_curvature_;
};

}  // namespace tdcr
