// Private to models/: the subsegment statics shared by the lumped static models CCsub and PRB
// (paper Section 5.2.2-5.2.3, Eq. 44-47 and 50-51): the recursive force and moment balance from
// the tip to the base, with the discrete tendon forces of Eq. 30-33 (and Eq. 58) at every disk,
// the tip wrench and gravity.
#pragma once

#include <vector>

#include "tdcr/core/robot.hpp"
#include "tdcr/core/scene.hpp"
#include "tdcr/core/types.hpp"

namespace tdcr::detail {

/// @brief Loads of a robot cut into subsegments, decided once from a scene, and the
/// allocation-free recursive balance of Eq. 44-47.
///
/// Subsegment j (1-based, j = 1..N with N the number of disks) is the piece of backbone between
/// disk j-1 and disk j; disk 0 is the base disk. Everything is in the base frame.
///
/// Effects the scene does not enable cost nothing: zero-tension tendons are skipped by the
/// tendon physics, the tip wrench is added only if present, disk and backbone weights only if
/// gravity acts on a nonzero mass. Subsegments distal of the last loaded disk (no tendon with
/// nonzero tension reaches them, no tip wrench, no gravity) carry no load at all: they are
/// exactly straight and untwisted, and the models leave them out of their unknowns
/// (active_subsegments()).
class SubsegmentStatics {
 public:
  /// @brief Build from a validated, tension-actuated scene.
  explicit SubsegmentStatics(const Scene& scene);

  /// @brief The tendon routing and disk list of the scene's robot.
  const TendonRouting& routing() const { return routing_; }
  /// @brief Number of subsegments N (= number of disks, base disk excluded).
  int subsegments() const { return n_; }
  /// @brief J: subsegments 1..J can carry load; J+1..N are straight (see class comment).
  int active_subsegments() const { return active_; }
  /// @brief Length l_j of subsegment j (m), j = 1..N.
  double length(int j) const { return length_[j]; }
  /// @brief Segment (0-based) subsegment j belongs to.
  int segment_of(int j) const { return routing_.disk_segment[j]; }
  /// @brief True if the backbone weight acts (gravity and nonzero mass per length).
  bool has_backbone_weight() const { return backbone_weight_on_; }
  /// @brief Weight of the backbone of subsegment j (N, base frame): rho A l_j g.
  const Vec3& backbone_weight(int j) const { return backbone_weight_[j]; }
  /// @brief Tensions (N), one per tendon in global order.
  const std::vector<double>& tensions() const { return tensions_; }

  /// @brief The recursive balance (Eq. 44-47) for subsegments 1..J.
  ///
  /// @param frames Disk frames 0..N (base disk first).
  /// @param backbone_centroid Centre of mass of the backbone of subsegment j (base frame), index
  ///        1..N; read only if has_backbone_weight().
  /// @param F Out, index 1..J: total force on everything distal of subsegment j, i.e. on disk j
  ///        and beyond (tendon forces at disks >= j, disk weights at disks >= j, backbone weight
  ///        of subsegments > j, tip force). Excludes the backbone weight of subsegment j itself.
  /// @param M Out, index 1..J: the moment of the same loads about the centre O_j of disk j.
  void distal_wrenches(const Frame* frames, const Vec3* backbone_centroid, Vec3* F, Vec3* M) const;

 private:
  TendonRouting routing_;
  std::vector<double> tensions_;
  std::vector<double> length_;           // index 1..N
  std::vector<Vec3> disk_weight_;        // index 1..N (N, base frame)
  std::vector<Vec3> backbone_weight_;    // index 1..N (N, base frame)
  Vec3 tip_force_ = Vec3::Zero();
  Vec3 tip_moment_ = Vec3::Zero();
  int n_ = 0;
  int active_ = 0;
  bool tip_wrench_on_ = false;
  bool disk_weight_on_ = false;
  bool backbone_weight_on_ = false;
  bool remove_normal_ = true;
};

}  // namespace tdcr::detail
