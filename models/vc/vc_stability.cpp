// Stability of a VC equilibrium: the conjugate-point test of Till & Rucker, "Elastic stability of
// Cosserat rods and parallel continuum robots", IEEE T-RO 2017.
//
// The rod is clamped at the base (p(0) = 0, R(0) = I) and every load VC applies is conservative:
// the fully constrained tendons (Rucker & Webster) derive from the potential sum T_k l_k, the
// tip force and the weights are dead loads. A tendon's length is the integral of |q_k|,
// q_k = v + u x r_k, so the rod is a hyperelastic rod whose strain energy density is the
// backbone's plus T_k |q_k| (convex in the strains: the Legendre condition holds), and its
// internal wrench is the backbone's (n, m) plus the pull T_k R t_k of every tensioned tendon
// crossing the section, at p + R r_k ("as if it ended there", the termination wrench of Eq.
// 40-41 with u, v at s). That wrench w is continuous across the disks, where tendons end or
// kink; the backbone's alone is not, and misses how the tendon pull turns with the section.
//
// Jacobi fields are the solutions of the shooting ODE linearized about the equilibrium, in the
// state (position, rotation, w). For a rod clamped at 0 with a dead load at its free tip the
// stability question is the generalized Jacobi condition of a fixed-free problem: the family of
// sub-problems is [s, L], clamped at s and free at L (each one conservative, so every conjugate
// point is crossed in the same direction and their number is the Morse index). The Jacobi fields
// of the free end have delta w(L) = 0 (dead tip loads) and any tip pose variation; with the
// tip pose variation as parameter, their pose part at s is the 6 x 6 matrix M(s), M(L) = I. A
// point s in [0, L) is conjugate when M(s) is singular, with the multiplicity dim ker M(s), and
// the equilibrium is stable iff there is none. (At s = 0 this is the shooting Jacobian
// d w(L) / d w(0) being singular: the sub-problem is the robot itself.)
//
// Counting them: det M(s) changes sign at a conjugate point of odd multiplicity only. A straight
// round column past its critical load has a double one (both bending planes at once): det M
// touches zero and keeps its sign, and the sign test called the column stable. The count with
// multiplicity comes from the disks' stiffness instead. With the pose at disk j+1 as the only
// coordinate of the sub-problem [s_j, L] (the interval [s_j, s_j+1] clamped at s_j, the rod
// beyond free), its second variation reduces to the 6 x 6 stiffness
//   K_j+1 = D B^-1 - N(s_j+1) M(s_j+1)^-1,
// the interval's end wrench per end pose (its transfer matrix [A B; C D] from (pose, w) at s_j
// to s_j+1, B D the columns of the wrench at s_j) minus the distal rod's start wrench per start
// pose (N the wrench part of the free end's fields). K_j+1 is the derivative of the net wrench
// on disk j+1, which is zero at an equilibrium, so it is symmetric in the pairing of pose and
// wrench (dp . dn + dtheta . dm; in every chart of the rotations); the residual asymmetry is
// the integration error (up to 1.3e-3 of |K| over the loaded-scene suite on its coarse
// loading-path meshes, 3e-6 on s1001's requested mesh; a temporary print). By the Schur
// complement (Haynsworth), the Morse index of [s_j, L] is that of [s_j+1, L], plus that of the
// interval clamped at both ends (zero: each interval is far below its own buckling loads
// ~ 4 pi^2 EI / h^2, as VCref's test assumes), plus the number of negative eigenvalues of
// K_j+1. So the conjugate points in [s_j, s_j+1) with their multiplicity are the negative
// eigenvalues of K_j+1, and their sum from the tip is the Morse index. det K_j+1 has the sign
// of det M(s_j) / det M(s_j+1) (times det B's, positive for a short interval), so the count
// changes parity exactly where det M changes sign: on the 278 rows of the loaded-scene suite
// every verdict and row is unchanged.
//
// The earlier family, [0, s] with the wrench transmitted at s held as a dead load, is not
// conservative (a dead couple of finite 3-D rotations), and its det changed sign twice within a
// few disks on stable robots: draw 193 beyond the loaded-scene suite (docs/hard-cases.md),
// where VCref with conservative disk forces at 40 disks per segment (the same shape to 0.1 mm)
// finds a positive definite reduced stiffness and VC's own damped motion comes to rest.
//
// The linearization is taken per disk interval by forward differences: from the converged state
// at disk j (after its point loads), shot across the interval to disk j+1 (with its point
// loads; with RK4 the unperturbed shot is the sweep's from the base), 9 shots with one component of the rotation, the backbone force or moment at s_j
// perturbed (steps sqrt(noise) times 1, EI / h^2, EI / h: the interval's natural scales), and
// the position columns the identity (the rod is translation invariant). In the scaled
// coordinates (positions by L, spatial rotation, w by the residual scales of the solve) its
// transfer matrix is T_j = d(state at s_j+1) / d(state at s_j). (Transfer matrices from the base
// to every disk, by 12 perturbed shots of the whole robot, give the same M(s) but not the
// intervals' B: T_j = Phi(s_j+1) Phi(s_j)^-1 lost the stiff shear and extension directions to
// the differences' noise on the bent robots of the loaded-scene suite, and with them the
// symmetry of K.) The free end's fields are [I; 0] at the tip and T_j^-1 times those at s_j+1
// at s_j, and M(s) their pose rows. A Kirchhoff rod's B is singular when straight (its end pose
// does not see an axial force): the shear and extension compliance is added to it as a penalty
// on those stiff directions, as in VCref's test. The margin is
//   margin = min over the base and the disks before the tip of +-sigma_min(M(s)),
// the sign turned negative from the first disk (walking from the tip) with a conjugate point
// between it and the tip on. Between -u and u, u = max(1e-6, 10 sqrt(integrator noise)), the
// test does not decide.
// Every shot of the test, the sweep from the base included, is taken on a coarse RK4 mesh when
// the solve integrates with RK4 (solve/stability_mesh.hpp: at least 1 step per disk interval,
// steps of at most 8 mm, never finer than the solve's), with CVODE by the solve's integrator.
// With contact (docs/contact.md, "Stability with contact"): the intervals' shots hold the contact
// forces at their values (an interval ending at a loaded contact is shot from its place, every
// column, since the obstacle breaks the translation and rotation invariance). A rigid contact with
// force constrains the fields at its disk: K counts on the tangent space of its gap, and the
// fields carried on are those poses with the distal rod's wrench and one per contact with no
// pose and its force's wrench ([Z 0; S Z E]); a compliant one adds its penalty to the distal
// rod's start wrench. Weakly active contacts: open (sufficient), then closed (necessary).
// A dead tip moment (fixed in the base frame) is not conservative for finite 3-D rotations; it
// is treated as if it were (delta w(L) = 0, the symmetric part of K), exact for a moment normal
// to a planar deformation.
#include "vc/vc_stability.hpp"

