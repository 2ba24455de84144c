// Private to models/: the subsegment statics shared by the lumped static models CCsub and PRB
// (paper Section 5.2.2-5.2.3, Eq. 44-47 and 50-51): the recursive force and moment balance from
// the tip to the base, with the discrete tendon forces of Eq. 30-33 (and Eq. 58) at every disk,
// the tip wrench and gravity. The loads themselves come from physics::LoadCase.
#pragma once

#include <vector>

#include "physics/load_case.hpp"
#include "tdcr/core/robot.hpp"
#include "tdcr/core/scene.hpp"
#include "tdcr/core/types.hpp"

namespace tdcr::detail {

/// @brief The loads of one input on the subsegments: bound per input, kept in a workspace.
struct SubsegmentLoads {
  physics::LoadCase loads;
  /// Tensions at the current load factor, by global index (what tendon::disk_wrench reads).
  std::vector<double> tensions;
  /// With tendon friction: the chord tensions of tendon::friction_tensions in the last evaluated
  /// shape (what tendon::disk_wrench_friction reads); empty without friction.
  std::vector<double> chord;
  /// J: subsegments 1..J can carry load; J+1..N are exactly straight and untwisted.
  int active = 0;
  /// Scratch of SubsegmentStatics::disk_loads, sized at bind: hole positions and unit chord
  /// directions (towards the previous disk) by tendon and disk.
  std::vector<Vec3> holes, chords;

  /// With the tendons' axial compression (CCsub with effects.shear_extension, as CC): the stretch
  /// 1 + eps_j = 1 - N_j / EA of subsegment j (index 0..N), N_j the tensions of the tendons that
  /// pass through it, taken along the backbone (the compression of CC's Eq. 12 per subsegment);
  /// empty: inextensible. Follows the tensions (set_load_factor, driven tensions).
  std::vector<double> stretch;
  /// 1 / EA (1/N) with the compression, and the last subsegment of each tendon (global index).
  double axial_compliance = 0.0;
  std::vector<int> tendon_end;

  /// @brief Scale every load by lambda (continuation); allocation-free.
  void set_load_factor(double lambda);
  /// @brief The stretches of subsegments 0..N, or nullptr when inextensible.
  const double* stretch_data() const { return stretch.empty() ? nullptr : stretch.data(); }
  /// @brief The stretch of subsegment j (1 when inextensible).
  double stretch_of(int j) const { return stretch.empty() ? 1.0 : stretch[static_cast<std::size_t>(j)]; }
  /// @brief stretch from the current tensions; allocation-free.
  void update_stretch();
};

/// @brief A robot cut into subsegments (decided once per model) and the allocation-free
/// recursive balance of Eq. 44-47 for the loads of one input.
///
/// Subsegment j (1-based, j = 1..N with N the number of disks) is the piece of backbone between
/// disk j-1 and disk j; disk 0 is the base disk. Everything is in the base frame.
///
/// Effects an input does not enable cost nothing: zero-tension tendons are skipped by the tendon
/// physics, the tip wrench and the weights are added only if present. Subsegments distal of the
/// last loaded disk (no tendon with nonzero tension reaches them, no tip wrench, no gravity)
/// carry no load: the models leave them out of their unknowns (SubsegmentLoads::active).
///
/// Holds references to the robot and routing it was built from (those of the model owning it).
class SubsegmentStatics {
 public:
  SubsegmentStatics(const Robot& robot, const TendonRouting& routing, const Effects& effects);

  /// @brief The tendon routing and disk list of the robot.
  const TendonRouting& routing() const { return *routing_; }
  /// @brief Number of subsegments N (= number of disks, base disk excluded).
  int subsegments() const { return n_; }
  /// @brief Length l_j of subsegment j (m), j = 1..N, unstretched (SubsegmentLoads::stretch
  /// shortens it under the tendons' compression).
  double length(int j) const { return length_[j]; }

