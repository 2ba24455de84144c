#include "tdcr/models/prb.hpp"

#include <algorithm>
#include <cmath>

#include "lumped/lumped_problem.hpp"
#include "tdcr/core/lie.hpp"

namespace tdcr {

namespace {
constexpr int kU = 5;  // unknowns per subsegment
// The phi gauge (see prb.hpp): eta a0^2 / (a0^2 + t^2) sin(phi - phi_0), t = (l/EI) |M*|.
// It pins phi where the in-plane moment vanishes (t << a0) and fades out as soon as the moment
// defines the plane: below 1e-12 (a hundredth of the default tolerance) for t >= 1e-3.
constexpr double kGaugeEta = 1e-6;
constexpr double kGaugeA0 = 1e-6;
// Unknown scale of phi: finite-difference step 1.5e-4 rad for phi, so that the phi column of the
// Jacobian resolves the gauge term above the rounding noise of the residual (~1e-16 / step).
constexpr double kPhiScale = 1e-4;
// Maximum scaled Newton step (rad of joint angle): a Newton step changes the joint angles by at
// most about one radian in total. A longer step from the straight guess can throw a strongly
// bent subsegment (n = 1) into the basin where its bending plane is 90 deg off the moment, a
// local minimum of |F| (configurations 14 and 15 of the case study at n = 1 end there with
// KINSOL's automatic bound).
constexpr double kMaxNewtonStep = 1.0;
// Automatic formulation: structured Newton steps (the recursive Jacobian's quasiseparable block
// LU, lumped_structured.cpp, O(J)) from this many loaded subsegments on, i.e. always: they cost
// less than the dense LU of the same Jacobian at every J measured (cold loaded solves of
// bench_loaded's cases, CPU time: n = 3 26 -> 22 us, n = 5 57 -> 40 us, n = 10 about the same;
// the trajectory at J = 20 already took them). Before, with the block-banded system on KLU, the
// crossover was J = 16.
constexpr int kBandedFrom = 1;
// The contact solve's structured steps (KLU on the contact system) from this many subsegments on:
// the crossover measured with the free-space solve's former KLU steps (lumped_contact.cpp).
constexpr int kContactStructuredFrom = 16;
// Fixed-point passes of the cold guess (PrbProblem::guess_x).
constexpr int kColdGuessPasses = 3;
// Cold direct solves: exact Newton down to this scaled residual, then modified Newton (as CCsub).
constexpr double kColdFreezeJacobianBelow = 1e-3;

// Model-specific points of a PRB subsegment in detail::SubsegmentPose::aux.
constexpr int kJoint = 0;  // joint centres P_1..P_3: aux[0..2]
constexpr int kMid = 3;    // link midpoints: aux[3..6]

class PrbBody final : public detail::LumpedBody {
 public:
  PrbBody(const Robot& robot, const TendonRouting& routing, const Effects& effects, LumpedFormulation formulation)
      : LumpedBody(robot, routing, effects, kU, formulation, kBandedFrom) {
    contact_structured_from = kContactStructuredFrom;
    gamma_sum = 0.0;
    for (int i = 0; i < 4; ++i) {
      gamma[i] = effects.prb.gamma[i];
      gamma_sum += gamma[i];
    }
    for (int q = 0; q < 3; ++q) k_theta[q] = effects.prb.k_theta[q];
    // With shear and extension the tendons' compression shortens every link of a subsegment
    // alike (as CCsub's arcs and CC's): the four models then shorten the same way.
    if (effects.shear_extension) statics.set_axial_compression(robot.backbone.effective_stiffness().EA);
  }

  std::unique_ptr<detail::LumpedProblem> make_problem() const override;

  // Eq. 11-12 with the twist: the rigid-link body of subsegment j in its base disk frame.
  void local(int j, const double* xj, detail::SubsegmentPose& g) const override {
    double sa[3], ca[3];
    local(j, xj, g, sa, ca);
  }

