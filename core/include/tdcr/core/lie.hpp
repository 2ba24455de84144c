/// @file lie.hpp
/// @brief SO(3) and SE(3) helpers: hat/vee, exponential and logarithm maps, elementary rotations,
/// rotation distance and projection onto SO(3).
///
/// Conventions: hat(u) is the skew-symmetric matrix of paper Eq. 4, so hat(u) * v = u x v.
/// The exponential map of SO(3) is Rodrigues' formula, evaluated with series expansions near
/// zero so that straight configurations (zero curvature) are handled without division by zero.
#pragma once

#include "tdcr/core/types.hpp"

namespace tdcr::lie {

/// @brief Skew-symmetric matrix [u]x of paper Eq. 4: hat(u) * v == u.cross(v).
inline Mat3 hat(const Vec3& u) {
  Mat3 S;
  S << 0.0, -u.z(), u.y(),
       u.z(), 0.0, -u.x(),
       -u.y(), u.x(), 0.0;
  return S;
}

/// @brief Inverse of hat: the vector of the skew-symmetric part of S.
inline Vec3 vee(const Mat3& S) {
  return Vec3(S(2, 1) - S(1, 2), S(0, 2) - S(2, 0), S(1, 0) - S(0, 1)) * 0.5;
}

/// @brief Exponential map of SO(3): rotation by angle |w| about axis w/|w| (Rodrigues).
/// Exact to machine precision for all w, including w = 0.
Mat3 exp_so3(const Vec3& w);

/// @brief Logarithm map of SO(3): the rotation vector w with exp_so3(w) == R, |w| in [0, pi].
/// R must be a rotation (use nearest_rotation first if it may have drifted).
Vec3 log_so3(const Mat3& R);

/// @brief Left Jacobian V(w) of SO(3), t = |w|:
/// V(w) = I + (1 - cos t)/t^2 [w]x + (t - sin t)/t^3 [w]x^2 (series expansions near t = 0).
/// It is the translation part of the SE(3) exponential: exp_se3(u, v).p == V(u) v.
Mat3 left_jacobian_so3(const Vec3& w);

/// @brief Exponential map of SE(3) for a constant twist over unit length: the frame reached
/// from the identity by moving with body angular velocity u and body linear velocity v for
/// s = 1. This is the exact solution of dR/ds = R[u], dp/ds = R v with constant u, v.
Frame exp_se3(const Vec3& u, const Vec3& v);

/// @brief Rotation about the x axis by angle a (rad).
Mat3 rot_x(double a);
/// @brief Rotation about the y axis by angle a (rad), paper Eq. 10.
Mat3 rot_y(double a);
/// @brief Rotation about the z axis by angle a (rad), paper Eq. 9.
Mat3 rot_z(double a);

/// @brief Angle (rad, in [0, pi]) of the relative rotation A B^T, the e_R term of paper Eq. 57.
/// Computed robustly with atan2 of the vee and trace parts, so it is accurate near 0 and pi
/// and never NaN for slightly non-orthonormal inputs.
double rotation_angle(const Mat3& A, const Mat3& B);

/// @brief Nearest rotation matrix (orthogonal polar factor) of M, with det = +1.
Mat3 nearest_rotation(const Mat3& M);

/// @brief Frobenius norm of R^T R - I: how far a matrix is from orthonormal.
double orthonormality_error(const Mat3& R);

}  // namespace tdcr::lie
