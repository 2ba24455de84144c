#include "tdcr/models/ccsub.hpp"

#include <cmath>

#include "lumped/lumped_problem.hpp"
#include "tdcr/core/lie.hpp"

namespace tdcr {

namespace {

// Arc functions of the bending angle t, with series where the closed forms cancel:
// s1 = sin t / t, c2 = (1 - cos t) / t^2, g3 = (t - sin t) / t^3.
struct ArcCoefficients {
  double s1, c2, g3;
  explicit ArcCoefficients(double t2) {
    if (t2 < 1e-8) {
      s1 = 1.0 - t2 / 6.0 + t2 * t2 / 120.0;
      c2 = 0.5 - t2 / 24.0 + t2 * t2 / 720.0;
      g3 = 1.0 / 6.0 - t2 / 120.0 + t2 * t2 / 5040.0;
    } else {
      const double t = std::sqrt(t2);
      const double s = std::sin(t), c = std::cos(t);
      s1 = s / t;
      c2 = (1.0 - c) / t2;
      g3 = (t - s) / (t2 * t);
    }
  }
};

// The derivatives of s1 and c2 in t^2: (cos t - s1) / (2 t^2) and (s1 - 2 c2) / (2 t^2), by
// their series below t^2 = 1e-2 (where the closed forms lose up to 1e-16 / t^2; the series'
// first omitted term is below 1e-16 there).
struct ArcRates {
  double ds1, dc2;
  ArcRates(double t2, const ArcCoefficients& a) {
    if (t2 < 1e-2) {
      ds1 = -1.0 / 6.0 + t2 * (1.0 / 60.0 + t2 * (-1.0 / 1680.0 + t2 * (1.0 / 90720.0 - t2 * (5.0 / 39916800.0))));
      dc2 = -1.0 / 24.0 + t2 * (1.0 / 360.0 + t2 * (-1.0 / 13440.0 + t2 * (1.0 / 907200.0 - t2 * (5.0 / 479001600.0))));
    } else {
      ds1 = (std::cos(std::sqrt(t2)) - a.s1) / (2.0 * t2);
      dc2 = (a.s1 - 2.0 * a.c2) / (2.0 * t2);
    }
  }
};

// Automatic formulation: structured Newton steps (the recursive Jacobian's quasiseparable block
// LU, lumped_structured.cpp, O(J)) from this many loaded subsegments on, i.e. always: on the cold
// loaded cases of bench_loaded (CPU time, medians per n) n = 3 14.5 -> 13.6 us, n = 5 28.5 ->
// 23.8 us, n = 10 71 -> 53 us against the dense LU, n = 20 124 -> 76 us against the block-banded
// system on KLU (which took over from J = 30 before).
constexpr int kBandedFrom = 1;
// The contact solve's structured steps (KLU on the contact system) from this many subsegments on:
// the crossover measured with the free-space solve's former KLU steps (lumped_contact.cpp).
constexpr int kContactStructuredFrom = 30;
// Cold direct solves: exact Newton down to this scaled residual, then modified Newton
// (bvp::NewtonOptions::freeze_jacobian_below). On the 60 loaded cases of bench_loaded one
// Jacobian instead of 3-4 (the recursive form's Jacobian costs about n/2 residuals), the same
// answers within the tolerance.
constexpr double kColdFreezeJacobianBelow = 1e-3;
// ... and without external loads only from this many unknowns (bench_lumped, configuration 2:
// n = 10 per segment, 30 unknowns, 56 -> 63 us with freezing; n = 20, 60 unknowns, 204 -> 184 us).
constexpr int kColdFreezeFromUnknowns = 60;
// Fixed-point passes of the cold guess (CcsubProblem::guess_x).
constexpr int kColdGuessPasses = 3;

class CcsubBody final : public detail::LumpedBody {
 public:
  CcsubBody(const Robot& robot, const TendonRouting& routing, const Effects& effects, LumpedFormulation formulation)
      : LumpedBody(robot, routing, effects, 3, formulation, kBandedFrom) {
    contact_structured_from = kContactStructuredFrom;
    // With shear and extension, the tendons' compression shortens each subsegment as CC's arc
    // (N / EA with N the tensions through it): the co-tension of an antagonistic pair then moves
    // the tendons' pulls, so displacement input decides it as in VC.
    if (effects.shear_extension) statics.set_axial_compression(robot.backbone.effective_stiffness().EA);
  }