  // local(), with the sines and cosines of the partial angles a_q after joint q (local_rates()
  // takes them from here rather than evaluating them again: sin and cos were a tenth of a PRB
  // dynamics run).
  void local(int j, const double* xj, detail::SubsegmentPose& g, double* sa_out, double* ca_out) const {
    const double l = statics.length(j);
    const double cp = std::cos(xj[3]), sp = std::sin(xj[3]);
    g.cphi = cp;
    g.sphi = sp;
    // In-plane coordinates (x', z') of the chain, then x' mapped along (cos phi, sin phi).
    double x = 0.0, z = gamma[0] * l, a = 0.0, sa = 0.0, ca = 1.0;
    auto to3 = [&](double px, double pz) { return Vec3(px * cp, px * sp, pz); };
    Vec3* joint = g.aux + kJoint;
    Vec3* mid = g.aux + kMid;
    mid[0] = Vec3(0.0, 0.0, 0.5 * gamma[0] * l);
    for (int q = 0; q < 3; ++q) {
      joint[q] = to3(x, z);
      a += xj[q];
      const double L = gamma[q + 1] * l;
      sa = std::sin(a);
      ca = std::cos(a);
      sa_out[q] = sa;
      ca_out[q] = ca;
      mid[q + 1] = to3(x + 0.5 * L * sa, z + 0.5 * L * ca);
      x += L * sa;
      z += L * ca;
    }
    g.p = to3(x, z);
    Vec3 c = Vec3::Zero();
    for (int i = 0; i < 4; ++i) c += gamma[i] * mid[i];
    g.c = c / gamma_sum;
    // Rz(phi) Ry(a) Rz(eps - phi), with sin a, cos a of the last joint's total angle.
    const double e = xj[4] - xj[3], ce = std::cos(e), se = std::sin(e);
    // Rz(phi) Ry(a), by columns (no comma initializer: a hot path of the dynamics).
    const Vec3 A0(cp * ca, sp * ca, -sa), A1(-sp, cp, 0.0);
    g.R.col(0) = ce * A0 + se * A1;
    g.R.col(1) = -se * A0 + ce * A1;
    g.R.col(2) = Vec3(cp * sa, sp * sa, ca);
  }

  // local() and its rates: the joints turn about Rz(phi) e_y, eps about the end's axis A e_z,
  // phi about e_z less the end's axis (R = Rz(phi) Ry(a) Rz(eps) Rz(-phi)); the in-plane points
  // move with the joints proximal of them and turn with phi.
  bool local_rates(int j, const double* xj, detail::SubsegmentPose& g, detail::SubsegmentRates& d) const override {
    // Partial angles a_q after joint q: their sines and cosines from local(); the links' lengths.
    double L[3], sa[3], ca[3];
    local(j, xj, g, sa, ca);
    const double l = statics.length(j);
    const double cp = g.cphi, sp = g.sphi;
    for (int q = 0; q < 3; ++q) L[q] = gamma[q + 1] * l;
    auto plane = [&](double dx, double dz) { return Vec3(dx * cp, dx * sp, dz); };
    auto turn = [&](const Vec3& v) { return Vec3(-v.y(), v.x(), 0.0); };  // d/dphi of a point
    const Vec3 axis(cp * sa[2], sp * sa[2], ca[2]);
    for (int i = 0; i < 3; ++i) {
      d.w[i] = Vec3(-sp, cp, 0.0);
      double dx = 0.0, dz = 0.0;  // in-plane rate of the chain's point after joint q
      d.dmid[0][i].setZero();
      for (int q = 0; q < 3; ++q) {
        if (q < i) {
          d.dmid[q + 1][i].setZero();
          continue;
        }
        d.dmid[q + 1][i] = plane(dx + 0.5 * L[q] * ca[q], dz - 0.5 * L[q] * sa[q]);
        dx += L[q] * ca[q];
        dz -= L[q] * sa[q];
      }
      d.dp[i] = plane(dx, dz);
    }
    d.w[3] = Vec3(0.0, 0.0, 1.0) - axis;
    d.dp[3] = turn(g.p);
    for (int k = 0; k < 4; ++k) d.dmid[k][3] = turn(g.aux[kMid + k]);
    d.w[4] = axis;
    d.dp[4].setZero();
    for (int k = 0; k < 4; ++k) d.dmid[k][4].setZero();
    return true;
  }

  // local_rates()' structure: the joints move the links after them, phi turns all but the first
  // (on the axis), eps none: link k by theta_1..theta_k and phi, link 0 by nothing.
  unsigned link_unknowns(int k) const override { return k == 0 ? 0u : ((1u << k) - 1u) | (1u << 3); }

  double gamma[4] = {};
  double gamma_sum = 1.0;
  double k_theta[3] = {};
};

// The 5 residuals of Eq. 48-54 per subsegment (see prb.hpp).
class PrbProblem final : public detail::LumpedProblem {
 public:
  explicit PrbProblem(const PrbBody& body) : LumpedProblem(body), body_(body) { phi_ref_.assign(body.N + 1, 0.0); }

