// Tendon routing beyond straight (helical, hole positions per disk): the routed models reduce to
// straight routing where the routing is straight, a helical tendon twists the robot as well as
// bending it, VCref tends to VC as the disks grow, and VC agrees with an independent RK4 + shooting
// integration of Rucker & Webster's equations (2011, "Statics and dynamics of continuum robots
// with general tendon routing and external loading") written here in their own form.
#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "tdcr/core/error.hpp"
#include "tdcr/core/lie.hpp"
#include "tdcr/core/paper_robot.hpp"
#include "tdcr/core/scene_io.hpp"
#include "tdcr/models/static_model.hpp"
#include "tdcr/models/verification.hpp"

using namespace tdcr;

namespace {

using Type = TendonRoutingSpec::Type;

Solution solve_kind(ModelKind kind, const Scene& s) {
  auto m = make_model(kind, s.robot, s.effects);
  auto ws = m->make_workspace();
  return solve(*m, *ws, s.input(), s.solver);
}

/// The paper robot (2 segments, 10 disks each) under a tension set that bends and twists it.
Scene paper_scene() {
  Scene s = paper::scene(10, 1, "vc");
  s.actuation.values = {2.0, 0.0, 0.0, 1.0};
  return s;
}

/// Every tendon of `s` routed by `make(tendon, disks it passes after the base)`.
template <class Make>
Scene routed(Scene s, Make make) {
  int passed = 0;
  for (Segment& seg : s.robot.segments) {
    passed += seg.disks;
    for (TendonSpec& t : seg.tendons) t.routing = make(t, passed);
  }
  return s;
}

TendonRoutingSpec helix(double turns) {
  TendonRoutingSpec r;
  r.type = Type::Helical;
  r.turns = turns;
  return r;
}

double max_frame_error(const Solution& a, const Solution& b) {
  EXPECT_EQ(a.disk_frames.size(), b.disk_frames.size());
  double e = 0.0;
  for (std::size_t j = 0; j < a.disk_frames.size() && j < b.disk_frames.size(); ++j) {
    e = std::max(e, (a.disk_frames[j].p - b.disk_frames[j].p).norm());
    e = std::max(e, 0.1 * (a.disk_frames[j].R - b.disk_frames[j].R).norm());  // 0.1 m lever
  }
  return e;
}

const ModelKind kRouted[] = {ModelKind::CCsub, ModelKind::PRB, ModelKind::VC, ModelKind::VCref};

/// One segment of length L with one tendon at radius rho, routed helically by `turns`.
Scene helical_robot(int disks, double turns, double tension, double L = 0.1, double rho = 0.008) {
  Scene s;
  s.robot.backbone.outer_radius = 0.0005;
  Segment seg;
  seg.length = L;
  seg.disks = disks;
  TendonSpec t(rho, 0.0);
  t.routing = helix(turns);
  seg.tendons = {t};
  s.robot.segments = {seg};
  s.actuation.kind = Actuation::Kind::Tensions;
  s.actuation.values = {tension};
  s.model = "vc";
  return s;
}

}  // namespace

// A helix of zero turns is the straight tendon (to rounding), in every model that takes routing;
// CC refuses any non-straight routing, naming the field.
TEST(TendonRouting, ZeroTurnHelixEqualsStraight) {
  const Scene straight = paper_scene();
  const Scene zero = routed(straight, [](const TendonSpec&, int) { return helix(0.0); });
  for (ModelKind k : kRouted) {
    const Solution a = solve_kind(k, straight), b = solve_kind(k, zero);
    ASSERT_TRUE(a.converged()) << a.summary.message << to_string(k);
    ASSERT_TRUE(b.converged()) << b.summary.message << to_string(k);
    EXPECT_GT((a.disk_frames.back().p - Vec3(0, 0, 0.2)).norm(), 0.01) << "the robot bends";
    EXPECT_LT(max_frame_error(a, b), 1e-10) << to_string(k);
    for (std::size_t i = 0; i < a.tendon_displacements.size(); ++i)
      EXPECT_NEAR(a.tendon_displacements[i], b.tendon_displacements[i], 1e-10) << to_string(k);
  }
  try {
    make_model(ModelKind::CC, zero.robot, zero.effects);
    FAIL() << "CC took a helical tendon";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("robot.segments[0].tendons[0].routing"), std::string::npos) << e.what();
  }
}

