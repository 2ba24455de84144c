// Private to models/: what the lumped static models CCsub and PRB share around their residuals.
// Both cut the robot into subsegments between disks with a few unknowns each, share the
// recursive statics (subsegment_statics.hpp), and differ only in their kinematics and
// constitutive residuals: a LumpedBody (immutable, owned by the model) says those, a
// LumpedProblem (one per workspace) binds an input and gives the solve driver the rest.
#pragma once

#include <memory>
#include <vector>

#include <Eigen/Core>

#include "common/model_problem.hpp"
#include "common/subsegment_statics.hpp"
#include "tdcr/models/lumped_model.hpp"

namespace tdcr::detail {

class LumpedProblem;

/// The subsegments of one lumped model, their stiffness and kinematics.
class LumpedBody {
 public:
  LumpedBody(const Robot& robot, const TendonRouting& routing, const Effects& effects, int per_subsegment);
  virtual ~LumpedBody();

  /// Disk frames 0..N (base disk first) from the unknowns of subsegments 1..J (x holds at least
  /// per_subsegment J values); subsegments beyond J are straight.
  virtual void compute_frames(const double* x, int J, Frame* frames) const = 0;
  /// The problem of a new workspace.
  virtual std::unique_ptr<LumpedProblem> make_problem() const = 0;
  /// Disk frames for a full unknown vector (per_subsegment N values; InputError otherwise).
  std::vector<Frame> disk_frames(const Eigen::VectorXd& x) const;

  SubsegmentStatics statics;
  double EI = 0.0, GJ = 0.0;  ///< Bending and torsional stiffness (N m^2).
  int per_subsegment = 0;     ///< Unknowns per subsegment.
  int N = 0;                  ///< Subsegments.
};

/// One workspace's solve of a lumped model: its residual system (the parameter is the load
/// factor: every load of the bound input scales with it), Newton memory and buffers, sized once.
/// Unknowns: per_subsegment values for each of the J loaded subsegments; Solution::unknowns
/// holds all N (zero beyond J), so warm starts work across inputs with another J.
class LumpedProblem : public ModelProblem, public bvp::ParameterizedSystem {
 public:
  explicit LumpedProblem(const LumpedBody& body);

  /// Resolve the loads of `input` (allocation-free after the first bind).
  void bind(const ModelInput& input);

  bvp::ParameterizedSystem* system() override { return this; }
  bvp::NewtonSolver& newton() override { return newton_; }
  /// Dense LU: the finite-difference Jacobian of the recursion is dense.
  void adjust(bvp::NewtonOptions& options) const override;
  /// The straight robot.
  void cold_guess(Eigen::VectorXd& x) override { x.setZero(size()); }
  void rest_state(Eigen::VectorXd& x) override { x.setZero(size()); }
  bool warm_guess(const Solution& previous, Eigen::VectorXd& x) override;
  void extract(const Eigen::VectorXd& x, bool evaluated, Solution& solution) override;

  int size() const override { return body_.per_subsegment * loads_.active; }
  void set_parameter(double lambda) override { loads_.set_load_factor(lambda); }

 protected:
  /// The model's geometry at x: frames_ (all N + 1), and centroids_ (backbone centres of mass)
  /// if the backbone weight acts.
  virtual void geometry(const double* x) = 0;
  /// geometry(x), then the distal wrenches F_, M_ of subsegments 1..J.
  void evaluate(const double* x);
  /// Moment about O_{j-1} (base frame) of everything distal of disk j-1 at the last evaluate().
  Vec3 base_moment(int j) const {
    const Vec3& o = frames_[j - 1].p;
    Vec3 m = M_[j] + (frames_[j].p - o).cross(F_[j]);
    if (backbone_weight_on()) m += (centroids_[j] - o).cross(backbone_weight(j));
    return m;
  }

  int active() const { return loads_.active; }
  bool backbone_weight_on() const { return loads_.loads.has_backbone_weight(); }
  Vec3 backbone_weight(int j) const { return body_.statics.backbone_weight(loads_, j); }

  SubsegmentLoads loads_;
  std::vector<Frame> frames_;
  std::vector<Vec3> centroids_, F_, M_;

 private:
  const LumpedBody& body_;
  bvp::NewtonSolver newton_;
  Actuation::DisplacementConvention convention_ = Actuation::DisplacementConvention::AtBase;
};

}  // namespace tdcr::detail