  // The bending-plane angle phi of a subsegment is held by its in-plane moment (Eq. 52-53):
  // d r_phi / d phi changes sign where that moment passes through zero (an inflection of the
  // bend moving along the robot), and so does the determinant, while (phi + pi, -theta) is the
  // same shape. Such sign changes are no bifurcations: bench_soft's E0.178x_n20_+y reported 6,
  // whose refinement took 168 of the path's 206 Newton iterations (554 -> 48 ms without them,
  // the same answer). PRB's stability verdicts come from its reduced stiffness, not from these.
  bool determinant_marks_bifurcations() const override { return false; }

  // Cold direct solves: modified Newton once the scaled residual is below kColdFreezeJacobianBelow.
  // phi is a chart a stale Jacobian can wander along: from the straight guess a frozen Jacobian
  // once drifted by 5 pi on configuration 7 of the case study and landed on the other chart of
  // the same shape (where the stability test read the wrong sign). From the fixed-point guess
  // the frozen phase starts closer: the 16 configurations of the case study at n = 1, 2, 3, 5, 7,
  // 10, 15, 16, 20, 30 give the same status, tip (within 1e-8 m) and stability verdict with and
  // without freezing, and so do the 80 rows of the loaded-scene suite. Measured gain: PRB n = 100
  // with a 0.5 N tip force (bench_lumped's tip_0.5N) 3 exact iterations -> 8 with one Jacobian
  // less, 2.5 -> 1.8 ms (docs/design-notes/lumped.md).
  double cold_freeze_jacobian_below() const override { return kColdFreezeJacobianBelow; }
  void adjust(bvp::NewtonOptions& options) const override {
    LumpedProblem::adjust(options);
    // The banded unknowns include every disk pose: a bound on their joint step would stall it.
    if (!banded()) options.max_newton_step = kMaxNewtonStep;
  }

 private:
  void x_scale(double* s) const override {
    for (int i = 0; i < kU; ++i) s[i] = 1.0;
    s[3] = kPhiScale;
  }
  void on_warm(const Eigen::VectorXd& x) override { set_phi_ref(x); }
  // A straight subsegment's bending plane phi is a polar angle at zero bending: no derivative.
  bool differentiable(const Eigen::VectorXd& y) const override {
    const int stride = banded() ? kU + 12 : kU;  // banded: x_j then the 12 wrench unknowns
    for (int j = 0; j < active(); ++j)
      if (y.segment(stride * j, 3).cwiseAbs().sum() < 1e-9) return false;
    return true;
  }

  void constitutive(int j, const double* xj, const detail::SubsegmentPose& g, const Vec3& F, const Vec3& Mj,
                    const Vec3& Wj, double* r) const override {
    const bool bb = backbone_weight_on();
    const double gj_ei = body_.GJ / body_.EI;
    const double s = body_.statics.length(j) / body_.EI;
    const double cp = g.cphi, sp = g.sphi;  // local() of these xj
    const Vec3* joint = g.aux + kJoint;
    const Vec3* mid = g.aux + kMid;
    const Vec3 W = Wj / body_.gamma_sum;
    const Vec3 y(-sp, cp, 0.0);
    // Eq. 48-51: joint q balances the moment of everything distal of it.
    for (int q = 0; q < 3; ++q) {
      Vec3 Mq = Mj + (g.p - joint[q]).cross(F);
      if (bb)
        for (int i = q + 1; i < 4; ++i) Mq += (mid[i] - joint[q]).cross(body_.gamma[i] * W);
      r[q] = body_.k_theta[q] * xj[q] - s * y.dot(Mq);
    }
    // Moment about O_{j-1}.
    Vec3 Mb = Mj + g.p.cross(F);
    if (bb)
      for (int i = 0; i < 4; ++i) Mb += mid[i].cross(body_.gamma[i] * W);
    // Eq. 52-53, two-sided: the in-plane moment has no component across the joint axis.
    const double t2 = s * s * (Mb.x() * Mb.x() + Mb.y() * Mb.y());
    const double gauge = kGaugeEta * kGaugeA0 * kGaugeA0 / (kGaugeA0 * kGaugeA0 + t2);
    r[3] = s * (cp * Mb.x() + sp * Mb.y()) + gauge * std::sin(xj[3] - phi_ref_[j]);
    // Eq. 54: twist about the end tangent.
    r[4] = gj_ei * xj[4] - s * g.R.col(2).dot(Mb);
  }