// A straight tendon given as one hole position per disk is the straight tendon.
TEST(TendonRouting, StraightPointsEqualStraight) {
  const Scene straight = paper_scene();
  const Scene points = routed(straight, [](const TendonSpec& t, int passed) {
    TendonRoutingSpec r;
    r.type = Type::Points;
    r.positions.assign(passed, {t.x, t.y});
    return r;
  });
  for (ModelKind k : kRouted) {
    const Solution a = solve_kind(k, straight), b = solve_kind(k, points);
    ASSERT_TRUE(b.converged()) << b.summary.message << to_string(k);
    EXPECT_LT(max_frame_error(a, b), 1e-10) << to_string(k);
    for (std::size_t i = 0; i < a.tendon_displacements.size(); ++i)
      EXPECT_NEAR(a.tendon_displacements[i], b.tendon_displacements[i], 1e-10) << to_string(k);
  }
}

// A helical tendon twists the robot about its axis as well as bending it; a straight one does not
// twist it. Hole positions sampled from the helix give nearly the same shape.
TEST(TendonRouting, HelicalTendonTwistsAndBends) {
  const Scene straight = helical_robot(20, 0.0, 1.0);
  Scene s = helical_robot(20, 0.5, 1.0);
  for (ModelKind k : kRouted) {
    const Solution a = solve_kind(k, s), b = solve_kind(k, straight);
    ASSERT_TRUE(a.converged()) << a.summary.message << to_string(k);
    const Vec3 w = lie::log_so3(a.disk_frames.back().R), w0 = lie::log_so3(b.disk_frames.back().R);
    EXPECT_GT(std::abs(w.z()), 0.01) << to_string(k) << " twist " << w.transpose();
    EXPECT_GT(w.head<2>().norm(), 0.02) << to_string(k) << " bend " << w.transpose();
    EXPECT_LT(std::abs(w0.z()), 1e-9) << to_string(k);
  }
  // The same helix as hole positions (VC: through its spline).
  Scene pts = s;
  TendonRoutingSpec& r = pts.robot.segments[0].tendons[0].routing;
  r.type = Type::Points;
  for (int j = 1; j <= 20; ++j) {
    const double a = M_PI * j / 20.0;
    r.positions.push_back({0.008 * std::cos(a), 0.008 * std::sin(a)});
  }
  const Solution a = solve_kind(ModelKind::VC, s), b = solve_kind(ModelKind::VC, pts);
  ASSERT_TRUE(b.converged()) << b.summary.message;
  EXPECT_LT((a.disk_frames.back().p - b.disk_frames.back().p).norm(), 2e-4);
  EXPECT_GT((a.disk_frames.back().p - b.disk_frames.back().p).norm(), 0.0);
}

// VCref's chords between holes tend to VC's continuous helix as the disks grow, at second order (the
// chord of a smooth path is off by O(h^2); measured 2.03e-5, 5.08e-6, 1.27e-6 m at n = 10, 20, 40).
TEST(TendonRouting, VcrefTendsToVcAsDisksGrow) {
  std::vector<double> err;
  for (int n : {10, 20, 40}) {
    const Scene s = helical_robot(n, 0.5, 1.0);
    const Solution vc = solve_kind(ModelKind::VC, s), ref = solve_kind(ModelKind::VCref, s);
    ASSERT_TRUE(vc.converged()) << vc.summary.message;
    ASSERT_TRUE(ref.converged()) << ref.summary.message;
    err.push_back((vc.disk_frames.back().p - ref.disk_frames.back().p).norm());
  }
  for (int i = 1; i < 3; ++i) {
    EXPECT_LT(err[i], 0.35 * err[i - 1]) << err[i - 1] << " " << err[i];
    EXPECT_GT(err[i], 0.15 * err[i - 1]) << err[i - 1] << " " << err[i] << ": about second order";
  }
}

