// The Cosserat rod's right-hand side (cosserat_rod.hpp, written once for VC and VCref) against
// an exactly known solution and against finite differences of the tendon load it must balance.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "tdcr/bvp/integrator.hpp"
#include "tdcr/core/lie.hpp"
#include "tdcr/core/paper_robot.hpp"
#include "tdcr/models/cosserat_rod.hpp"

using namespace tdcr;
using namespace tdcr::cosserat;

namespace {

Section paper_section(bool shear, const Vec3& weight) {
  Effects e;
  e.shear_extension = shear;
  return Section::from(paper::robot(10), e, weight);
}

// A state away from every symmetry (paper robot: EI ~ 2.6e-3 N m^2, so |u| ~ 5 rad/m).
State generic_state() {
  const Frame f = lie::exp_se3(Vec3(0.3, -0.2, 0.5), Vec3(0.01, 0.02, 0.03));
  return make_state(f, Vec3(0.3, -0.2, -1.5), Vec3(0.01, -0.008, 0.004));
}

// The rod with a fixed tendon list, as an ODE (what VC integrates along a segment).
class LoadedRod final : public bvp::OdeSystem {
 public:
  LoadedRod(const Section& s, std::vector<TendonLoad> t) : s_(s), t_(std::move(t)) {}
  int dimension() const override { return kStateSize; }
  void rhs(double, const double* y, double* dyds) const override {
    rod_rhs(s_, t_.data(), static_cast<int>(t_.size()), y, dyds);
  }

 private:
  Section s_;
  std::vector<TendonLoad> t_;
};

// World-frame unit tangent of a fully constrained tendon at the state y: R q / |q|, q = v + u x r.
Vec3 tendon_direction(const Section& s, const double* y, const Vec3& r) {
  const Mat3 R = rotation(y);
  const Vec3 q = s.strain(R, force(y)) + s.curvature(R, moment(y)).cross(r);
  return R * q.normalized();
}

}  // namespace

// FreeRod is rod_rhs without tendons, bit for bit, for every combination of effects; a tendon
// of zero tension (which takes the tendon path, with its linear solve) gives the free rod up to
// rounding.
TEST(CosseratRod, FreeRodIsTheRightHandSideWithoutTendons) {
  const State y = generic_state();
  for (bool shear : {true, false})
    for (const Vec3& w : {Vec3(Vec3::Zero()), Vec3(0.1, -0.3, -0.2)}) {
      const Section s = paper_section(shear, w);
      State a, b, c;
      FreeRod(s).rhs(0.0, y.data(), a.data());
      rod_rhs(s, nullptr, 0, y.data(), b.data());
      for (int i = 0; i < kStateSize; ++i) EXPECT_EQ(a[i], b[i]) << "state " << i << " shear " << shear;
      const TendonLoad slack = TendonLoad::make(Vec3(0.004, 0.003, 0), 0.0);
      rod_rhs(s, &slack, 1, y.data(), c.data());
      EXPECT_LT((c - a).head<12>().norm(), 1e-15 * a.head<12>().norm()) << "shear " << shear;
      EXPECT_LT((c - a).segment<3>(12).norm(), 1e-12 * (1.0 + w.norm())) << "shear " << shear;
      EXPECT_LT((c - a).tail<3>().norm(), 1e-12 * a.tail<3>().norm()) << "shear " << shear;
    }
}