  // d r / d(F, M, W) of constitutive() in closed form (5 x 9, column-major): Eq. 48-51 and 54
  // are linear in the loads, Eq. 52-53 through the gauge term's t2 = s^2 |Mb_xy|^2.
  bool load_jacobian(int j, const double* xj, const detail::SubsegmentPose& g, const Vec3& F, const Vec3& Mj,
                     const Vec3& Wj, double* Lp) const override {
    const bool bb = backbone_weight_on();
    const double s = body_.statics.length(j) / body_.EI;
    const double cp = g.cphi, sp = g.sphi;  // local() of these xj
    const Vec3* joint = g.aux + kJoint;
    const Vec3* mid = g.aux + kMid;
    const Eigen::RowVector3d y(-sp, cp, 0.0);
    Eigen::Map<Eigen::Matrix<double, kU, 9>> L(Lp);
    L.setZero();
    for (int q = 0; q < 3; ++q) {
      L.block<1, 3>(q, 0) = -s * y * lie::hat(g.p - joint[q]);
      L.block<1, 3>(q, 3) = -s * y;
      if (bb) {
        Mat3 A = Mat3::Zero();
        for (int i = q + 1; i < 4; ++i) A += (body_.gamma[i] / body_.gamma_sum) * lie::hat(mid[i] - joint[q]);
        L.block<1, 3>(q, 6) = -s * y * A;
      }
    }
    // Moment about O_{j-1} and its derivatives.
    Vec3 Mb = Mj + g.p.cross(F);
    Mat3 dW = Mat3::Zero();
    if (bb) {
      const Vec3 W = Wj / body_.gamma_sum;
      for (int i = 0; i < 4; ++i) {
        Mb += mid[i].cross(body_.gamma[i] * W);
        dW += (body_.gamma[i] / body_.gamma_sum) * lie::hat(mid[i]);
      }
    }
    const double a2 = kGaugeA0 * kGaugeA0;
    const double t2 = s * s * (Mb.x() * Mb.x() + Mb.y() * Mb.y());
    const double dgauge_dt2 = -kGaugeEta * a2 / ((a2 + t2) * (a2 + t2));
    const double sn = std::sin(xj[3] - phi_ref_[j]);
    const Eigen::RowVector3d d3 =
        Eigen::RowVector3d(s * cp, s * sp, 0.0) + sn * dgauge_dt2 * 2.0 * s * s * Eigen::RowVector3d(Mb.x(), Mb.y(), 0.0);
    const Eigen::RowVector3d d4 = -s * g.R.col(2).transpose();
    const Mat3 dF = lie::hat(g.p);
    L.block<1, 3>(3, 0) = d3 * dF;
    L.block<1, 3>(3, 3) = d3;
    L.block<1, 3>(4, 0) = d4 * dF;
    L.block<1, 3>(4, 3) = d4;
    if (bb) {
      L.block<1, 3>(3, 6) = d3 * dW;
      L.block<1, 3>(4, 6) = d4 * dW;
    }
    return true;
  }

  void set_phi_ref(const Eigen::VectorXd& x) {
    residual_changed();
    for (int j = 1; j <= active(); ++j) phi_ref_[j] = x[kU * (j - 1) + 3];
  }
  // Rest state: the straight robot (all joint angles and twists zero), each bending plane put
  // where the moment at the straight state under the full load points (y_phi along M*), see
  // prb.hpp; with phi_ref = phi it is also the exact solution at load factor 0. Cold guess: from
  // there, fixed-point passes (LumpedProblem::fixed_point_passes, PrbProblem::fixed_point).
  void guess_x(Eigen::VectorXd& x, bool rest) override {
    x.setZero(kU * active());
    const double lambda = loads_.loads.load_factor();
    set_parameter(1.0);
    evaluate(x.data());
    for (int j = 1; j <= active(); ++j) {
      const Vec3 a = frames_[j - 1].R.transpose() * base_moment(j);
      const double scale = body_.statics.length(j) / body_.EI;
      x[kU * (j - 1) + 3] = scale * std::hypot(a.x(), a.y()) > 1e-14 ? std::atan2(-a.x(), a.y()) : 0.0;
    }
    set_parameter(lambda);
    if (!rest) fixed_point_passes(x, kColdGuessPasses);
    set_phi_ref(x);
  }
  // Eq. 48-54 solved for x_j with the joint positions and end axis of the shape x_j: the bending
  // plane along the moment about O_{j-1} (Eq. 52-53 without the gauge), then each joint angle
  // from the moment about its joint (Eq. 48-51) and the twist from Eq. 54. phi is a chart (any
  // value at zero bending): it does not count in the contraction test.
  bool fixed_point(int j, const double* xj, const detail::SubsegmentPose& g, const Vec3& F, const Vec3& Mj,
                   const Vec3& Wj, double* next, double* weight) const override {
    const bool bb = backbone_weight_on();
    const double s = body_.statics.length(j) / body_.EI;
    const Vec3* joint = g.aux + kJoint;
    const Vec3* mid = g.aux + kMid;
    const Vec3 W = Wj / body_.gamma_sum;
    Vec3 Mb = Mj + g.p.cross(F);
    if (bb)
      for (int i = 0; i < 4; ++i) Mb += mid[i].cross(body_.gamma[i] * W);
    next[3] = s * std::hypot(Mb.x(), Mb.y()) > 1e-14 ? std::atan2(-Mb.x(), Mb.y()) : xj[3];
    const Vec3 y(-std::sin(next[3]), std::cos(next[3]), 0.0);
    for (int q = 0; q < 3; ++q) {
      Vec3 Mq = Mj + (g.p - joint[q]).cross(F);
      if (bb)
        for (int i = q + 1; i < 4; ++i) Mq += (mid[i] - joint[q]).cross(body_.gamma[i] * W);
      next[q] = s * y.dot(Mq) / body_.k_theta[q];
    }
    next[4] = s * g.R.col(2).dot(Mb) / (body_.GJ / body_.EI);
    weight[3] = 0.0;
    return true;
  }

