/// @file contact_geometry.hpp
/// @brief Signed distances of the obstacle primitives (scene.hpp, Obstacle) and the contact
/// points of the robot's surface (backbone and disks) against them (docs/contact.md).
#pragma once

#include "tdcr/core/scene.hpp"
#include "tdcr/core/types.hpp"

namespace tdcr {

/// @brief The signed distance of a point to an obstacle: positive in free space, negative
/// inside the obstacle, with the outward normal (the unit gradient of the distance, pointing
/// into free space) and the closest point of the obstacle's surface.
struct SignedDistance {
  double distance = 0.0;        ///< m; > 0 in free space.
  Vec3 normal = Vec3::UnitZ();  ///< Unit gradient of `distance` (towards free space).
  Vec3 closest = Vec3::Zero();  ///< Closest point of the obstacle's surface.
};

/// @brief Signed distance of `x` to `obstacle` (allocation-free). Where the gradient is not
/// defined (a point on a capsule's axis, a lumen's centreline, the axis of a cylinder inside
/// it) a unit normal perpendicular to the axis is chosen.
SignedDistance signed_distance(const Obstacle& obstacle, const Vec3& x);

/// @brief What of the robot touches.
enum class ContactBody {
  Backbone,  ///< The backbone's surface (its outer radius) at a disk's centre.
  Disk       ///< The rim of a spacer disk.
};

/// @brief The candidate contact of one body part with one obstacle, in a given disk frame.
struct ContactPoint {
  double gap = 0.0;             ///< m; negative: penetration.
  Vec3 point = Vec3::Zero();    ///< The robot's surface point nearest the obstacle (base frame).
  Vec3 normal = Vec3::UnitZ();  ///< Direction of the force the obstacle exerts on the robot.
};

/// @brief The contact point of the backbone (a sphere of radius `radius` about the disk centre
/// `frame.p`) or of a disk (a circle of radius `radius` in the frame's x-y plane about its
/// centre) with an obstacle. A disk touches with the rim point towards the obstacle (the
/// normal at its centre projected on the disk plane); a disk facing a plane squarely touches
/// with its centre (gap: the distance of its plane). Exact for planes; for curved obstacles the
/// rim point is the one facing the obstacle's closest point to the centre.
ContactPoint contact_point(const Obstacle& obstacle, const Frame& frame, ContactBody body, double radius);

/// @brief Text name ("backbone", "disk").
const char* to_string(ContactBody body);

}  // namespace tdcr