  std::unique_ptr<detail::LumpedProblem> make_problem() const override;

  // The arc with twist of subsegment j in the frame of disk j-1, and its centroid.
  void local(int j, const double* xj, detail::SubsegmentPose& g) const override {
    const double l = statics.length(j);
    const double bx = xj[0], by = xj[1], eps = xj[2];
    const double t2 = bx * bx + by * by;
    const ArcCoefficients a(t2);
    // Arc end (Eq. 5; the arc bends towards u x e_z = (u_y, -u_x)).
    g.p = Vec3(by * l * a.c2, -bx * l * a.c2, l * a.s1);
    // Rotation exp([u l]) R_z(eps) (Eq. 8 with the twist of Section 3.1).
    Mat3 Rb;
    const double c2 = a.c2;
    Rb << 1.0 - c2 * by * by, c2 * bx * by, a.s1 * by,
          c2 * bx * by, 1.0 - c2 * bx * bx, -a.s1 * bx,
          -a.s1 * by, a.s1 * bx, 1.0 - c2 * t2;
    const double ce = std::cos(eps), se = std::sin(eps);
    g.R.col(0) = ce * Rb.col(0) + se * Rb.col(1);
    g.R.col(1) = -se * Rb.col(0) + ce * Rb.col(1);
    g.R.col(2) = Rb.col(2);
    g.c = Vec3(by * l * a.g3, -bx * l * a.g3, l * a.c2);
  }

  // R = exp([u]) R_z(eps), u = (b_x, b_y, 0): the rates of b_x, b_y are the left Jacobian of
  // exp, I + c2 [u] + g3 [u]^2, times e_x, e_y; that of eps is R e_z. p = l (b_y c2, -b_x c2, s1).
  bool local_rates(int j, const double* xj, detail::SubsegmentPose& g, detail::SubsegmentRates& d) const override {
    local(j, xj, g);
    const double l = statics.length(j);
    const double bx = xj[0], by = xj[1];
    const double t2 = bx * bx + by * by;
    const ArcCoefficients a(t2);
    const ArcRates r(t2, a);
    d.w[0] = Vec3(1.0 - a.g3 * by * by, a.g3 * bx * by, -a.c2 * by);
    d.w[1] = Vec3(a.g3 * bx * by, 1.0 - a.g3 * bx * bx, a.c2 * bx);
    d.w[2] = g.R.col(2);
    d.dp[0] = l * Vec3(2.0 * r.dc2 * bx * by, -a.c2 - 2.0 * r.dc2 * bx * bx, 2.0 * r.ds1 * bx);
    d.dp[1] = l * Vec3(a.c2 + 2.0 * r.dc2 * by * by, -2.0 * r.dc2 * bx * by, 2.0 * r.ds1 * by);
    d.dp[2] = Vec3::Zero();
    return true;
  }
};

// The 3 residuals of Eq. 43 per subsegment (see ccsub.hpp).
class CcsubProblem final : public detail::LumpedProblem {
 public:
  explicit CcsubProblem(const CcsubBody& body) : LumpedProblem(body), body_(body) {}
  // The unknowns are curvature components: no chart for a stale Jacobian to wander along (PRB's
  // bending-plane angle has one, see PrbProblem::cold_freeze_jacobian_below).
  // Tendon-only scenes (the case study's configurations) take 0-1 exact Newton iterations from
  // the fixed-point guess (2 from the straight robot, where freezing was measured not to pay
  // below 60 unknowns: the second Newton call's overhead): freeze there only under external
  // loads.
  double cold_freeze_jacobian_below() const override {
    const physics::LoadCase& l = loads_.loads;
    const bool external = l.has_tip_wrench() || l.has_gravity();
    return external || size() >= kColdFreezeFromUnknowns ? kColdFreezeJacobianBelow : 0.0;
  }