namespace {

// Rucker & Webster 2011, Eq. (numbers of the paper's Section III): states p, R, v, u; the tendon
// path p_i = p + R r_i(s) with r_i a helix; v', u' from
//   [Kse + A, G; B, Kbt + H] [v'; u'] = [d; c],
//   A_i = -tau_i [p_i']x^2 / |p_i'|^3 (p_i' = u x r_i + r_i' + v, body frame), G_i = -A_i [r_i]x,
//   a_i = A_i (u x p_i' + u x r_i' + r_i''), B = sum [r_i]x A_i, H = sum [r_i]x G_i,
//   d = -u x Kse (v - e3) - a,  c = -u x Kbt u - v x Kse (v - e3) - sum r_i x a_i,
// and at the tip Kse (v - e3) = R^T F - sum tau_i t_i, Kbt u = -sum tau_i r_i x t_i.
struct RwHelix {
  double L, rho, rate, tau;
  Eigen::Vector3d kse, kbt, F;
  using V = Eigen::Matrix<double, 19, 1>;  // p, R (column-major), v, u, tendon length

  static Eigen::Matrix3d hat(const Eigen::Vector3d& a) {
    Eigen::Matrix3d h;
    h << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
    return h;
  }
  void route(double s, Eigen::Vector3d& r, Eigen::Vector3d& dr, Eigen::Vector3d& ddr) const {
    const double a = rate * s;
    r = rho * Eigen::Vector3d(std::cos(a), std::sin(a), 0);
    dr = rho * rate * Eigen::Vector3d(-std::sin(a), std::cos(a), 0);
    ddr = -rate * rate * r;
  }
  V f(double s, const V& y) const {
    const Eigen::Map<const Eigen::Matrix3d> R(y.data() + 3);
    const Eigen::Vector3d v = y.segment<3>(12), u = y.segment<3>(15);
    Eigen::Vector3d r, dr, ddr;
    route(s, r, dr, ddr);
    const Eigen::Vector3d pb = u.cross(r) + dr + v;
    const double np = pb.norm();
    const Eigen::Matrix3d A = -tau * hat(pb) * hat(pb) / (np * np * np);
    const Eigen::Matrix3d G = -A * hat(r);
    const Eigen::Vector3d a = A * (u.cross(pb) + u.cross(dr) + ddr);
    const Eigen::Vector3d e3(0, 0, 1);
    const Eigen::Vector3d d = -u.cross(kse.cwiseProduct(v - e3)) - a;
    const Eigen::Vector3d c = -u.cross(kbt.cwiseProduct(u)) - v.cross(kse.cwiseProduct(v - e3)) - r.cross(a);
    Eigen::Matrix<double, 6, 6> M;
    M << Eigen::Matrix3d(kse.asDiagonal()) + A, G, hat(r) * A, Eigen::Matrix3d(kbt.asDiagonal()) + hat(r) * G;
    Eigen::Matrix<double, 6, 1> rhs;
    rhs << d, c;
    const Eigen::Matrix<double, 6, 1> x = M.partialPivLu().solve(rhs);
    V dy;
    dy.segment<3>(0) = R * v;
    Eigen::Map<Eigen::Matrix3d>(dy.data() + 3) = R * hat(u);
    dy.segment<6>(12) = x;
    dy[18] = np;
    return dy;
  }
  V shoot(const Eigen::Matrix<double, 6, 1>& vu0, int steps) const {
    V y = V::Zero();
    Eigen::Map<Eigen::Matrix3d>(y.data() + 3).setIdentity();
    y.segment<6>(12) = vu0;
    const double h = L / steps;
    for (int i = 0; i < steps; ++i) {
      const double s = i * h;
      const V k1 = f(s, y), k2 = f(s + h / 2, y + h / 2 * k1), k3 = f(s + h / 2, y + h / 2 * k2),
              k4 = f(s + h, y + h * k3);
      y += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
    }
    return y;
  }
  Eigen::Matrix<double, 6, 1> residual(const V& y) const {
    const Eigen::Map<const Eigen::Matrix3d> R(y.data() + 3);
    const Eigen::Vector3d v = y.segment<3>(12), u = y.segment<3>(15);
    Eigen::Vector3d r, dr, ddr;
    route(L, r, dr, ddr);
    const Eigen::Vector3d t = (u.cross(r) + dr + v).normalized();
    Eigen::Matrix<double, 6, 1> res;
    res << kse.cwiseProduct(v - Eigen::Vector3d::UnitZ()) - R.transpose() * F + tau * t,
        (kbt.cwiseProduct(u) + tau * r.cross(t)) / 0.01;
    return res;
  }
  V solve(int steps) const {
    Eigen::Matrix<double, 6, 1> x;
    x << 0, 0, 1, 0, 0, 0;
    for (int it = 0; it < 30; ++it) {
      const Eigen::Matrix<double, 6, 1> r0 = residual(shoot(x, steps));
      if (r0.norm() < 1e-13) break;
      Eigen::Matrix<double, 6, 6> J;
      for (int c = 0; c < 6; ++c) {
        Eigen::Matrix<double, 6, 1> xc = x;
        const double h = 1e-7 * (c < 3 ? 1e-3 : 1.0);
        xc[c] += h;
        J.col(c) = (residual(shoot(xc, steps)) - r0) / h;
      }
      x -= J.partialPivLu().solve(r0);
    }
    return shoot(x, steps);
  }
};

}  // namespace

