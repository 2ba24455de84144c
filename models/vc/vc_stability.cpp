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
// point s in [0, L) is conjugate when M(s) is singular, and the equilibrium is stable iff none
// is: det M(s) keeps the sign it has at the tip. (At s = 0 this is the shooting Jacobian
// d w(L) / d w(0) being singular: the sub-problem is the robot itself.)
//
// The earlier family, [0, s] with the wrench transmitted at s held as a dead load, is not
// conservative (a dead couple of finite 3-D rotations), and its det changed sign twice within a
// few disks on stable robots: draw 193 beyond the loaded-scene suite (docs/hard-cases.md),
// where VCref with conservative disk forces at 40 disks per segment (the same shape to 0.1 mm)
// finds a positive definite reduced stiffness and VC's own damped motion comes to rest.
//
// The linearization is sampled at the base and at every disk by forward differences: 12 shots
// from the converged state, each with one component of the base wrench or of the base pose
// perturbed (the base pose through `shoot`'s base frame), giving the 12 x 12 transfer matrix
// Phi(s) from the base state to the state at s, scaled to be dimensionless (positions by L,
// forces and moments by the residual scales of the solve). The fields of the free end start at
// Z = Phi(L)^-1 [I; 0], and M(s) is the pose rows of Phi(s) Z. The margin is
//   margin = min over the base and the disks before the tip of +-sigma_min(M(s)),
// the sign turned negative from the first sign change of det M (walking from the tip) on.
// Between -u and u, u = max(1e-6, 10 sqrt(integrator noise)), the test does not decide.
// A dead tip moment (fixed in the base frame) is not conservative for finite 3-D rotations; it
// is treated as if it were (delta w(L) = 0), exact for a moment normal to a planar deformation.
// Limitation: a conjugate point of even multiplicity leaves the sign of det M unchanged and is
// missed (a straight round column past its critical load: both bending planes at once).
#include "vc/vc_stability.hpp"

#include "physics/tendon_path.hpp"
#include "tdcr/core/lie.hpp"

#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/LU>
#include <Eigen/SVD>

namespace tdcr::vc {

namespace {

using Mat6 = Eigen::Matrix<double, 6, 6>;
using Mat12 = Eigen::Matrix<double, 12, 12>;
using Vec12 = Eigen::Matrix<double, 12, 1>;

/// Below this |margin| the test never decides (forward differences with increments sqrt(eps)
/// carry relative errors near 1e-8).
constexpr double kUndecided = 1e-6;

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
// of a shot from base frame `frame` with base wrench `base`.
bool sweep(VcWorkspace::Impl& W, const Vec6& base, const Frame& frame, std::vector<Frame>& frames,
           std::vector<BackboneSample>& samples, std::vector<Vec6>& wrench) {
  frames.clear();
  samples.clear();
  const Record rec{&frames, &samples, nullptr};
  Vec6 res;
  if (!shoot(W, *W.shot_integrator, *W.shot_rod, base, res, &rec, &frame)) return false;
  wrench.resize(samples.size());
  for (std::size_t j = 0; j < samples.size(); ++j) wrench[j] = cut_wrench(W, static_cast<int>(j), samples[j]);
  return frames.size() == samples.size();
}

}  // namespace

Stability conjugate_point_test(VcWorkspace::Impl& W, const Vec6& base, double load_factor) {
  Stability out;
  out.method = "conjugate points (Till & Rucker 2017) of the fixed-free rod: tip-anchored Jacobi fields at every disk";
  set_load_factor(W, load_factor);
  std::vector<Frame> frames, pframes;
  std::vector<BackboneSample> samples;
  std::vector<Vec6> nominal, perturbed;
  const Frame clamp{};
  if (!sweep(W, base, clamp, frames, samples, nominal)) {
    out.method += "; the shot from the base failed";
    return out;
  }
  const std::size_t disks = nominal.size();
  const double L = W.model->robot().total_length();
  const double Fs = W.loads.force_scale(), Ms = W.loads.moment_scale();
  Vec6 unit;
  unit << Fs, Fs, Fs, Ms, Ms, Ms;
  std::vector<Mat12> Phi(disks);
  const double rel = std::sqrt(std::max(std::numeric_limits<double>::epsilon(), W.shot_integrator->relative_noise()));
  for (int c = 0; c < 12; ++c) {
    // Columns 0-2: base position (scaled by L), 3-5: base rotation, 6-11: base wrench (scaled).
    Vec6 xp = base;
    Frame fp = clamp;
    double h = rel;  // in scaled units
    if (c < 3) {
      fp.p[c] = h * L;
    } else if (c < 6) {
      Vec3 w = Vec3::Zero();
      w[c - 3] = h;
      fp.R = lie::exp_so3(w);
    } else {
      const int k = c - 6;
      h = rel * std::max(std::abs(base[k]) / unit[k], 1.0);
      xp[k] += h * unit[k];
    }
    if (!sweep(W, xp, fp, pframes, samples, perturbed) || perturbed.size() != disks) {
      out.method += "; a perturbed shot failed";
      return out;
    }
    for (std::size_t j = 0; j < disks; ++j) {
      const Mat3 D = pframes[j].R * frames[j].R.transpose();  // I + [d theta]x, spatial
      Vec12 col;
      col << (pframes[j].p - frames[j].p) / L, 0.5 * (D(2, 1) - D(1, 2)), 0.5 * (D(0, 2) - D(2, 0)),
          0.5 * (D(1, 0) - D(0, 1)), (perturbed[j] - nominal[j]).cwiseQuotient(unit);
      Phi[j].col(c) = col / h;
    }
  }
  // The free end's Jacobi fields: delta w(L) = 0, tip pose variation e_i.
  Eigen::Matrix<double, 12, 6> tip = Eigen::Matrix<double, 12, 6>::Zero();
  tip.topRows<6>().setIdentity();
  const Eigen::PartialPivLU<Mat12> lu(Phi[disks - 1]);
  const Eigen::Matrix<double, 12, 6> Z = lu.solve(tip);
  if (!Z.allFinite()) {
    out.method += "; the transfer matrix to the tip is singular";
    return out;
  }
  const double undecided = std::max(kUndecided, 10.0 * rel);
  double margin = std::numeric_limits<double>::infinity();
  bool passed = false;  // a conjugate point lies between the tip and the current sample
  double det = 1.0;     // det M(L) = det I
  for (std::size_t j = disks - 1; j-- > 0;) {
    const Mat6 M = (Phi[j] * Z).topRows<6>();
    const double d = M.determinant();
    if ((d > 0.0) != (det > 0.0)) passed = true;
    det = d;
    const double smin = Eigen::JacobiSVD<Mat6>(M).singularValues()[5];
    margin = std::min(margin, passed ? -smin : smin);
  }
  out.margin = margin;
  if (margin > undecided)
    out.status = StabilityStatus::Stable;
  else if (margin < -undecided)
    out.status = StabilityStatus::Unstable;
  return out;
}

}  // namespace tdcr::vc
