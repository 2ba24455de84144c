/// @file lumped_model.hpp
/// @brief The common base of the lumped static models CCsub (ccsub.hpp) and PRB (prb.hpp).
///
/// Both cut the robot into subsegments between consecutive disks, describe each by a few
/// dimensionless unknowns, and balance the tendon forces at the disks (paper Eq. 30-33, 58), the
/// tip wrench and gravity by the same recursion from the tip (Eq. 44-47); only the kinematics
/// and the constitutive law of a subsegment differ. No shear; the subsegments shorten under the
/// tendons' compression with effects.shear_extension (SubsegmentLoads::stretch).
///
/// Subsegments distal of the last loaded disk (no tendon with nonzero tension reaches them, no
/// tip wrench, no gravity) are exactly straight: they are no unknowns of the solve
/// (SolverSummary::unknowns counts the loaded ones), while Solution::unknowns holds the values
/// of all N subsegments (zero for the straight ones), so that any Solution of the same model can
/// warm-start another input. Cold guess: the straight robot.
///
/// Formulations of the same equations (LumpedFormulation), same solution: recursive (the
/// subsegment unknowns only; dense Jacobian by structured forward differences, dense LU, cost
/// ~J^3 in the LU, fastest for few subsegments) and banded (disk poses and internal wrenches are
/// unknowns too; block-banded Jacobian, KLU, cost ~J per iteration, but more iterations: its
/// steps leave the pose constraints). Automatic: the recursive unknowns with structured Newton
/// steps: the recursive Jacobian is a block diagonal plus two low-rank block-triangular parts (a
/// change of one subsegment moves everything distal of it rigidly), so each step is solved by
/// its block LU in those factors, a few small products per subsegment (the iterations of the
/// recursive form at a cost ~J each), or, where that loses accuracy, as a block-banded system in
/// the step and two partial sums, factored by KLU (docs/design-notes/lumped.md).
#pragma once

#include <memory>
#include <vector>

#include <Eigen/Core>

#include "tdcr/models/static_model.hpp"

namespace tdcr {

namespace detail {
class LumpedBody;
}  // namespace detail

class DynamicsIntegrator;

/// @brief How a lumped model sets up its Newton system (see the file comment).
enum class LumpedFormulation { Automatic, Recursive, Banded };

/// @brief A lumped static model: immutable; solved through tdcr::solve with its workspace.
class LumpedModel : public StaticModel {
 public:
  ~LumpedModel() override;
  /// @brief What CCsub and PRB take (statics of both inputs, tendon forces at the disks,
  /// friction): one set for both, read by their registry rows as CcsubModel::kCapabilities and
  /// PrbModel::kCapabilities.
  static constexpr ModelCapabilities kCapabilities = [] {
    ModelCapabilities c;
    c.displacement_input = true;
    c.tendon_forces_at_disks = true;
    c.displacement_statics = true;
    c.tendon_friction = true;
    c.contact = true;
    return c;
  }();
  ModelCapabilities capabilities() const override { return kCapabilities; }
  std::unique_ptr<ModelWorkspace> make_workspace() const override;
  /// @brief Unknowns per subsegment (3 for CCsub, 5 for PRB).
  int unknowns_per_subsegment() const;
  /// @brief Disk frames (base disk first, tip last) for unknowns x of every subsegment
  /// (Solution::unknowns) under the tension input `input` (whose tensions shorten CCsub's
  /// subsegments with effects.shear_extension; for a displacement solve's answer pass its
  /// Solution::tensions as tensions). Throws InputError on a vector of another size.
  std::vector<Frame> frames(const Eigen::VectorXd& x, const ModelInput& input) const;
  /// @brief The time integrator of this model (models/lumped/lumped_dynamics.cpp; reached through
  /// tdcr::make_dynamics_integrator). InputError naming `robot.backbone.density` for a robot
  /// without mass.
  std::unique_ptr<DynamicsIntegrator> make_dynamics_integrator(const DynamicsSettings& settings, double dt,
                                                               const SolverOptions& solver) const;
  /// @brief Undamped natural frequencies (Hz, ascending) about the shape x (Solution::unknowns) at
  /// rest under `input` (models/lumped/lumped_dynamics.cpp).
  Eigen::VectorXd natural_frequencies(const Eigen::VectorXd& x, const ModelInput& input) const;

 protected:
  /// @brief Builds a model's subsegments from the (validated) robot, its routing and effects.
  using BodyFactory = std::unique_ptr<detail::LumpedBody> (*)(const Robot&, const TendonRouting&, const Effects&,
                                                              LumpedFormulation);
  /// @brief Validates robot and effects (InputError) and builds the body with `make_body`.
  LumpedModel(const Robot& robot, const Effects& effects, LumpedFormulation formulation, BodyFactory make_body);
  /// @brief The model's subsegments (private type, models/lumped/lumped_problem.hpp).
  const detail::LumpedBody& body() const { return *body_; }

 private:
  ModelProblem& bind(ModelWorkspace& workspace, const ModelInput& input,
                             const SolverOptions& options) const override;
  std::unique_ptr<detail::LumpedBody> body_;
};

}  // namespace tdcr