  // A subsegment with an inflection inside (joint angles of both signs): its plane law
  // r_3 = s (M_b . e_phi) is s (M . e - z F . y) about the subsegment's base, while the potential's
  // gradient in phi is a M . e - x' F . y (a the end's tilt theta_1 + theta_2 + theta_3, x' the
  // end's offset in the plane; small bends): alike where a and x' / z have one sign, not where
  // the joints bend both ways (a and x' can then differ in sign). Measured: a cantilever under
  // 1 N on a 1 mm capsule across it (n = 10) had its only unstable mode (-27.7) all in the plane
  // angle of subsegment 4 (joint angles -5.3e-4, 4.3e-4, 1.5e-3), where CCsub finds the answer
  // stable (docs/contact.md, "Stability with contact").
  int ill_posed_unknown(const double* xj) const override {
    const double lo = std::min({xj[0], xj[1], xj[2]}), hi = std::max({xj[0], xj[1], xj[2]});
    const double size = std::max(-lo, hi);
    return size > 1e-9 && std::min(-lo, hi) > 1e-3 * size ? 3 : -1;
  }

  // A subsegment bent against its bending plane (theta_1 + theta_2 + theta_3 < 0) is the same
  // shape as (phi + pi, -theta, eps): rotating the chain's plane by pi about z maps the in-plane
  // coordinate x' to -x' and Rz(pi) Ry(-a) Rz(-pi) = Ry(a), so the twist eps is unchanged. Its
  // gauge reference turns with it, so the gauge term keeps its sign.
  void enter_stability_chart(Eigen::VectorXd& x) override {
    residual_changed();
    saved_phi_ref_ = phi_ref_;
    for (int j = 1; j <= active(); ++j) {
      double* q = x.data() + kU * (j - 1);
      if (q[0] + q[1] + q[2] >= 0.0) continue;
      for (int i = 0; i < 3; ++i) q[i] = -q[i];
      q[3] += M_PI;
      phi_ref_[j] += M_PI;
    }
  }
  void leave_stability_chart() override {
    residual_changed();
    phi_ref_.swap(saved_phi_ref_);
  }

  const PrbBody& body_;
  std::vector<double> phi_ref_, saved_phi_ref_;
};

std::unique_ptr<detail::LumpedProblem> PrbBody::make_problem() const { return std::make_unique<PrbProblem>(*this); }

}  // namespace

PrbModel::PrbModel(const Robot& robot, const Effects& effects, LumpedFormulation formulation)
    : LumpedModel(robot, effects, formulation, detail::make_body<PrbBody>) {}

std::vector<Vec3> PrbModel::joint_points(const Eigen::VectorXd& x, const ModelInput& input) const {
  const auto& b = static_cast<const PrbBody&>(body());
  detail::SubsegmentLoads loads;
  b.statics.bind(input, loads);
  const std::vector<Frame> f = b.disk_frames(x, loads.stretch_data());
  std::vector<Vec3> pts;
  pts.reserve(4 * b.N);
  detail::SubsegmentPose g;
  for (int j = 1; j <= b.N; ++j) {
    b.pose(j, x.data() + kU * (j - 1), loads.stretch_of(j), g);
    for (int q = 0; q < 3; ++q) pts.push_back(f[j - 1].transform(g.aux[kJoint + q]));
    pts.push_back(f[j].p);
  }
  return pts;
}


}  // namespace tdcr