  /// @brief Resolve the loads of `input` (tension input) at load factor 1 and its J.
  void bind(const ModelInput& input, SubsegmentLoads& out) const;
  /// @brief Shorten the subsegments under the tendons' compression (axial stiffness EA, N):
  /// every bind then fills SubsegmentLoads::stretch.
  void set_axial_compression(double EA) { axial_compliance_ = 1.0 / EA; }
  /// @brief True if the subsegments shorten under the tendons' compression.
  bool axial_compression() const { return axial_compliance_ > 0.0; }
  /// @brief Weight of the backbone of subsegment j (N, base frame) at the current load factor.
  Vec3 backbone_weight(const SubsegmentLoads& b, int j) const { return length_[j] * b.loads.backbone_weight(); }

  /// @brief True if the tensions follow the shape (Effects::tendon_friction on).
  bool friction() const { return friction_on_; }
  /// @brief With friction: b.chord from the base tensions in the shape `frames` (disk frames 0..N);
  /// call before disk_loads / distal_wrenches. Allocation-free after bind.
  void update_friction(SubsegmentLoads& b, const Frame* frames) const;

  /// @brief The loads on disks 1..J alone at the current load factor (f, m index 1..J): their
  /// tendon forces (Eq. 30-33, 58, as tendon::disk_wrench), weights and, at the tip disk, the
  /// tip wrench; m[j] about O_j. Every hole position and chord direction is computed once.
  /// With first > 1 only disks first..J are computed (their hole positions and chords from disk
  /// first - 1 on), f and m below first are left as they are: the loads of disks below first
  /// depend on frames 0..first only, so after a change of frames >= first + 1 this gives the same
  /// numbers as a full evaluation (the structured finite differences of LumpedProblem).
  /// With last_disk >= 0 only disks first..min(last_disk, J) are computed (their holes up to disk
  /// last_disk + 1), the tip wrench only if that range ends at J.
  /// With fresh_from >= 0 the holes of disks below fresh_from (and the chords between them) are
  /// taken from b's scratch as the last call left them: a caller that changed only frames >=
  /// fresh_from since a call with the same first saves their recomputation (the columns of one
  /// subsegment in LumpedProblem's structured differences).
  void disk_loads(SubsegmentLoads& b, const Frame* frames, Vec3* f, Vec3* m, int first = 1, int last_disk = -1,
                  int fresh_from = -1) const;
  /// @brief The recursive balance (Eq. 44-47) for subsegments 1..J at the current load factor.
  ///
  /// @param frames Disk frames 0..N (base disk first).
  /// @param backbone_centroid Centre of mass of the backbone of subsegment j (base frame), index
  ///        1..N; read only if the backbone weight acts.
  /// @param F Out, index 1..J: total force on everything distal of subsegment j, i.e. on disk j
  ///        and beyond (tendon forces at disks >= j, disk weights at disks >= j, backbone weight
  ///        of subsegments > j, tip force). Excludes the backbone weight of subsegment j itself.
  /// @param M Out, index 1..J: the moment of the same loads about the centre O_j of disk j.
  void distal_wrenches(SubsegmentLoads& b, const Frame* frames, const Vec3* backbone_centroid, Vec3* F,
                       Vec3* M) const;
  /// @brief The same from disk loads computed by disk_loads (disk_f, disk_m, index 1..J), which
  /// are kept: F, M must be other arrays.
  void distal_wrenches(const SubsegmentLoads& b, const Frame* frames, const Vec3* backbone_centroid,
                       const Vec3* disk_f, const Vec3* disk_m, Vec3* F, Vec3* M) const;

 private:
  // Eq. 46-47 in place: F, M hold the disk loads on entry, the distal wrenches on return.
  void accumulate_distal(const SubsegmentLoads& b, const Frame* frames, const Vec3* backbone_centroid, Vec3* F,
                         Vec3* M) const;

  const Robot* robot_;
  const TendonRouting* routing_;
  std::vector<double> length_;  // index 1..N
  int n_ = 0;
  bool remove_normal_ = true;
  bool friction_on_ = false;
  TendonFriction friction_;
  double axial_compliance_ = 0.0;  // 1 / EA with the tendons' compression, else 0
};

}  // namespace tdcr::detail