// VC against the independent integration above: tip pose and the tendon's displacement.
TEST(TendonRouting, VcMatchesIndependentRuckerWebster) {
  Scene s = helical_robot(20, 0.75, 1.5);
  s.loads.tip_force = Vec3(0.05, -0.02, 0.0);
  s.solver.integrator = IntegratorKind::FixedStepRK4;
  s.solver.rk4_steps = 10;
  const BackboneStiffness k = s.robot.backbone.effective_stiffness();
  RwHelix rw{0.1, 0.008, 2 * M_PI * 0.75 / 0.1, 1.5, Eigen::Vector3d(k.GA, k.GA, k.EA),
             Eigen::Vector3d(k.EI, k.EI, k.GJ), Eigen::Vector3d(0.05, -0.02, 0.0)};
  const RwHelix::V y = rw.solve(2000);
  const Solution vc = solve_kind(ModelKind::VC, s);
  ASSERT_TRUE(vc.converged()) << vc.summary.message;
  const Frame& tip = vc.disk_frames.back();
  EXPECT_GT(y.head<3>().head<2>().norm(), 0.002) << "a real bend";
  EXPECT_LT((tip.p - y.head<3>()).norm(), 1e-8) << tip.p.transpose() << " vs " << y.head<3>().transpose();
  EXPECT_LT((tip.R - Eigen::Map<const Eigen::Matrix3d>(y.data() + 3)).norm(), 1e-7);
  // Displacement: the helix's rest length minus its loaded length.
  const double rest = std::hypot(1.0, rw.rho * rw.rate) * rw.L;
  EXPECT_NEAR(vc.tendon_displacements[0], rest - y[18], 1e-9);
}

// The routing survives a scene write and read; bad routing is refused naming the field.
TEST(TendonRouting, SceneRoundTripAndValidation) {
  Scene s = helical_robot(4, 1.25, 1.0);
  TendonSpec p(0.0, 0.008);
  p.routing.type = Type::Points;
  p.routing.positions = {{0.001, 0.008}, {0.002, 0.008}, {0.003, 0.0075}, {0.004, 0.007}};
  s.robot.segments[0].tendons.push_back(p);
  s.actuation.values = {1.0, 0.5};
  const Scene back = parse_scene(scene_to_json(s));
  ASSERT_EQ(back.robot.segments[0].tendons.size(), 2u);
  EXPECT_EQ(back.robot.segments[0].tendons[0].routing.type, Type::Helical);
  EXPECT_EQ(back.robot.segments[0].tendons[0].routing.turns, 1.25);
  EXPECT_EQ(back.robot.segments[0].tendons[1].routing.positions, p.routing.positions);
  EXPECT_EQ(scene_to_json(back), scene_to_json(s));

  Scene bad = s;
  bad.robot.segments[0].tendons[1].routing.positions.pop_back();
  try {
    bad.robot.validate();
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("robot.segments[0].tendons[1].routing.positions"), std::string::npos);
  }
}

namespace {

/// One 100 mm segment of the paper robot's backbone with two tendons 90 deg apart, (rho, 0) and
/// (0, rho), both helical by `turns`, pulled with 2 N and 1 N, and a tip force: a helical robot
/// whose shape is neither planar nor of constant curvature.
Scene adjacent_pair(int disks, double turns, const Vec3& tip_force) {
  Scene s = helical_robot(disks, turns, 2.0);
  s.robot.backbone.outer_radius = 0.0004;
  TendonSpec t(0.0, 0.008);
  t.routing = helix(turns);
  s.robot.segments[0].tendons.push_back(t);
  s.actuation.values = {2.0, 1.0};
  s.loads.tip_force = tip_force;
  return s;
}

}  // namespace

