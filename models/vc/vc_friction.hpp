// Private to models/vc: VC with capstan tendon friction (Effects::tendon_friction). The rod of
// vc_rhs.hpp with the tension of every tendon as an extra state: along the fully constrained
// path dT_k/ds = s mu_k |f_k| (s = -1 pulling, +1 releasing), f_k = T_k d(R t_k)/ds the normal
// force per unit length between tendon and backbone, and the tendon loads the backbone with
// d(T_k R t_k)/ds, whose tangential part T_k' R t_k is the friction force (docs/models.md).
#pragma once

#include <vector>

#include "tdcr/bvp/integrator.hpp"
#include "tdcr/core/scene.hpp"
#include "tdcr/models/cosserat_rod.hpp"
#include "tdcr/models/vc.hpp"
#include "vc/vc_rhs.hpp"

namespace tdcr::vc {

/// The rod of one segment with tension states: 18 rod states, one length per tendon if
/// requested, then one tension per tendon (global order; constant where a tendon does not run).
class FrictionRod final : public bvp::OdeSystem {
 public:
  /// `section`, `segment` and `friction` must outlive the rod.
  FrictionRod(const cosserat::Section& section, const SegmentLoads& segment, const TendonFriction& friction,
              int tendon_count, bool lengths);
  int dimension() const override { return tension_offset() + tendon_count_; }
  void rhs(double s, const double* y, double* dyds) const override;
  /// Integrate segment `segment` from now on.
  void set(const SegmentLoads& segment) { seg_ = &segment; }
  /// Record the largest curvature x offset of the tensioned tendons in `d` (TendonRod::watch).
  void watch(Degeneracy* d) { watch_ = d; }
  /// True if the states hold the tendon lengths.
  bool lengths() const { return lengths_; }
  /// Index of tendon 0's tension in the state.
  int tension_offset() const { return cosserat::kStateSize + (lengths_ ? tendon_count_ : 0); }
  /// s mu_k of tendon k (global index).
  double rate(int k) const { return rate_[k]; }

 private:
  /// Per tendon: what the loads of one evaluation need.
  struct Term {
    Mat3 A;  ///< T_k / |q_k| (I - t_k t_k^T)
    Vec3 a;  ///< The normal force at zero strain rates.
    Vec3 t;  ///< Unit tangent t_k (body frame).
  };
  const cosserat::Section* section_;
  const SegmentLoads* seg_;
  std::vector<double> rate_;
  int tendon_count_;
  bool lengths_;
  Degeneracy* watch_ = nullptr;
  mutable std::vector<Term> terms_;  ///< Scratch, one per tendon (no allocation in rhs).
};

/// Tension states at the start of a shot with base wrench (y's n(0), m(0)): the actuator tension
/// after the turn from the base disk's axis into the path's tangent at s = 0 (as VCref's base hole).
void begin_friction_shot(const VcWorkspace::Impl& W, const FrictionRod& rod, double* y);
/// Before the point loads of disk j (segment i): the tendons terminating or kinking there carry
/// the local tensions of the state. With friction the T of W.segments' loads are these local
/// values (the rod itself reads its tensions from the state, the shot's base from W.loads).
void friction_at_disk(VcWorkspace::Impl& W, const FrictionRod& rod, int i, int j, const double* y);
/// Each tendon's tension at its end from a shot's final state y (Solution::tendon_end_tensions).
void friction_end_tensions(const VcWorkspace::Impl& W, const FrictionRod& rod, const double* y,
                           std::vector<double>& tensions);

}  // namespace tdcr::vc