  // The cold guess: fixed-point passes from the straight robot (LumpedProblem::
  // fixed_point_passes). The first pass is exact for tendons alone where the routing is straight
  // (their moment in the frame of disk j-1 does not depend on the shape: the constant curvature
  // of CC) and under a pure tip moment, and adds the other external loads as linear beam theory
  // does; the next ones bend the loads' lever arms with that shape. On the 60 loaded cases of
  // bench_loaded three passes take the cold direct solves from 6.1 to 2.9 Newton iterations on
  // average (docs/design-notes/lumped.md).
  void guess_x(Eigen::VectorXd& x, bool rest) override {
    x.setZero(3 * active());
    if (!rest) fixed_point_passes(x, kColdGuessPasses);
  }
  // Eq. 43 solved for x_j with the axis z_j of the shape x_j: eps from the z row, then u.
  bool fixed_point(int j, const double*, const detail::SubsegmentPose& g, const Vec3& F, const Vec3& M, const Vec3& W,
                   double* next, double*) const override {
    const Vec3 m = M + g.p.cross(F) + g.c.cross(W);
    const double gj_ei = body_.GJ / body_.EI;
    const double s = body_.statics.length(j) / body_.EI;
    const Vec3 z = g.R.col(2);
    next[2] = s * m.z() / (gj_ei * z.z());
    next[0] = s * m.x() - gj_ei * next[2] * z.x();
    next[1] = s * m.y() - gj_ei * next[2] * z.y();
    return true;
  }
  // The straight robot, if a direct solve from the fixed-point guess fails.
  bool alternative_guess(Eigen::VectorXd& y) override {
    y.setZero(size());
    return !banded();
  }

 private:
  void constitutive(int j, const double* xj, const detail::SubsegmentPose& g, const Vec3& F, const Vec3& M,
                    const Vec3& W, double* r) const override {
    // Moment about O_{j-1} of everything distal of disk j-1 (Eq. 45, 47), frame of disk j-1.
    const Vec3 m = M + g.p.cross(F) + g.c.cross(W);
    const Vec3 z = g.R.col(2);
    const double gj_ei = body_.GJ / body_.EI;
    const double s = body_.statics.length(j) / body_.EI;
    // Eq. 43 scaled by l/EI: l u + (GJ/EI) eps z_j - (l/EI) M_j = 0, frame of disk j-1.
    r[0] = xj[0] + gj_ei * xj[2] * z.x() - s * m.x();
    r[1] = xj[1] + gj_ei * xj[2] * z.y() - s * m.y();
    r[2] = gj_ei * xj[2] * z.z() - s * m.z();
  }
  // Eq. 43 is linear in the loads: d r / d(F, M, W) = -(l/EI) ([p]x, I, [c]x).
  bool load_jacobian(int j, const double*, const detail::SubsegmentPose& g, const Vec3&, const Vec3&, const Vec3&,
                     double* L) const override {
    const double s = body_.statics.length(j) / body_.EI;
    Eigen::Map<Eigen::Matrix<double, 3, 9>> A(L);
    A.leftCols<3>() = -s * lie::hat(g.p);
    A.middleCols<3>(3) = -s * Mat3::Identity();
    A.rightCols<3>() = -s * lie::hat(g.c);
    return true;
  }
  const CcsubBody& body_;
};

std::unique_ptr<detail::LumpedProblem> CcsubBody::make_problem() const { return std::make_unique<CcsubProblem>(*this); }

}  // namespace

CcsubModel::CcsubModel(const Robot& robot, const Effects& effects, LumpedFormulation formulation)
    : LumpedModel(robot, effects, formulation, detail::make_body<CcsubBody>) {}


}  // namespace tdcr
