// VC's kink fixed point (vc::kink_fixed_point, models/vc/vc_shooting.cpp): the wrench z just
// distal of a disk where point loads make the strains jump, so that every tensioned tendon
// continuing past the disk turns there and pulls with T R (t+ - t-), t+ depending on z.
//
// The two cases are states met by VC's damped snap on s1135 (draw 135 beyond the loaded-scene
// suite: E x 0.17, n = 5; tendon T1 at 2 EI / r^2 terminating at disk 5, T4 continuing),
// printed in full precision. In the first the fixed-point iteration does not contract and plain
// Newton fell into a 2-cycle (scaled |h| 0.50 for 30 iterations); Newton with backtracking
// converges. In the second no root exists: the least |h| lies where T4's path just distal of the
// disk reaches its geometric limit (curvature x offset 1), and the solver must say so.
#include <gtest/gtest.h>

#include <vector>

#include "tdcr/models/cosserat_rod.hpp"
#include "vc/vc_shooting.hpp"

using namespace tdcr;

namespace {

constexpr double kForceScale = 33.643966473790776, kMomentScale = 0.39676926026396042;

cosserat::Section s1135_section() {
  cosserat::Section S;
  S.kbt = Vec3(0.00072129144807949624, 0.00072129144807949624, 0.00055483957544576635);
  S.kse = Vec3(6935.4946930720798, 6935.4946930720798, 18032.286201987408);
  S.inv_kbt = S.kbt.cwiseInverse();
  S.inv_kse = S.kse.cwiseInverse();
  S.shear_extension = true;
  return S;
}

struct KinkCase {
  double R[9];  // column-major
  Vec3 u, v;
  double T;
  Vec6 base;
};

// Scaled |z - G(z)| and the continuing tendon's curvature x offset just distal of the disk,
// c+ = 1 - q+ . v+ / |v+|^2.
struct KinkCheck {
  double residual;
  double c_plus;
};

KinkCheck check(const vc::KinkMap<double>& G, const Vec6& z) {
  Vec6 scale;
  scale << Vec3::Constant(kForceScale), Vec3::Constant(kMomentScale);
  const Vec3 up = G.S.curvature(G.R, z.tail<3>()), vp = G.S.strain(G.R, z.head<3>());
  const Vec3 q = vp + up.cross(G.tendons[0].r);
  return {(z - G(z)).cwiseQuotient(scale).norm(), 1.0 - q.dot(vp) / vp.squaredNorm()};
}

}  // namespace

TEST(VcKinks, BacktrackingNewtonFindsTheRootPlainNewtonCycledAround) {
  const cosserat::Section S = s1135_section();
  const KinkCase k{{0.69066342807845971, 0.38002157525875169, -0.61507219059522045, 0.64363547777497787,
                    0.064710801902822912, 0.76243765507531347, 0.32990718154830034, -0.9224810061587827,
                    -0.20011421378295699},
                   Vec3(-96.944333993040246, 29.853150069202485, -0.97608587167373817),
                   Vec3(-0.00020461763523840697, 0.00012320559184407124, 0.99848826614417041),
                   7.5886999034682212,
                   (Vec6() << -2.5352395907762872, 6.9824045704530775, 2.6843679407868066, 0.071053662294053868,
                    0.039359003488550579, -0.035080624015538409)
                       .finished()};
  const std::vector<cosserat::TendonLoad> tendons = {cosserat::TendonLoad::make(Vec3(0.0, -0.008, 0.0), k.T)};
  const vc::KinkMap<double> G{S, Eigen::Map<const Mat3>(k.R), k.u, k.v, tendons, k.base};
  // Before the disk the tendon runs on the outside of the bend (c- < 0); the kink turns it.
  const Vec3 qm = k.v + k.u.cross(tendons[0].r);
  EXPECT_LT(1.0 - qm.dot(k.v) / k.v.squaredNorm(), -0.5);
  Vec6 z = k.base;
  ASSERT_TRUE(vc::kink_fixed_point(G, kForceScale, kMomentScale, z));
  const KinkCheck c = check(G, z);
  EXPECT_LT(c.residual, 1e-12);
  // A buildable kink: the tendon's path distal of the disk stays short of its limit.
  EXPECT_GT(c.c_plus, 0.5);
  EXPECT_LT(c.c_plus, 0.99);
}

TEST(VcKinks, NoRootAtTheTendonLimitIsAFailureNeverASuccess) {
  const cosserat::Section S = s1135_section();
  const KinkCase k{{0.73827427599438311, -0.048129101121416294, 0.67278534352403008, 0.67039034647190177,
                    -0.057710359284002199, -0.73976739782683087, 0.074441489707590291, 0.99717277532738358,
                    -0.010334075119149008},
                   Vec3(-50.772264613293629, 22.353322086341741, -6.8909534911325965),
                   Vec3(-8.5658501758119996e-05, -0.00010466964379606032, 0.99846217341850696),
                   7.9002583998978508,
                   (Vec6() << -0.10613159952220075, -7.5574752092223321, 1.4794334527042019, 0.10150598894112042,
                    -0.025702669364475406, 0.072196592440601115)
                       .finished()};
  const std::vector<cosserat::TendonLoad> tendons = {cosserat::TendonLoad::make(Vec3(0.0, -0.008, 0.0), k.T)};
  const vc::KinkMap<double> G{S, Eigen::Map<const Mat3>(k.R), k.u, k.v, tendons, k.base};
  Vec6 z = k.base;
  EXPECT_FALSE(vc::kink_fixed_point(G, kForceScale, kMomentScale, z));
  // No root along the segment from the start towards the limit: |h| stays away from 0 on a
  // line through the start in every wrench direction sampled (a coarse scan, not a proof).
  double least = INFINITY;
  for (int d = 0; d < 6; ++d)
    for (double t = -2.0; t <= 2.0; t += 0.01) {
      Vec6 zt = k.base;
      zt[d] += t * (d < 3 ? kForceScale : kMomentScale);
      const KinkCheck c = check(G, zt);
      if (std::isfinite(c.residual)) least = std::min(least, c.residual);
    }
  EXPECT_GT(least, 1e-3);
}
