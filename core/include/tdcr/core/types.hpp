/// @file types.hpp
/// @brief Fixed-size linear-algebra types and the rigid frame used throughout tdcr.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace tdcr {

using Vec3 = Eigen::Vector3d;  ///< A 3-vector (m, N, N m, rad/m depending on context).
using Mat3 = Eigen::Matrix3d;  ///< A 3x3 matrix, usually a rotation.
using Mat4 = Eigen::Matrix4d;  ///< A homogeneous transform.

/// @brief A rigid frame: orientation R (columns are the frame's x, y, z axes in the base frame)
/// and origin p (m, base frame). Disk frames are material frames of the backbone: z is the
/// backbone tangent, x and y are the axes in which tendon positions are given.
struct Frame {
  Mat3 R = Mat3::Identity();  ///< Rotation from the frame to the base frame.
  Vec3 p = Vec3::Zero();      ///< Origin in the base frame (m).

  /// @brief The 4x4 homogeneous transform [R p; 0 1].
  Mat4 matrix() const {
    Mat4 T = Mat4::Identity();
    T.topLeftCorner<3, 3>() = R;
    T.topRightCorner<3, 1>() = p;
    return T;
  }
  /// @brief Composition: the frame `other`, given relative to this one, expressed in the base.
  Frame operator*(const Frame& other) const { return Frame{R * other.R, R * other.p + p}; }
  /// @brief The inverse transform.
  Frame inverse() const { return Frame{R.transpose(), -(R.transpose() * p)}; }
  /// @brief A point given in this frame, expressed in the base frame.
  Vec3 transform(const Vec3& x) const { return R * x + p; }
};

}  // namespace tdcr
