#include "tdcr/core/lie.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/SVD>

namespace tdcr::lie {

Mat3 exp_so3(const Vec3& w) {
  const double t2 = w.squaredNorm();
  const double t = std::sqrt(t2);
  // Series below ~1e-4 rad: the closed forms lose digits to cancellation there.
  double a, b;
  if (t < 1e-4) {
    a = 1.0 - t2 / 6.0 + t2 * t2 / 120.0;
    b = 0.5 - t2 / 24.0 + t2 * t2 / 720.0;
  } else {
    a = std::sin(t) / t;
    b = (1.0 - std::cos(t)) / t2;
  }
  const Mat3 W = hat(w);
  return Mat3::Identity() + a * W + b * W * W;
}

Vec3 log_so3(const Mat3& R) {
  // atan2 of the sine part (vee of the skew part) and the cosine part (trace) is accurate over
  // the whole range; near pi the axis comes from the symmetric part instead.
  const Vec3 s = vee(R);  // = sin(t) * axis
  const double c = std::clamp((R.trace() - 1.0) * 0.5, -1.0, 1.0);
  const double sn = s.norm();
  const double t = std::atan2(sn, c);
  if (t < 1e-6) return s * (1.0 + t * t / 6.0);
  if (M_PI - t > 1e-6) return s * (t / sn);
  // Near pi: R ~ 2 a a^T - I; take the best-conditioned column of (R + I) / 2.
  const Mat3 B = (R + Mat3::Identity()) * 0.5;
  int k;
  B.diagonal().maxCoeff(&k);
  Vec3 axis = B.col(k) / std::sqrt(std::max(B(k, k), 1e-300));
  axis.normalize();
  if (axis.dot(s) < 0.0) axis = -axis;
  return axis * t;
}

Mat3 left_jacobian_so3(const Vec3& w) {
  const double t2 = w.squaredNorm();
  const double t = std::sqrt(t2);
  double b, c;
  if (t < 1e-4) {
    b = 0.5 - t2 / 24.0;
    c = 1.0 / 6.0 - t2 / 120.0;
  } else {
    b = (1.0 - std::cos(t)) / t2;
    c = (t - std::sin(t)) / (t2 * t);
  }
  const Mat3 W = hat(w);
  return Mat3::Identity() + b * W + c * W * W;
}

Frame exp_se3(const Vec3& u, const Vec3& v) {
  return Frame{exp_so3(u), left_jacobian_so3(u) * v};
}

Mat3 rot_x(double a) {
  Mat3 R;
  const double c = std::cos(a), s = std::sin(a);
  R << 1, 0, 0, 0, c, -s, 0, s, c;
  return R;
}

Mat3 rot_y(double a) {
  Mat3 R;
  const double c = std::cos(a), s = std::sin(a);
  R << c, 0, s, 0, 1, 0, -s, 0, c;
  return R;
}

Mat3 rot_z(double a) {
  Mat3 R;
  const double c = std::cos(a), s = std::sin(a);
  R << c, -s, 0, s, c, 0, 0, 0, 1;
  return R;
}

double rotation_angle(const Mat3& A, const Mat3& B) {
  const Mat3 D = nearest_rotation(A) * nearest_rotation(B).transpose();
  const double c = (D.trace() - 1.0) * 0.5;
  const double s = vee(D).norm();
  return std::atan2(s, c);
}

Mat3 nearest_rotation(const Mat3& M) {
  // Nearly a rotation (disk frames of an integrated or rebuilt shape, orthonormal to round-off):
  // Newton-Schulz, X <- X (3 I - X^T X) / 2, keeps the singular vectors and takes every singular
  // value to 1 quadratically, so it converges to the polar factor U V^T, the SVD's answer, in one
  // or two steps at a tenth of the SVD's cost (VCref's warm guess takes one per disk per solve).
  constexpr double kNearlyOrthonormal = 1e-3;
  if (orthonormality_error(M) < kNearlyOrthonormal && M.determinant() > 0.0) {
    Mat3 X = M;
    for (int k = 0; k < 4; ++k) {
      const Mat3 E = X.transpose() * X - Mat3::Identity();
      if (E.cwiseAbs().maxCoeff() <= 4.0 * std::numeric_limits<double>::epsilon()) break;
      X = X * (Mat3::Identity() - 0.5 * E);
    }
    return X;
  }
  Eigen::JacobiSVD<Mat3> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 U = svd.matrixU();
  const Mat3 V = svd.matrixV();
  if ((U * V.transpose()).determinant() < 0.0) U.col(2) *= -1.0;
  return U * V.transpose();
}

double orthonormality_error(const Mat3& R) {
  return (R.transpose() * R - Mat3::Identity()).norm();
}

}  // namespace tdcr::lie