// A helical tendon under tension unwinds: the end disk turns about the axis against the helix's
// sense (the tendon shortens as its turns shrink), so +t and -t twist the tip by opposite angles.
// Under a small tension the twist is the torsion of the tendon's pull at the end disk, a moment
// T rho (rho phi') / |q| about the axis (phi' = 2 pi t / L, |q| = sqrt(1 + (rho phi')^2)), over
// the backbone's GJ: measured within 0.15 % in VC and 0.5 % in CCsub, PRB and VCref (20 disks) at 0.01 N.
TEST(TendonRouting, HelixTwistsAgainstItsTurns) {
  for (ModelKind k : kRouted)
    for (double turns : {0.5, -0.5, 0.25}) {
      Scene s = helical_robot(20, turns, 0.01);
      s.robot.backbone.outer_radius = 0.0004;
      const Solution a = solve_kind(k, s);
      ASSERT_TRUE(a.converged()) << a.summary.message << to_string(k);
      const double twist = lie::log_so3(a.disk_frames.back().R).z();
      const double rho = 0.008, L = 0.1, dphi = 2 * M_PI * turns / L;
      const double GJ = s.robot.backbone.effective_stiffness().GJ;
      const double expected = -0.01 * rho * rho * dphi / std::hypot(1.0, rho * dphi) * L / GJ;
      EXPECT_LT(twist * turns, 0.0) << to_string(k) << " turns " << turns << " twist " << twist;
      EXPECT_NEAR(twist, expected, 0.02 * std::abs(expected)) << to_string(k) << " turns " << turns;
    }
}

// Mirror symmetry: the scene reflected in the x-z plane (tendon holes (x, -y), turns -t, tip force
// (Fx, -Fy, Fz)) has the reflected shape, p -> M p and R -> M R M with M = diag(1, -1, 1), at every
// disk and in every model that takes routing.
TEST(TendonRouting, OppositeTurnsMirrorTheShape) {
  const Scene a = adjacent_pair(20, 0.5, Vec3(0.1, 0.2, 0.0));
  Scene b = a;
  for (TendonSpec& t : b.robot.segments[0].tendons) {
    t.y = -t.y;
    t.routing.turns = -t.routing.turns;
  }
  b.loads.tip_force.y() = -b.loads.tip_force.y();
  const Mat3 M = Vec3(1, -1, 1).asDiagonal();
  for (ModelKind k : kRouted) {
    const Solution sa = solve_kind(k, a), sb = solve_kind(k, b);
    ASSERT_TRUE(sa.converged()) << sa.summary.message << to_string(k);
    ASSERT_TRUE(sb.converged()) << sb.summary.message << to_string(k);
    EXPECT_GT(std::abs(sa.tip().p.y()), 0.01) << to_string(k) << ": the shape leaves the x-z plane";
    ASSERT_EQ(sa.disk_frames.size(), sb.disk_frames.size());
    for (std::size_t j = 0; j < sa.disk_frames.size(); ++j) {
      // To the solvers' tolerance (PRB: 4e-10 m, 1.2e-8 in R); a wrong sense of the turns is ~1e-2 off.
      EXPECT_LT((M * sa.disk_frames[j].p - sb.disk_frames[j].p).norm(), 1e-8) << to_string(k) << " disk " << j;
      EXPECT_LT((M * sa.disk_frames[j].R * M - sb.disk_frames[j].R).norm(), 1e-7) << to_string(k) << " disk " << j;
    }
  }
}

