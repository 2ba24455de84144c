/// @file tendon_physics.hpp
/// @brief Tendon physics shared by the models, written once: tendon hole positions, the
/// discrete disk forces of a partially constrained tendon path (paper Eq. 30-33) with the
/// frictionless-disk condition (Eq. 58), and tendon path lengths and displacements.
///
/// All vectors are in the base frame. `frames[j]` is the frame of disk j (0 = base disk).
#pragma once

#include <vector>

#include "tdcr/core/robot.hpp"
#include "tdcr/core/scene.hpp"
#include "tdcr/core/types.hpp"

namespace tdcr::tendon {

/// @brief Force and moment (about the disk centre O_j) applied to a disk, base frame.
struct DiskWrench {
  Vec3 force = Vec3::Zero();   ///< N.
  Vec3 moment = Vec3::Zero();  ///< N m, about the disk's backbone point.
};

/// @brief Hole position P_{k,j} = p_j + R_j r_k of tendon k in disk frame `f` (base frame, m).
inline Vec3 hole_position(const Frame& f, const RoutedTendon& t) { return f.p + f.R * t.r; }

/// @brief Sum over tendons of the wrench the tendons apply to disk j >= 1 (paper Eq. 30-33).
///
/// A tendon ending at disk j pulls towards its hole in disk j-1 (Eq. 30-31). A tendon passing
/// through disk j pulls towards its holes in disks j-1 and j+1 (Eq. 32-33); with
/// `remove_normal` (frictionless disks, Eq. 58) the component along the disk normal z_j is
/// removed from that pass-through force. Terminating tendons always act with their full force.
/// Allocation-free; `frames` must hold at least j+2 frames if any tendon passes disk j.
DiskWrench disk_wrench(int j, const Frame* frames, const TendonRouting& routing, const double* tensions,
                       bool remove_normal);

/// @brief Capstan friction (Effects::tendon_friction): the tension of every chord of every
/// tendon of `routing` in the shape `frames`.
///
/// Walking from the base, the tension of tendon t starts at base_tensions[t.index] (the
/// actuator's) and is multiplied at each hole it passes, disks 0 .. end_disk - 1, by
/// exp(friction.sign() mu_t theta), theta the angle between the incoming and the outgoing
/// chord (at the base disk the incoming direction is the base disk's z axis). Out:
/// chord[t.index * D + j] (D = routing.disk_count()) is the tension of the chord from disk j-1
/// to disk j, j = 1 .. end_disk (and j <= up_to: chord j reads frames 0..j only); other entries
/// are left alone. Allocation-free.
void friction_tensions(const Frame* frames, const TendonRouting& routing, const double* base_tensions,
                       const TendonFriction& friction, double* chord, int up_to = 1 << 30);

/// @brief disk_wrench with the chord tensions of friction_tensions: a tendon pulls disk j towards
/// disk j-1 with the tension of chord j and towards disk j+1 with that of chord j+1.
DiskWrench disk_wrench_friction(int j, const Frame* frames, const TendonRouting& routing, const double* chord,
                                bool remove_normal);

/// @brief Per tendon (global order) the tension of its last chord, from friction_tensions'
/// output (zero for a tendon of no tension).
std::vector<double> end_tensions(const TendonRouting& routing, const double* chord, int tendon_count);

/// @brief Length of tendon k along the partially constrained path: the sum of the chords
/// between its holes in consecutive disks, from disk `first` to its terminating disk.
double chord_length(const Frame* frames, const TendonRouting& routing, int k, int first = 0);

/// @brief chord_displacements() of tendon k alone, from the disk frames `frames` (N + 1 of
/// them); allocates nothing (the lumped dynamics' elastic tendons, every right-hand side).
double chord_displacement(const Frame* frames, const TendonRouting& routing, int k,
                          Actuation::DisplacementConvention convention);

/// @brief Tendon displacements (m, positive when pulled) of every tendon from the chord lengths
/// between disks: with AtBase, straight length (the arc length to its end disk) minus the path
/// length from the base; with PerSegment, only over the tendon's own segment (the paper code's
/// convention for feeding CC).
std::vector<double> chord_displacements(const std::vector<Frame>& frames, const TendonRouting& routing,
                                        Actuation::DisplacementConvention convention);

/// @brief Add every elastic tendon's stretch (TendonSpec::stiffness EA) to its displacement:
/// the pull a motor at the base sets is the path's pull plus T L_free / EA, L_free the tendon's
/// path length from the base to its end disk on the straight robot (its routing included) and T
/// its tension at the base (with tendon friction the base tension over the whole length: the
/// stretch of a tendon that friction holds back is overestimated by at most the capstan loss).
/// Inextensible tendons are left as they are.
void add_elastic_stretch(const Robot& robot, const TendonRouting& routing, const std::vector<double>& tensions,
                         std::vector<double>& displacements);

}  // namespace tdcr::tendon
