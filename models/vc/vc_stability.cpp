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
// A dead tip moment (fixed in the base frame) is not conservative for finite 3-D rotations; it
// is treated as if it were (delta w(L) = 0, the symmetric part of K), exact for a moment normal
// to a planar deformation.
#include "vc/vc_stability.hpp"

#include "physics/small_dense.hpp"
#include "physics/tendon_path.hpp"
#include "tdcr/core/lie.hpp"

#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

namespace tdcr::vc {

namespace {

using Mat6 = Eigen::Matrix<double, 6, 6>;
using Mat12 = Eigen::Matrix<double, 12, 12>;
using Vec12 = Eigen::Matrix<double, 12, 1>;

/// Below this |margin| the test never decides (forward differences with increments sqrt(eps)
/// carry relative errors near 1e-8).
constexpr double kUndecided = 1e-6;

// The number of negative eigenvalues of the symmetric S (its inertia, Sylvester's law): the signs
// of the pivots of its LDL^T factorisation, or of its eigenvalues where a pivot is too small to
// tell; -1 if S is not finite.
int negative_eigenvalues(const Mat6& S) {
  if (!S.allFinite()) return -1;
  const Eigen::LDLT<Mat6> ldlt(S);
  const Vec6 d = ldlt.vectorD();
  if (ldlt.info() == Eigen::Success && d.cwiseAbs().minCoeff() > 1e-9 * d.cwiseAbs().maxCoeff())
    return static_cast<int>((d.array() < 0.0).count());
  const Eigen::SelfAdjointEigenSolver<Mat6> eig(S, Eigen::EigenvaluesOnly);
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
  std::vector<Vec6>& nominal = W.stability_wrench;
  if (!sweep(W, integ, base, Frame{}, frames, samples, nominal)) {
    out.method += "; the shot from the base failed";
    return out;
  }
  const TendonRouting& rt = W.model->routing();
  const int intervals = static_cast<int>(nominal.size()) - 1;
  const double L = W.model->robot().total_length();
  const double EI = W.section.kbt.x();
  const double Fs = W.loads.force_scale(), Ms = W.loads.moment_scale();
  Vec6 unit;
  unit << Fs, Fs, Fs, Ms, Ms, Ms;
  const double rel = std::sqrt(std::max(std::numeric_limits<double>::epsilon(), integ.relative_noise()));
  const double undecided = std::max(kUndecided, 10.0 * rel);
  TendonRod& rod = *W.shot_rod;
  Eigen::VectorXd &y0 = W.stability_y0, &y1 = W.stability_y1, &y = W.stability_y;
  y0.resize(rod.dimension());
  y1.resize(rod.dimension());
  y.resize(rod.dimension());
  // With RK4 the unperturbed shot across an interval is the sweep's (the same steps); CVODE's
  // error control makes a shot restarted at a disk differ from it by its tolerance, so the
  // interval's own unperturbed shot is taken.
  const bool from_sweep = W.stability_integrator != nullptr;
  // Without weights the rotation columns follow from the wrench columns (below): 6 shots per
  // interval instead of 9 (with RK4; CVODE keeps every shot, the reference test).
  const bool rotation_invariant = from_sweep && !W.loads.has_gravity();
  // The scaled coordinates (pose, cut wrench) of a state at the cut distal of disk j.
  auto coordinates = [&](int j, const double* state, const Frame& ref, const Vec6& ref_wrench) {
    const Mat3 R = cosserat::rotation(state);
    const Mat3 D = R * ref.R.transpose();  // I + [d theta]x, spatial
    BackboneSample b{rt.disk_s[j], Frame{R, Vec3(cosserat::position(state))}, Vec3(cosserat::force(state)),
                     Vec3(cosserat::moment(state))};
    Vec12 c;
    c << (b.frame.p - ref.p) / L, 0.5 * (D(2, 1) - D(1, 2)), 0.5 * (D(0, 2) - D(2, 0)), 0.5 * (D(1, 0) - D(0, 1)),
        (cut_wrench(W, j, b) - ref_wrench).cwiseQuotient(unit);
    return c;
  };
  // The pairing of pose and wrench in the scaled coordinates: diag(L Fs, Ms) / Ms.
  const Mat6 pairing = (Vec6() << L * Fs / Ms, L * Fs / Ms, L * Fs / Ms, 1.0, 1.0, 1.0).finished().asDiagonal();
  Eigen::Matrix<double, 12, 6> cut = Eigen::Matrix<double, 12, 6>::Zero();
  cut.bottomRows<6>().setIdentity();
  // The free end's Jacobi fields (delta w(L) = 0, tip pose variation e_i), carried to the base.
  Eigen::Matrix<double, 12, 6> free_next = Eigen::Matrix<double, 12, 6>::Zero(), free_here, clamped, carried;
  free_next.topRows<6>().setIdentity();
  Mat12 in, end;
  Mat6 Rinv, Binv, Minv;
  double margin = std::numeric_limits<double>::infinity();
  int index = 0;  // conjugate points between the tip and the current disk, with multiplicity
  for (int k = intervals - 1; k >= 0; --k) {
    // Interval k, from disk k to disk k+1 (with its point loads), shot from p = 0: the rod is
    // translation invariant, so the position columns of its transfer matrix are the identity.
    const double h = rt.disk_s[k + 1] - rt.disk_s[k];
    const int seg = rt.disk_segment[k + 1];
    rod.set(W.segments[seg]);
    y0.setZero();
    cosserat::rotation(y0.data()) = frames[k].R;
    cosserat::force(y0.data()) = samples[k].n;
    cosserat::moment(y0.data()) = samples[k].m;
    // The unperturbed shot across the interval, from p = 0 (the sweep's moved there: the rod is
    // translation invariant).
    const Frame start{frames[k].R, Vec3::Zero()};
    Frame stop{frames[k + 1].R, frames[k + 1].p - frames[k].p};
    Vec6 w_stop = nominal[k + 1];
    if (!from_sweep) {
      y1 = y0;
      if (!integ.integrate(rod, rt.disk_s[k], rt.disk_s[k + 1], y1.data()) ||
          !disk_point_loads(W, seg, k + 1, y1.data())) {
        out.method += "; a shot across a disk interval failed";
        return out;
      }
      stop = cosserat::frame_of(y1.data());
      const BackboneSample b1{rt.disk_s[k + 1], stop, Vec3(cosserat::force(y1.data())),
                              Vec3(cosserat::moment(y1.data()))};
      w_stop = cut_wrench(W, k + 1, b1);
    }
    const Vec6 w_start = nominal[k];
    in.setIdentity();
    end.setIdentity();
    for (int c = rotation_invariant ? 6 : 3; c < 12; ++c) {
      // Natural scales of the interval: 1 (rotation), EI / h^2 (force), EI / h (moment).
      y = y0;
      double step = rel;
      if (c < 6) {
        Vec3 w = Vec3::Zero();
        w[c - 3] = step;
        cosserat::rotation(y.data()) = lie::exp_so3(w) * frames[k].R;
      } else if (c < 9) {
        step = rel * std::max(std::abs(samples[k].n[c - 6]), EI / (h * h));
        cosserat::force(y.data())[c - 6] += step;
      } else {
        step = rel * std::max(std::abs(samples[k].m[c - 9]), EI / h);
        cosserat::moment(y.data())[c - 9] += step;
      }
      in.col(c) = coordinates(k, y.data(), start, w_start) / step;
      if (!integ.integrate(rod, rt.disk_s[k], rt.disk_s[k + 1], y.data()) || !disk_point_loads(W, seg, k + 1, y.data())) {
        out.method += "; a perturbed shot across a disk interval failed";
        return out;
      }
      end.col(c) = coordinates(k + 1, y.data(), stop, w_stop) / step;
    }
    if (rotation_invariant) {
      // Without weights the interval is invariant under a rotation Q of its whole start state
      // about the start point, (R, n, m) -> (Q R, Q n, Q m): its end state turns alike, the
      // position about that point, and so do the cut wrenches. A rotation w of R alone is that
      // rigid rotation less the wrench perturbation (w x n, w x m), whose response is the wrench
      // columns'; so the rotation columns need no shots.
      for (int j = 0; j < 3; ++j) {
        const Vec3 e = Vec3::Unit(j);
        Vec12 rigid_in, rigid_end;
        rigid_in << Vec3::Zero(), e, e.cross(w_start.head<3>()) / Fs, e.cross(w_start.tail<3>()) / Ms;
        rigid_end << e.cross(stop.p) / L, e, e.cross(w_stop.head<3>()) / Fs, e.cross(w_stop.tail<3>()) / Ms;
        const Vec3 dn = e.cross(samples[k].n), dm = e.cross(samples[k].m);
        in.col(3 + j) = rigid_in - in.middleCols<3>(6) * dn - in.middleCols<3>(9) * dm;
        end.col(3 + j) = rigid_end - end.middleCols<3>(6) * dn - end.middleCols<3>(9) * dm;
      }
    }
    // The transfer matrix of the interval in the scaled coordinates is T = end in^-1; `in` is
    // block lower triangular (a wrench perturbation leaves the start pose as it is), [P 0; Q R].
    // The interval clamped at disk k, its end pose and wrench for a cut wrench at disk k:
    // T [0; I] = end [0; R^-1]. (Small systems by physics/small_dense.hpp and fixed-size products
    // lazily: Eigen's general LU solves and product kernel cost more than the arithmetic here.)
    if (!physics::invert_small<6>(in.bottomRightCorner<6, 6>(), Rinv)) {
      out.method += "; the stiffness at a disk could not be formed";
      return out;
    }
    clamped.noalias() = end.rightCols<6>().lazyProduct(Rinv);
    Mat6 B = clamped.topRows<6>();
    // A Kirchhoff rod's end pose does not see an axial force when straight (B singular): the
    // compliance of shear and extension is added as a penalty on those stiff directions.
    if (!W.section.shear_extension)
      B.topLeftCorner<3, 3>() += (h * Fs / L) * (frames[k].R * W.section.inv_kse.asDiagonal() * frames[k].R.transpose());
    // The stiffness at disk k+1 of the rod [s_k, L] clamped at s_k: the interval's end wrench
    // minus the distal rod's start wrench per unit pose variation there (symmetric in the
    // pairing of pose and wrench). Its negative eigenvalues are the conjugate points in [s_k, s_k+1).
    if (!physics::invert_small<6>(B, Binv) || !physics::invert_small<6>(free_next.topRows<6>(), Minv)) {
      out.method += "; the stiffness at a disk could not be formed";
      return out;
    }
    const Mat6 K = pairing * (clamped.bottomRows<6>().lazyProduct(Binv) - free_next.bottomRows<6>().lazyProduct(Minv));
    const int negative = negative_eigenvalues(0.5 * (K + K.transpose()));
    if (negative < 0) {
      out.method += "; the stiffness at a disk could not be formed";
      return out;
    }
    index += negative;
    // The free end's fields at disk k: T^-1 = in end^-1.
    carried = free_next;
    if (!physics::solve_small<12, 6>(end, carried)) {
      out.method += "; a transfer matrix across a disk interval is singular";
      return out;
    }
    free_here.noalias() = in.lazyProduct(carried);
    if (!free_here.allFinite()) {
      out.method += "; a transfer matrix across a disk interval is singular";
      return out;
    }
    // The smallest singular value of M(s_k), from the eigenvalues of M^T M (6 x 6, symmetric).
    const Mat6 MtM = free_here.topRows<6>().transpose().lazyProduct(free_here.topRows<6>());
    const double smin = std::sqrt(std::max(0.0, Eigen::SelfAdjointEigenSolver<Mat6>(MtM, Eigen::EigenvaluesOnly).eigenvalues()[0]));
    margin = std::min(margin, index > 0 ? -smin : smin);
    free_next = free_here;
  }
  out.margin = margin;
  if (margin > undecided)
    out.status = StabilityStatus::Stable;
  else if (margin < -undecided)
    out.status = StabilityStatus::Unstable;
  return out;
}

}  // namespace tdcr::vc