// The tendon force at a disk (docs/models.md): a frictionless hole keeps one tension on both sides,
// so the disk takes the whole T (t- + t+), normal component included. VCref with the default disk
// force converges to VC, its continuous limit, at second order on a helical robot with two tendons
// and a tip force (tips 2.2e-5, 5.6e-6, 1.4e-6 m from VC's at 10, 20, 40 disks); with Eq. 58 it
// levels off (0.65, 0.66, 0.67 mm): the normal force it drops is O(h) per disk on an inclined
// tendon, a finite force in all, which robot and tendons then miss.
TEST(TendonRouting, VcrefDefaultDiskForceConvergesToVcOnHelicalRobots) {
  EXPECT_EQ(Effects().disk_normal_force, DiskNormalForce::Kept) << "the default is the frictionless hole's force";
  std::vector<double> kept, removed, dropped;
  for (int n : {10, 20, 40}) {
    const Scene s = adjacent_pair(n, 0.5, Vec3(0.0, 0.1, 0.0));
    Scene eq58 = s;
    eq58.effects.disk_normal_force = DiskNormalForce::Removed;
    const Solution vc = solve_kind(ModelKind::VC, s), k = solve_kind(ModelKind::VCref, s),
                   r = solve_kind(ModelKind::VCref, eq58);
    ASSERT_TRUE(vc.converged() && k.converged() && r.converged()) << n;
    kept.push_back((k.tip().p - vc.tip().p).norm());
    removed.push_back((r.tip().p - vc.tip().p).norm());
    // Robot and tendons: in equilibrium with the force kept; Eq. 58's dropped force stays finite.
    auto m = make_model(ModelKind::VCref, s.robot, s.effects);
    const EquilibriumCheck qk = verify_equilibrium(*m, s.input(), k);
    ASSERT_TRUE(qk.evaluated) << qk.reason;
    EXPECT_LT(qk.relative_error(), 1e-6) << n;
    EXPECT_EQ(qk.eq58_force.norm(), 0.0);
    auto m58 = make_model(ModelKind::VCref, eq58.robot, eq58.effects);
    dropped.push_back(verify_equilibrium(*m58, eq58.input(), r).eq58_force.norm());
  }
  for (int i = 1; i < 3; ++i) {
    EXPECT_LT(kept[i], 0.35 * kept[i - 1]) << kept[i - 1] << " " << kept[i] << ": second order";
    EXPECT_GT(removed[i], 0.8 * removed[i - 1]) << removed[i - 1] << " " << removed[i] << ": Eq. 58 levels off";
    EXPECT_GT(dropped[i], 0.5 * dropped[i - 1]) << dropped[i - 1] << " " << dropped[i];
  }
  EXPECT_LT(kept[2], 1e-5);
  EXPECT_GT(removed[2], 20 * kept[2]);
  EXPECT_GT(dropped[2], 1e-3) << "N: a finite force as the disks grow";
}

// Straight routing without external loads: where a tendon passes a disk between subsegments of equal
// bending the chords make equal angles with it, the normal component vanishes and the two disk forces
// give the same shape (configurations 2 and 5 of the paper robot: T1 alone, T3 alone). Where the
// curvature changes, at the disk between the segments under T1 and T3 (configuration 6), Eq. 58 drops
// a force of second order in the disk spacing: the tips differ by 8.0e-6, 1.9e-6 m at n = 10, 20, and
// both tend to VC.
TEST(TendonRouting, DiskForceSettingsOnStraightUnloadedRobots) {
  std::vector<double> differ;
  for (int n : {10, 20})
    for (int c : {2, 5, 6}) {
      Scene s = paper::scene(n, c);
      s.effects.disk_normal_force = DiskNormalForce::Kept;
      Scene r = s;
      r.effects.disk_normal_force = DiskNormalForce::Removed;
      for (ModelKind k : {ModelKind::CCsub, ModelKind::PRB, ModelKind::VCref}) {
        const Solution a = solve_kind(k, s), b = solve_kind(k, r);
        ASSERT_TRUE(a.converged() && b.converged()) << to_string(k);
        const double e = max_frame_error(a, b);
        // PRB's subsegment (joints at Table 1's gamma, not symmetric about its middle) leaves its
        // chords unequal at a disk even under equal bending: 2.5e-7 to 6.6e-7 m here.
        if (c != 6) {
          EXPECT_LT(e, k == ModelKind::PRB ? 1e-6 : 1e-9) << to_string(k) << " configuration " << c;
        }
        if (c == 6 && k == ModelKind::VCref) differ.push_back((a.tip().p - b.tip().p).norm());
      }
    }
  ASSERT_EQ(differ.size(), 2u);
  EXPECT_GT(differ[0], 1e-6);
  EXPECT_LT(differ[1], 0.3 * differ[0]) << differ[0] << " " << differ[1] << ": second order";
}
