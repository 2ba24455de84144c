// Property tests of the SO(3)/SE(3) helpers (manif style): identities that must hold for every
// sample, plus analytic-vs-numerical derivative checks.
#include <random>

#include <Eigen/SVD>
#include <gtest/gtest.h>

#include "tdcr/core/lie.hpp"

using namespace tdcr;

namespace {
std::vector<Vec3> samples() {
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Vec3> out = {Vec3::Zero(), Vec3(1e-9, 0, 0), Vec3(0, 1e-5, 2e-5), Vec3(0, 0, M_PI - 1e-9),
                           Vec3(M_PI / 2, 0, 0), Vec3(0, 3.0, 0.5)};
  for (int i = 0; i < 50; ++i) {
    Vec3 w(u(rng), u(rng), u(rng));
    out.push_back(w.normalized() * (M_PI * 0.999 * std::abs(u(rng))));
  }
  return out;
}
}  // namespace

TEST(Lie, HatIsCrossProduct) {
  for (const Vec3& w : samples()) {
    const Vec3 v(0.3, -1.2, 2.0);
    EXPECT_LT((lie::hat(w) * v - w.cross(v)).norm(), 1e-15);
    EXPECT_LT((lie::vee(lie::hat(w)) - w).norm(), 1e-15);
  }
}

TEST(Lie, ExpIsRotation) {
  for (const Vec3& w : samples()) {
    const Mat3 R = lie::exp_so3(w);
    EXPECT_LT(lie::orthonormality_error(R), 1e-14);
    EXPECT_NEAR(R.determinant(), 1.0, 1e-14);
    EXPECT_LT((R * w - w).norm(), 1e-14) << "the axis is fixed";
  }
}

TEST(Lie, LogInvertsExp) {
  for (const Vec3& w : samples()) {
    EXPECT_LT((lie::log_so3(lie::exp_so3(w)) - w).norm(), 1e-8 * std::max(1.0, w.norm())) << w.transpose();
  }
}

TEST(Lie, ExpMatchesElementaryRotations) {
  for (double a : {0.0, 0.1, -1.3, 3.0}) {
    EXPECT_LT((lie::exp_so3(Vec3(a, 0, 0)) - lie::rot_x(a)).norm(), 1e-15);
    EXPECT_LT((lie::exp_so3(Vec3(0, a, 0)) - lie::rot_y(a)).norm(), 1e-15);
    EXPECT_LT((lie::exp_so3(Vec3(0, 0, a)) - lie::rot_z(a)).norm(), 1e-15);
  }
}

TEST(Lie, RotationAngleIsTheGeodesicDistance) {
  for (const Vec3& w : samples()) {
    const Mat3 A = lie::exp_so3(Vec3(0.2, -0.1, 0.4));
    const Mat3 B = lie::exp_so3(w) * A;
    EXPECT_NEAR(lie::rotation_angle(B, A), w.norm(), 1e-12);
  }
  // Slightly non-orthonormal input (as integrated frames are) gives no NaN.
  Mat3 R = Mat3::Identity() * (1.0 + 1e-6);
  EXPECT_NEAR(lie::rotation_angle(R, Mat3::Identity()), 0.0, 1e-12);
}

TEST(Lie, ExpDerivativeMatchesFiniteDifference) {
  // d/ds exp(s w) = exp(s w) hat(w): compare with a central difference.
  for (const Vec3& w : samples()) {
    const double s = 0.7, h = 1e-6;
    const Mat3 num = (lie::exp_so3((s + h) * w) - lie::exp_so3((s - h) * w)) / (2 * h);
    const Mat3 ana = lie::exp_so3(s * w) * lie::hat(w);
    EXPECT_LT((num - ana).norm(), 1e-8 * std::max(1.0, w.squaredNorm()));
  }
}

TEST(Lie, Se3ExpSolvesConstantStrainOde) {
  // exp_se3(u, v) is the exact flow of R' = R hat(u), p' = R v over unit length; check against a
  // fine RK4 integration.
  for (const Vec3& u : samples()) {
    const Vec3 v(0.1, -0.2, 1.0);
    Mat3 R = Mat3::Identity();
    Vec3 p = Vec3::Zero();
    const int N = 2000;
    const double h = 1.0 / N;
    auto f = [&](const Mat3& Ri) { return std::make_pair(Mat3(Ri * lie::hat(u)), Vec3(Ri * v)); };
    for (int i = 0; i < N; ++i) {
      auto k1 = f(R);
      auto k2 = f(R + 0.5 * h * k1.first);
      auto k3 = f(R + 0.5 * h * k2.first);
      auto k4 = f(R + h * k3.first);
      p += h / 6 * (k1.second + 2 * k2.second + 2 * k3.second + k4.second);
      R += h / 6 * (k1.first + 2 * k2.first + 2 * k3.first + k4.first);
    }
    const Frame F = lie::exp_se3(u, v);
    EXPECT_LT((F.R - R).norm(), 1e-10);
    EXPECT_LT((F.p - p).norm(), 1e-10);
  }
}

TEST(Lie, NearestRotationIsIdempotentAndFixesDrift) {
  const Mat3 R = lie::exp_so3(Vec3(0.3, 0.2, -0.5));
  EXPECT_LT((lie::nearest_rotation(R) - R).norm(), 1e-14);
  Mat3 D = R;
  D(0, 1) += 1e-4;
  EXPECT_LT(lie::orthonormality_error(lie::nearest_rotation(D)), 1e-14);
  EXPECT_LT((lie::nearest_rotation(D) - R).norm(), 2e-4);
}

// The nearest rotation is the polar factor U V^T of the SVD M = U S V^T (det > 0): for matrices
// near a rotation (drift 1e-15 to 5e-4, inside and at the edge of the Newton-Schulz fast path)
// and far from one (1e-2, 0.3: the SVD path), random rotations and perturbations, the answer is
// that polar factor to round-off, and a rotation.
TEST(Lie, NearestRotationIsTheSvdPolarFactor) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (double drift : {1e-15, 1e-10, 1e-6, 5e-4, 1e-2, 0.3}) {
    for (int trial = 0; trial < 50; ++trial) {
      const Mat3 R = lie::exp_so3(3.0 * Vec3(u(rng), u(rng), u(rng)));
      Mat3 P;
      for (int i = 0; i < 9; ++i) P(i / 3, i % 3) = u(rng);
      const Mat3 M = R + drift * P;
      Eigen::JacobiSVD<Mat3> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
      const Mat3 polar = svd.matrixU() * svd.matrixV().transpose();
      ASSERT_GT(polar.determinant(), 0.0);
      const Mat3 N = lie::nearest_rotation(M);
      EXPECT_LT((N - polar).cwiseAbs().maxCoeff(), 1e-13) << "drift " << drift;
      EXPECT_LT(lie::orthonormality_error(N), 1e-14) << "drift " << drift;
      EXPECT_NEAR(N.determinant(), 1.0, 1e-14);
    }
  }
}

TEST(Frame, ComposeAndInverse) {
  const Frame A{lie::exp_so3(Vec3(0.1, 0.2, 0.3)), Vec3(1, 2, 3)};
  const Frame B{lie::exp_so3(Vec3(-0.4, 0.0, 0.9)), Vec3(-1, 0.5, 2)};
  const Frame I = A * A.inverse();
  EXPECT_LT((I.R - Mat3::Identity()).norm(), 1e-14);
  EXPECT_LT(I.p.norm(), 1e-14);
  EXPECT_LT(((A * B).matrix() - A.matrix() * B.matrix()).norm(), 1e-14);
}
