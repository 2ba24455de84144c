// Private to models/: the loads of one solve resolved against a robot, written once for every
// model: tendon tensions, tip wrench, disk and backbone weights, their totals and scales, the
// load factor of continuation, and the dimensionless loads of the cold-start rule.
#pragma once

#include <vector>

#include "tdcr/core/robot.hpp"
#include "tdcr/core/scene.hpp"
#include "tdcr/core/types.hpp"

namespace tdcr::physics {

/// The loads of one input on one robot (base frame, SI). Allocation happens in bind() only;
/// set_load_factor() rescales in place.
class LoadCase {
 public:
  /// Resolve `input` against the robot (tension input; for displacement input the tensions are 0).
  void bind(const Robot& robot, const TendonRouting& routing, const ModelInput& input);

  /// Scale every load (tensions, tip wrench, weights) by `lambda` (continuation; 1 = the input).
  void set_load_factor(double lambda);
  double load_factor() const { return lambda_; }

  /// Tension of tendon k at the current load factor (N); a fixed tension is not scaled.
  double tension(int k) const { return fixed_.empty() || !fixed_[k] ? lambda_ * tensions_[k] : fixed_tension_[k]; }
  /// Tensions at full load (N), by global index, as bound (a fixed tension's bound value: the
  /// models decide at bind which tendons act from these).
  const std::vector<double>& full_tensions() const { return tensions_; }
  /// Displacement input: tendon k pulls with `T` (N) at every load factor from now on (its
  /// tension is an unknown of the displacement solve, not a load that continuation scales) until
  /// the next bind. The model that owns this LoadCase must refresh what it derived from the
  /// tensions (ModelProblem::set_driven_tensions).
  void set_fixed_tension(int k, double T) {
    if (fixed_.empty()) {
      fixed_.assign(tensions_.size(), 0);
      fixed_tension_.assign(tensions_.size(), 0.0);
    }
    fixed_[k] = 1;
    fixed_tension_[k] = T;
  }
  /// Tip force and moment at the current load factor (N, N m; base frame).
  Vec3 tip_force() const { return lambda_ * tip_force_; }
  Vec3 tip_moment() const { return lambda_ * tip_moment_; }
  /// Weight of disk j (1..N) at the current load factor (N).
  Vec3 disk_weight(int j) const { return lambda_ * disk_weight_[j]; }
  /// Backbone weight per unit length rho A g at the current load factor (N/m).
  Vec3 backbone_weight() const { return lambda_ * backbone_weight_; }
  /// Total weight of backbone and disks at full load (N).
  const Vec3& total_weight() const { return total_weight_; }

  bool has_tip_wrench() const { return tip_wrench_; }          ///< Nonzero tip force or moment.
  bool has_disk_weight() const { return disk_weight_on_; }     ///< Gravity on disks with mass.
  bool has_backbone_weight() const { return backbone_weight_on_; }  ///< Gravity on the backbone.
  bool has_gravity() const { return disk_weight_on_ || backbone_weight_on_; }
  /// Any tendon with nonzero tension.
  bool has_tension() const { return any_tension_; }

  /// Force scale F_s = sum T + |F_tip| + |M_tip| / L + sum of weight magnitudes + 1 mN (N):
  /// every force residual divided by it is O(1).
  double force_scale() const { return force_scale_; }
  /// Moment scale M_s = sum T |r| + (|F_tip| + |W|) L + |M_tip| + 1 mN L (N m).
  double moment_scale() const { return moment_scale_; }
  /// P = L^2 (|W| + |F_tip|) / EI: the linear deflection of the external loads in units of L.
  double load_parameter() const { return load_parameter_; }
  /// P_c = L^2 max(0, -e_z . (F_tip + W)) / EI: compression of the straight robot (a cantilever
  /// with a tip load buckles at pi^2 / 4).
  double compression_parameter() const { return compression_parameter_; }

 private:
  std::vector<double> tensions_;
  std::vector<char> fixed_;             // set_fixed_tension (empty: none)
  std::vector<double> fixed_tension_;
  std::vector<Vec3> disk_weight_;  // index 0..N (0 unused)
  Vec3 tip_force_ = Vec3::Zero(), tip_moment_ = Vec3::Zero();
  Vec3 backbone_weight_ = Vec3::Zero(), total_weight_ = Vec3::Zero();
  bool tip_wrench_ = false, disk_weight_on_ = false, backbone_weight_on_ = false, any_tension_ = false;
  double lambda_ = 1.0;
  double force_scale_ = 1.0, moment_scale_ = 1.0;
  double load_parameter_ = 0.0, compression_parameter_ = 0.0;
};

}  // namespace tdcr::physics