// A rod under a pure moment is a circular arc: with u = (kx, ky, 0) in the body frame and n = 0,
// p(s), R(s) = exp_se3(u s, e_z s) and m(s) = EI R(s) u (constant in the base frame). The
// right-hand side at y(s) equals the central difference (y(s + h) - y(s - h)) / (2h) up to
// O(h^2 |u|^3) (~1e-9 at h = 1e-5).
TEST(CosseratRod, CircularArcUnderPureMomentMatchesFiniteDifferences) {
  const double kx = 21.0, ky = -8.0;
  for (bool shear : {true, false}) {
    const Section s = paper_section(shear, Vec3::Zero());
    const Vec3 u(kx, ky, 0.0);
    const double EI = 1.0 / s.inv_kbt.x();
    auto exact = [&](double t) {
      const Frame f = lie::exp_se3(u * t, Vec3::UnitZ() * t);
      return make_state(f, Vec3::Zero(), EI * (f.R * u));
    };
    const Vec3 m0 = exact(0.0).tail<3>();
    const double h = 1e-5;
    for (double t : {0.0, 0.02, 0.07}) {
      const State y = exact(t);
      EXPECT_LT((y.tail<3>() - m0).norm(), 1e-15 * m0.norm());  // the moment is constant
      State f;
      rod_rhs(s, nullptr, 0, y.data(), f.data());
      const State fd = (exact(t + h) - exact(t - h)) / (2 * h);
      EXPECT_LT((f.head<3>() - fd.head<3>()).norm(), 1e-8) << "p' at s = " << t;
      EXPECT_LT((f.segment<9>(3) - fd.segment<9>(3)).norm(), 1e-6) << "R' at s = " << t;
      EXPECT_EQ(f.segment<3>(12).norm(), 0.0);  // n' = 0 without gravity
      EXPECT_EQ(f.tail<3>().norm(), 0.0);       // m' = -p' x n = 0
    }
  }
}

// The tendon term balances the tendons' distributed loads: the solved (v_s, u_s) give
// n' = -(sum f_k + f_e) and m' = -p' x n - sum (R r_k) x f_k with f_k = T_k d/ds(R t_k), here
// from a central difference of the tendon direction along the rod's own solution (one RK4 step of
// +-h from y). The difference error is O(h^2): it falls 4x when h halves (a wrong tendon term
// would leave an error that does not fall).
TEST(CosseratRod, TendonTermBalancesFiniteDifferenceTendonForces) {
  const std::vector<TendonLoad> tendons = {TendonLoad::make(Vec3(0.004, 0.0, 0.0), 3.0),
                                           TendonLoad::make(Vec3(-0.002, 0.0035, 0.0), 5.0),
                                           TendonLoad::make(Vec3(0.0, -0.004, 0.0), 1.5)};
  const State y0 = generic_state();
  for (bool shear : {true, false})
    for (const Vec3& w : {Vec3(Vec3::Zero()), Vec3(0.2, -0.5, 0.1)}) {
      const Section s = paper_section(shear, w);
      const LoadedRod rod(s, tendons);
      State f;
      rod.rhs(0.0, y0.data(), f.data());
      const Vec3 dn = f.segment<3>(12), dm = f.tail<3>();
      auto balance_error = [&](double h) {
        bvp::Rk4Integrator rk(1);
        State yp = y0, ym = y0;
        EXPECT_TRUE(rk.integrate(rod, 0.0, h, yp.data()));
        EXPECT_TRUE(rk.integrate(rod, 0.0, -h, ym.data()));
        Vec3 sum_f = Vec3::Zero(), sum_l = Vec3::Zero();
        const Mat3 R = rotation(y0.data());
        for (const TendonLoad& t : tendons) {
          const Vec3 fk =
              t.T * (tendon_direction(s, yp.data(), t.r) - tendon_direction(s, ym.data(), t.r)) / (2 * h);
          sum_f += fk;
          sum_l += (R * t.r).cross(fk);
        }
        const Vec3 fe = s.gravity ? s.weight : Vec3::Zero();
        const Vec3 dp = f.head<3>();
        const double en = (dn + sum_f + fe).norm();
        const double em = (dm + dp.cross(Vec3(force(y0.data()))) + sum_l).norm();
        return std::make_pair(en, em);
      };
      const auto [en, em] = balance_error(2e-5);
      const auto [en2, em2] = balance_error(1e-5);
      // |n'| ~ 28 N/m, |m'| ~ 0.7 N: measured 3.7e-6 and 3.5e-9 at h = 2e-5 (1e-7 and 5e-9
      // relative), the difference error.
      EXPECT_LT(en, 1e-5) << "shear " << shear << " gravity " << w.norm();
      EXPECT_LT(em, 1e-8) << "shear " << shear << " gravity " << w.norm();
      EXPECT_GT(en / en2, 3.0) << "force balance error is not O(h^2): " << en << " " << en2;
      EXPECT_GT(em / em2, 3.0) << "moment balance error is not O(h^2): " << em << " " << em2;
      EXPECT_GT(dn.norm(), 10.0);  // the tendon load is not negligible
    }
}