#include "physics/contact_cone.hpp"
#include "physics/small_dense.hpp"
#include "tdcr/core/contact_geometry.hpp"
#include "physics/tendon_path.hpp"
#include "tdcr/core/lie.hpp"

#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>

namespace tdcr::vc {

namespace {

using Mat6 = Eigen::Matrix<double, 6, 6>;
using Mat12 = Eigen::Matrix<double, 12, 12>;
using Vec12 = Eigen::Matrix<double, 12, 1>;
using Fields = Eigen::Matrix<double, 12, 6>;
/// At most 6 x 6: a restriction of a disk's stiffness to its contacts' tangent space.
using SmallMat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6>;

/// Below this |margin| the test never decides (forward differences with increments sqrt(eps)
/// carry relative errors near 1e-8).
constexpr double kUndecided = 1e-6;

// The number of negative eigenvalues of the symmetric S (its inertia, Sylvester's law): the signs
// of the pivots of its LDL^T factorisation, or of its eigenvalues where a pivot is too small to
// tell; -1 if S is not finite.
template <class Matrix>
int negative_eigenvalues(const Matrix& S) {
  if (!S.allFinite()) return -1;
  const Eigen::LDLT<Matrix> ldlt(S);
  const auto d = ldlt.vectorD();
  if (ldlt.info() == Eigen::Success && d.cwiseAbs().minCoeff() > 1e-9 * d.cwiseAbs().maxCoeff())
    return static_cast<int>((d.array() < 0.0).count());
  const Eigen::SelfAdjointEigenSolver<Matrix> eig(S, Eigen::EigenvaluesOnly);
  if (eig.info() != Eigen::Success) return -1;
  return static_cast<int>((eig.eigenvalues().array() < 0.0).count());
}

// The tensioned tendons crossing the cut just distal of disk j (0 = base): those running on
// past it in its segment, or in the next segment at a segment's end.
const SegmentLoads* crossing(const VcWorkspace::Impl& W, int j) {
  const TendonRouting& rt = W.model->routing();
  const int nseg = static_cast<int>(W.segments.size());
  for (int i = 0; i < nseg; ++i) {
    if (j < rt.segment_end_disk[i]) return &W.segments[i];
    if (j == rt.segment_end_disk[i]) return i + 1 < nseg ? &W.segments[i + 1] : nullptr;
  }
  return nullptr;
}

// The wrench transmitted across the cut at sample j (see the top of the file), base frame.
Vec6 cut_wrench(const VcWorkspace::Impl& W, int j, const BackboneSample& b) {
  Vec6 w;
  w << b.n, b.m;
  const SegmentLoads* seg = crossing(W, j);
  if (!seg) return w;
  const Mat3& R = b.frame.R;
  const Vec3 u = W.section.curvature(R, b.m), v = W.section.strain(R, b.n);
  for (const cosserat::TendonLoad& t : seg->tendons_at(b.s)) {
    const Vec3 q = physics::tendon_tangent(v, u, t.r, t.dr);
    const Vec3 F = (t.T / q.norm()) * (R * q);
    w.head<3>() += F;
    w.tail<3>() += (R * t.r).cross(F);
  }
  return w;
}

// The state (p, R, cut wrench) at the base and at every disk after its point loads, to the tip,
// of a shot from base frame `frame` with base wrench `base`, by `integrator`.
bool sweep(VcWorkspace::Impl& W, bvp::Integrator& integrator, const Vec6& base, const Frame& frame,
           std::vector<Frame>& frames, std::vector<BackboneSample>& samples, std::vector<Vec6>& wrench) {
  frames.clear();
  samples.clear();
  const Record rec{&frames, &samples, nullptr};
  Vec6 res;
  if (!shoot(W, integrator, *W.shot_rod, base, res, &rec, &frame)) return false;
  wrench.resize(samples.size());
  for (std::size_t j = 0; j < samples.size(); ++j) wrench[j] = cut_wrench(W, static_cast<int>(j), samples[j]);
  return frames.size() == samples.size();
}

// Whether a contact force acts at disk j (a candidate with a nonzero force): the interval ending
// there is then neither translation nor rotation invariant.
bool loaded_by_contact(const VcWorkspace::Impl& W, int j) {
  for (const contact::Candidate& c : W.contacts)
    if (c.disk == j && c.lambda != 0.0) return true;
  return false;
}

// The test's scales: positions by L, rotations as they are, cut wrenches by the residual scales of
// the solve (`unit`); `rel` the relative forward-difference increment.
struct Scales {
  double L = 1.0;
  double EI = 1.0;
  Vec6 unit = Vec6::Ones();
  double rel = 1e-8;
};

// The transfer of every disk interval k in the scaled coordinates (pose, cut wrench), stored as
// in[k] and end[k]: the start and end coordinates per start perturbation, T_k = end[k] in[k]^-1.
// Interval k runs from disk k to disk k+1 with its point loads, shot from the sweep's state at
// disk k by forward differences. `why` names a failure.
bool interval_transfers(VcWorkspace::Impl& W, bvp::Integrator& integ, bool from_sweep, const Scales& sc,
                        const std::vector<Frame>& frames, const std::vector<BackboneSample>& samples,
                        const std::vector<Vec6>& nominal, std::vector<Mat12>& ins, std::vector<Mat12>& ends,
                        const char*& why) {
  const TendonRouting& rt = W.model->routing();
  const int intervals = static_cast<int>(nominal.size()) - 1;
  ins.resize(static_cast<std::size_t>(intervals));
  ends.resize(static_cast<std::size_t>(intervals));
  TendonRod& rod = *W.shot_rod;
  Eigen::VectorXd &y0 = W.stability_y0, &y1 = W.stability_y1, &y = W.stability_y;
  y0.resize(rod.dimension());
  y1.resize(rod.dimension());
  y.resize(rod.dimension());
  // The scaled coordinates (pose, cut wrench) of a state at the cut distal of disk j.
  auto coordinates = [&](int j, const double* state, const Frame& ref, const Vec6& ref_wrench) {
    const Mat3 R = cosserat::rotation(state);
    const Mat3 D = R * ref.R.transpose();  // I + [d theta]x, spatial
    BackboneSample b{rt.disk_s[j], Frame{R, Vec3(cosserat::position(state))}, Vec3(cosserat::force(state)),
                     Vec3(cosserat::moment(state))};
    Vec12 c;
    c << (b.frame.p - ref.p) / sc.L, 0.5 * (D(2, 1) - D(1, 2)), 0.5 * (D(0, 2) - D(2, 0)), 0.5 * (D(1, 0) - D(0, 1)),
        (cut_wrench(W, j, b) - ref_wrench).cwiseQuotient(sc.unit);
    return c;
  };
  const double Fs = sc.unit[0], Ms = sc.unit[3];
  for (int k = 0; k < intervals; ++k) {
    const double h = rt.disk_s[k + 1] - rt.disk_s[k];
    const int seg = rt.disk_segment[k + 1];
    // A contact force at disk k+1 depends on where the disk is: shot from the disk's place (and
    // every rotation column shot). Otherwise the rod is translation invariant: shot from p = 0,
    // the position columns the identity.
    const bool placed = loaded_by_contact(W, k + 1);
    // Without weights or contact forces the rotation columns follow from the wrench columns
    // (below): 6 shots per interval instead of 9 (with RK4; CVODE keeps every shot, the reference
    // test).
    const bool rotation_invariant = from_sweep && !W.loads.has_gravity() && !placed;
    rod.set(W.segments[seg]);
    y0.setZero();
    if (placed) cosserat::position(y0.data()) = frames[k].p;
    cosserat::rotation(y0.data()) = frames[k].R;
    cosserat::force(y0.data()) = samples[k].n;
    cosserat::moment(y0.data()) = samples[k].m;
    // The unperturbed shot across the interval: with RK4 the sweep's (the same steps, moved to
    // p = 0 where the rod is translation invariant); CVODE's error control makes a shot restarted
    // at a disk differ from it by its tolerance, so the interval's own is taken.
    const Vec3 origin = placed ? Vec3(frames[k].p) : Vec3::Zero();
    const Frame start{frames[k].R, origin};
    Frame stop{frames[k + 1].R, frames[k + 1].p - frames[k].p + origin};
    Vec6 w_stop = nominal[k + 1];
    if (!from_sweep) {
      y1 = y0;
      if (!integ.integrate(rod, rt.disk_s[k], rt.disk_s[k + 1], y1.data()) ||
          !disk_point_loads(W, seg, k + 1, y1.data())) {
        why = "; a shot across a disk interval failed";
        return false;
      }
      stop = cosserat::frame_of(y1.data());
      const BackboneSample b1{rt.disk_s[k + 1], stop, Vec3(cosserat::force(y1.data())),
                              Vec3(cosserat::moment(y1.data()))};
      w_stop = cut_wrench(W, k + 1, b1);
    }
    const Vec6 w_start = nominal[k];
    Mat12& in = ins[static_cast<std::size_t>(k)];
    Mat12& end = ends[static_cast<std::size_t>(k)];
    in.setIdentity();
    end.setIdentity();
    for (int c = rotation_invariant ? 6 : 3; c < 12; ++c) {
      // Natural scales of the interval: 1 (rotation), EI / h^2 (force), EI / h (moment).
      y = y0;
      double step = sc.rel;
      if (c < 6) {
        Vec3 w = Vec3::Zero();
        w[c - 3] = step;
        cosserat::rotation(y.data()) = lie::exp_so3(w) * frames[k].R;
      } else if (c < 9) {
        step = sc.rel * std::max(std::abs(samples[k].n[c - 6]), sc.EI / (h * h));
        cosserat::force(y.data())[c - 6] += step;
      } else {
        step = sc.rel * std::max(std::abs(samples[k].m[c - 9]), sc.EI / h);
        cosserat::moment(y.data())[c - 9] += step;
      }
      in.col(c) = coordinates(k, y.data(), start, w_start) / step;
      if (!integ.integrate(rod, rt.disk_s[k], rt.disk_s[k + 1], y.data()) || !disk_point_loads(W, seg, k + 1, y.data())) {
        why = "; a perturbed shot across a disk interval failed";
        return false;
      }
      end.col(c) = coordinates(k + 1, y.data(), stop, w_stop) / step;
    }
    if (!rotation_invariant) continue;
    // Without weights the interval is invariant under a rotation Q of its whole start state
    // about the start point, (R, n, m) -> (Q R, Q n, Q m): its end state turns alike, the
    // position about that point, and so do the cut wrenches. A rotation w of R alone is that
    // rigid rotation less the wrench perturbation (w x n, w x m), whose response is the wrench
    // columns'; so the rotation columns need no shots.
    for (int j = 0; j < 3; ++j) {
      const Vec3 e = Vec3::Unit(j);
      Vec12 rigid_in, rigid_end;
      rigid_in << Vec3::Zero(), e, e.cross(w_start.head<3>()) / Fs, e.cross(w_start.tail<3>()) / Ms;
      rigid_end << e.cross(stop.p) / sc.L, e, e.cross(w_stop.head<3>()) / Fs, e.cross(w_stop.tail<3>()) / Ms;
      const Vec3 dn = e.cross(samples[k].n), dm = e.cross(samples[k].m);
      in.col(3 + j) = rigid_in - in.middleCols<3>(6) * dn - in.middleCols<3>(9) * dm;
      end.col(3 + j) = rigid_end - end.middleCols<3>(6) * dn - end.middleCols<3>(9) * dm;
    }
  }
  return true;
}

// A contact the test holds at disk `disk`: its gap's gradient G (in units of r_o per scaled pose
// at the cut distal of the disk) and E, the response of the cut wrench there to its scaled force
// (scaled coordinates; the pose does not move). Rigid and active (`strong`) or weakly active
// (touching without force): a constraint G dpose = 0 with its force free; compliant and
// penetrated: its penalty, `penalty` = k r_o / F_s scaled force per scaled gap.
struct HeldContact {
  int disk = 0;
  Vec6 G = Vec6::Zero();
  Vec6 E = Vec6::Zero();
  bool strong = false;
  double penalty = 0.0;
};

// The contacts the test holds, from the sweep's frames: G by the gap's first variation
// (n . (dp + dtheta x (x_c - p)), the contact point on the robot's surface), E by a forward
// difference of the disk's point loads from the state just proximal of it.
bool held_contacts(VcWorkspace::Impl& W, bvp::Integrator& integ, const Scales& sc, const std::vector<Frame>& frames,
                   const std::vector<BackboneSample>& samples, std::vector<HeldContact>& held, const char*& why) {
  held.clear();
  const TendonRouting& rt = W.model->routing();
  const double ro = W.law.length_scale;
  const bool compliant = W.law.stiffness > 0.0;
  TendonRod& rod = *W.shot_rod;
  Eigen::VectorXd &pre = W.stability_y0, &y = W.stability_y;
  for (std::size_t i = 0; i < W.contacts.size(); ++i) {
    contact::Candidate& c = W.contacts[i];
    const int d = c.disk;
    if (d < 1 || d >= static_cast<int>(frames.size())) continue;
    const ContactPoint at =
        contact_point(W.obstacles[c.obstacle], frames[d], c.body, W.surfaces.radius(d, c.body));
    HeldContact hc;
    hc.disk = d;
    if (compliant) {
      if (!(at.gap < 0.0)) continue;
      hc.penalty = W.law.stiffness * ro / W.law.force_scale;
    } else {
      hc.strong = c.lambda > physics::kActiveForce;
      if (!hc.strong && !(at.gap / ro < physics::kTouching)) continue;
    }
    hc.G << (sc.L / ro) * at.normal, ((at.point - frames[d].p).cross(at.normal)) / ro;
    // The state just proximal of disk d: the interval from disk d-1 shot again (from its place).
    const int seg = rt.disk_segment[d];
    rod.set(W.segments[seg]);
    pre.resize(rod.dimension());
    y.resize(rod.dimension());
    pre.setZero();
    cosserat::position(pre.data()) = frames[d - 1].p;
    cosserat::rotation(pre.data()) = frames[d - 1].R;
    cosserat::force(pre.data()) = samples[d - 1].n;
    cosserat::moment(pre.data()) = samples[d - 1].m;
    if (!integ.integrate(rod, rt.disk_s[d - 1], rt.disk_s[d], pre.data())) {
      why = "; a shot to a contact's disk failed";
      return false;
    }
    const double lambda = c.lambda, step = sc.rel * std::max(std::abs(lambda), 1.0);
    Vec6 w[2];
    for (int side = 0; side < 2; ++side) {
      c.lambda = lambda + (side ? step : 0.0);
      y = pre;
      const bool ok = disk_point_loads(W, seg, d, y.data());
      c.lambda = lambda;
      if (!ok) {
        why = "; the point loads at a contact's disk failed";
        return false;
      }
      const BackboneSample b{rt.disk_s[d], cosserat::frame_of(y.data()), Vec3(cosserat::force(y.data())),
                             Vec3(cosserat::moment(y.data()))};
      w[side] = cut_wrench(W, d, b);
    }
    hc.E = (w[1] - w[0]).cwiseQuotient(sc.unit) / step;
    if (!hc.G.allFinite() || !hc.E.allFinite()) {
      why = "; a contact's gradient is not finite";
      return false;
    }
    held.push_back(hc);
  }
  return true;
}

// Which held contacts a pass of the test takes: none (forces held: the free rod under the same
// loads), the active ones (weakly active open: a sufficient test), or all (weakly active closed:
// a necessary test).
enum class Constraints { None, Active, All };

// The pass from the tip to the base (see the top of the file): the margin, or false and `why`.
bool tip_to_base(const VcWorkspace::Impl& W, const Scales& sc, const std::vector<Mat12>& ins,
                 const std::vector<Mat12>& ends, const std::vector<Frame>& frames, const std::vector<HeldContact>& held,
                 Constraints which, double& margin, const char*& why, int* morse_index = nullptr) {
  const TendonRouting& rt = W.model->routing();
  const int intervals = static_cast<int>(ins.size());
  const double Fs = sc.unit[0], Ms = sc.unit[3];
  // The pairing of pose and wrench in the scaled coordinates: diag(L Fs, Ms) / Ms.
  const Mat6 pairing =
      (Vec6() << sc.L * Fs / Ms, sc.L * Fs / Ms, sc.L * Fs / Ms, 1.0, 1.0, 1.0).finished().asDiagonal();
  // The free end's Jacobi fields (delta w(L) = 0, tip pose variation e_i), carried to the base.
  Fields free_next = Fields::Zero(), free_here, clamped, carried;
  free_next.topRows<6>().setIdentity();
  Mat6 Rinv, Binv, Minv;
  Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, 6> Gc(6, 0), Z;
  margin = std::numeric_limits<double>::infinity();
  int index = 0;  // conjugate points between the tip and the current disk, with multiplicity
  for (int k = intervals - 1; k >= 0; --k) {
    const Mat12& in = ins[static_cast<std::size_t>(k)];
    const Mat12& end = ends[static_cast<std::size_t>(k)];
    const double h = rt.disk_s[k + 1] - rt.disk_s[k];
    // Contacts at disk k+1. A compliant one adds its penalty to the distal rod's start wrench
    // (the interval's shots hold its force): N += penalty E G M. Rigid ones constrain the pose
    // there (columns of Gc).
    int constraints = 0;
    for (const HeldContact& c : held) {
      if (c.disk != k + 1) continue;
      if (c.penalty > 0.0) {
        const Eigen::Matrix<double, 1, 6> GM = c.G.transpose() * free_next.topRows<6>();
        free_next.bottomRows<6>().noalias() += c.penalty * c.E * GM;
      } else if (which == Constraints::All || (which == Constraints::Active && c.strong)) {
        Gc.conservativeResize(6, constraints + 1);  // at most 6 columns: fixed storage
        Gc.col(constraints++) = c.G;
      }
    }
    // The transfer matrix of the interval in the scaled coordinates is T = end in^-1; `in` is
    // block lower triangular (a wrench perturbation leaves the start pose as it is), [P 0; Q R].
    // The interval clamped at disk k, its end pose and wrench for a cut wrench at disk k:
    // T [0; I] = end [0; R^-1]. (Small systems by physics/small_dense.hpp and fixed-size products
    // lazily: Eigen's general LU solves and product kernel cost more than the arithmetic here.)
    if (!physics::invert_small<6>(in.bottomRightCorner<6, 6>(), Rinv)) {
      why = "; the stiffness at a disk could not be formed";
      return false;
    }
    clamped.noalias() = end.rightCols<6>().lazyProduct(Rinv);
    Mat6 B = clamped.topRows<6>();
    // A Kirchhoff rod's end pose does not see an axial force when straight (B singular): the
    // compliance of shear and extension is added as a penalty on those stiff directions.
    if (!W.section.shear_extension)
      B.topLeftCorner<3, 3>() += (h * Fs / sc.L) * (frames[k].R * W.section.inv_kse.asDiagonal() * frames[k].R.transpose());
    // The stiffness at disk k+1 of the rod [s_k, L] clamped at s_k: the interval's end wrench
    // minus the distal rod's start wrench S = N M^-1 per unit pose variation there (symmetric in
    // the pairing of pose and wrench). Its negative eigenvalues, on the tangent space of the
    // contacts there, are the conjugate points in [s_k, s_k+1).
    if (!physics::invert_small<6>(B, Binv) || !physics::invert_small<6>(free_next.topRows<6>(), Minv)) {
      why = "; the stiffness at a disk could not be formed";
      return false;
    }
    const Mat6 S = free_next.bottomRows<6>().lazyProduct(Minv);
    const Mat6 K = pairing * (clamped.bottomRows<6>().lazyProduct(Binv) - S);
    const Mat6 Ks = 0.5 * (K + K.transpose());
    int negative;
    const int fresh = constraints;  // the constraint forces' fields, columns 6 - fresh .. 5
    if (constraints == 0) {
      negative = negative_eigenvalues(Ks);
    } else {
      // Z: an orthonormal basis of the poses that keep the constrained gaps closed, null(Gc^T).
      const Eigen::HouseholderQR<Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, 6>> qr(Gc);
      const Mat6 Q = qr.householderQ();
      Z = Q.rightCols(6 - constraints);
      const SmallMat Kz = Z.transpose() * Ks * Z;
      negative = negative_eigenvalues(Kz);
      // The fields seen across the disk: the poses in the tangent space with the distal rod's
      // wrench, and the constraint forces' wrenches at fixed pose, [Z 0; S Z E].
      free_next.topRows<6>().setZero();
      free_next.topLeftCorner(6, 6 - constraints) = Z;
      free_next.bottomLeftCorner(6, 6 - constraints) = S * Z;
      int col = 6 - constraints;
      for (const HeldContact& c : held)
        if (c.disk == k + 1 && c.penalty == 0.0 && (which == Constraints::All || (which == Constraints::Active && c.strong)))
          free_next.block<6, 1>(6, col++) = c.E / c.E.norm();
      Gc.resize(6, 0);
    }
    if (negative < 0) {
      why = "; the stiffness at a disk could not be formed";
      return false;
    }
    index += negative;
    // The free end's fields at disk k: T^-1 = in end^-1.
    carried = free_next;
    if (!physics::solve_small<12, 6>(end, carried)) {
      why = "; a transfer matrix across a disk interval is singular";
      return false;
    }
    free_here.noalias() = in.lazyProduct(carried);
    if (!free_here.allFinite()) {
      why = "; a transfer matrix across a disk interval is singular";
      return false;
    }
    // A constraint force's field has no pose at its disk, and at disk k one interval's response,
    // mostly a rotation the tangent space's fields already span: the margin would measure that
    // interval's length. A basis of the same fields instead (conjugate points depend on their
    // span only): the constraint forces' fields less their least-squares part in the others'
    // poses, each to unit pose, orthogonal to the others' poses at disk k.
    for (int c = 6 - fresh; c < 6; ++c) {
      const auto P = free_here.topLeftCorner(6, c);
      const SmallMat PtP = P.transpose() * P;
      const Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 6, 1> a =
          PtP.ldlt().solve(P.transpose() * free_here.col(c).head<6>());
      free_here.col(c) -= free_here.leftCols(c) * a;
      const double norm = free_here.col(c).head<6>().norm();
      if (norm > 0.0) free_here.col(c) /= norm;
    }
    // The smallest singular value of M(s_k), from the eigenvalues of M^T M (6 x 6, symmetric).
    const Mat6 MtM = free_here.topRows<6>().transpose().lazyProduct(free_here.topRows<6>());
    const double smin = std::sqrt(std::max(0.0, Eigen::SelfAdjointEigenSolver<Mat6>(MtM, Eigen::EigenvaluesOnly).eigenvalues()[0]));
    margin = std::min(margin, index > 0 ? -smin : smin);
    free_next = free_here;
  }
  if (morse_index) *morse_index = index;
  return true;
}

}  // namespace

Stability conjugate_point_test(VcWorkspace::Impl& W, const Vec6& base, double load_factor) {
  Stability out;
  out.method = "conjugate points (Till & Rucker 2017) of the fixed-free rod, counted with multiplicity: tip-anchored "
               "Jacobi fields at every disk";
  set_load_factor(W, load_factor);
  // Every shot of the test on the stability mesh (coarse with RK4, the solve's CVODE otherwise).
  bvp::Integrator& integ = W.stability_pass_integrator();
  std::vector<Frame>& frames = W.stability_frames;
  std::vector<BackboneSample>& samples = W.stability_samples;
  if (!sweep(W, integ, base, Frame{}, frames, samples, W.stability_wrench)) {
    out.method += "; the shot from the base failed";
    return out;
  }
  Scales sc;
  sc.L = W.model->robot().total_length();
  sc.EI = W.section.kbt.x();
  const double Fs = W.loads.force_scale(), Ms = W.loads.moment_scale();
  sc.unit << Fs, Fs, Fs, Ms, Ms, Ms;
  sc.rel = std::sqrt(std::max(std::numeric_limits<double>::epsilon(), integ.relative_noise()));
  const double undecided = std::max(kUndecided, 10.0 * sc.rel);
  // With RK4 the unperturbed shot across an interval is the sweep's (the same steps).
  const bool from_sweep = W.stability_integrator != nullptr;
  const char* why = "";
  std::vector<HeldContact> held;  // empty without contact: no allocation
  if (!interval_transfers(W, integ, from_sweep, sc, frames, samples, W.stability_wrench, W.stability_in,
                          W.stability_end, why) ||
      !held_contacts(W, integ, sc, frames, samples, held, why)) {
    out.method += why;
    return out;
  }
  const auto decide = [&](double margin) {
    out.margin = margin;
    if (margin > undecided)
      out.status = StabilityStatus::Stable;
    else if (margin < -undecided)
      out.status = StabilityStatus::Unstable;
  };
  double margin = NAN;
  if (held.empty()) {
    if (!tip_to_base(W, sc, W.stability_in, W.stability_end, frames, held, Constraints::None, margin, why)) {
      out.method += why;
      return out;
    }
    decide(margin);
    return out;
  }
  // With contacts: the same transfers without the constraints (forces held) first, what the
  // contacts change; then the constrained (or compliant) pass.
  char buf[200];
  double free_margin = NAN;
  const char* free_why = "";
  tip_to_base(W, sc, W.stability_in, W.stability_end, frames, {}, Constraints::None, free_margin, free_why);
  std::snprintf(buf, sizeof buf, "; without the contacts' constraints (forces held) %.9g", free_margin);
  const std::string free_note = buf;
  int strong = 0, weak = 0, penalised = 0;
  for (const HeldContact& c : held) {
    if (c.penalty > 0.0)
      ++penalised;
    else if (c.strong)
      ++strong;
    else
      ++weak;
  }
  if (penalised > 0) {
    std::snprintf(buf, sizeof buf, " with the stiffness of %d compliant contacts", penalised);
    out.method += buf;
    if (!tip_to_base(W, sc, W.stability_in, W.stability_end, frames, held, Constraints::None, margin, why)) {
      out.method += why;
      return out;
    }
    decide(margin);
    out.method += free_note;
    return out;
  }
  std::snprintf(buf, sizeof buf, " on the tangent space of %d active contacts (their forces free)", strong);
  out.method += buf;
  int negative = 0;  // conjugate points with the weakly active contacts open
  if (!tip_to_base(W, sc, W.stability_in, W.stability_end, frames, held, Constraints::Active, margin, why,
                   &negative)) {
    out.method += why;
    return out;
  }
  if (weak > 0) out.method += physics::weakly_active_note(weak);
  if (margin > undecided || weak == 0) {
    decide(margin);
    out.method += free_note;
    return out;
  }
  // The cone test from the counts (physics/contact_cone.hpp): one weakly active contact, or more
  // conjugate points (negative directions) than such contacts, leaves a negative direction
  // admissible.
  if (margin < -undecided && physics::negative_direction_admissible(weak, negative)) {
    decide(margin);
    out.method += physics::cone_unstable_note(negative, "conjugate points") + free_note;
    return out;
  }
  // Not proven stable with the weakly active contacts open: with them closed (a necessary test).
  double closed = NAN;
  if (!tip_to_base(W, sc, W.stability_in, W.stability_end, frames, held, Constraints::All, closed, why)) {
    out.method += std::string("; with them closed") + why;
    return out;
  }
  std::snprintf(buf, sizeof buf, "; with them closed %.6g", closed);
  out.method += buf;
  if (closed < -undecided) {
    out.status = StabilityStatus::Unstable;
    out.margin = closed;
  } else {
    out.method += ": undetermined between the two (the cone of the weakly active contacts is not tested)";
  }
  out.method += free_note;
  return out;
}

}  // namespace tdcr::vc
