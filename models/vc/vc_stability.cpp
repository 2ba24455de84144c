// Stability of a VC equilibrium: the conjugate-point test of Till & Rucker, "Elastic stability of
// Cosserat rods and parallel continuum robots", IEEE T-RO 2017.
//
// The rod is clamped at the base (p(0) = 0, R(0) = I) and every load VC applies is conservative:
// the fully constrained tendons (Rucker & Webster) derive from the potential sum T_k l_k, the
// tip force and the weights are dead loads. The shooting ODE with its disk point loads is then
// the Euler-Lagrange system of the total potential, and its variations with respect to the base
// wrench, with the base pose held, are the Jacobi fields of the clamped rod. The equilibrium is
// stable iff no point s in (0, L] is conjugate to the base, i.e. iff
//   J(s) = d(n(s), m(s)) / d(n(0), m(0))
// (the Jacobian of the shooting residual, truncated at s, with respect to the base wrench) stays
// nonsingular on (0, L]; J(0) = I, so det J(s) > 0 there (a cantilever under a compressive dead
// force P: the bending block is cos(s sqrt(P / EI)), singular first at P = pi^2 EI / (4 L^2)).
// A dead tip moment (fixed in the base frame) is not conservative for finite 3-D rotations; it
// is treated as if it were (its variation is zero in the residual, as in Newton's Jacobian),
// exact for a moment normal to a planar deformation.
//
// The wrench at a cut s is the whole wrench the distal part transmits: the backbone's (n, m) plus
// the pull of every tensioned tendon crossing the cut, as if it ended there (the termination
// wrench of Eq. 40-41, T_k R t_k at p + R r_k, with u, v at s). It is the natural boundary
// condition of the rod truncated at s, whose tendons end at s; the backbone's (n, m) alone misses
// how the tendon pull turns with the section, and finds conjugate points on stable robots bent
// by strongly tensioned tendons. At the tip no tendon crosses and it is the shooting residual.
//
// J(s) is sampled at the base and at every disk (after its point loads) by forward differences: 6 shots from the
// converged base wrench, each perturbed in one component, recording the wrench at every disk.
// It is scaled to be dimensionless, Js = D J D^-1 with D = diag(1/F_s I, 1/M_s I) (the residual
// scales of the solve); Js(0) = I plus the variation of the crossing tendons' pull at the base. A
// conjugate point lies between two samples where det Js changes sign (from its sign at s = 0). The margin is
//   margin = min over disks of +-sigma_min(Js(s)),
// the smallest singular value of the scaled Jacobian, with the sign turned negative from the
// first sign change on. Between -u and u, u = max(1e-6, 10 sqrt(integrator noise)), the test
// does not decide. Limitation: a conjugate point of even multiplicity leaves the sign of det Js
// unchanged and is missed (a straight round column past its critical load: both bending planes
// at once); eigenvalue counting, which would see it, misreads the rotation-like Jacobians of
// bent robots (complex pairs meeting on the negative axis), so it is not used.
#include "vc/vc_stability.hpp"

#include "physics/tendon_path.hpp"

#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/LU>
#include <Eigen/SVD>

namespace tdcr::vc {

namespace {

using Mat6 = Eigen::Matrix<double, 6, 6>;

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

// The cut wrench at the base and at every disk after its point loads, to the tip.
bool sweep(VcWorkspace::Impl& W, const Vec6& base, std::vector<Frame>& frames, std::vector<BackboneSample>& samples,
           std::vector<Vec6>& wrench) {
  frames.clear();
  samples.clear();
  const Record rec{&frames, &samples, nullptr};
  Vec6 res;
  if (!shoot(W, *W.shot_integrator, *W.shot_rod, base, res, &rec)) return false;
  wrench.resize(samples.size());
  for (std::size_t j = 0; j < samples.size(); ++j) wrench[j] = cut_wrench(W, static_cast<int>(j), samples[j]);
  return true;
}

}  // namespace

Stability conjugate_point_test(VcWorkspace::Impl& W, const Vec6& base, double load_factor) {
  Stability out;
  out.method = "conjugate points (Till & Rucker 2017): d(cut wrench)(s) / d(n, m)(0) at every disk";
  set_load_factor(W, load_factor);
  std::vector<Frame> frames;
  std::vector<BackboneSample> samples;
  std::vector<Vec6> nominal, perturbed;
  if (!sweep(W, base, frames, samples, nominal)) {
    out.method += "; the shot from the base failed";
    return out;
  }
  const std::size_t disks = nominal.size();
  const double Fs = W.loads.force_scale(), Ms = W.loads.moment_scale();
  Vec6 unit;
  unit << Fs, Fs, Fs, Ms, Ms, Ms;
  std::vector<Mat6> J(disks);
  const double rel = std::sqrt(std::max(std::numeric_limits<double>::epsilon(), W.shot_integrator->relative_noise()));
  for (int c = 0; c < 6; ++c) {
    Vec6 xp = base;
    const double h = rel * std::max(std::abs(base[c]), unit[c]);
    xp[c] += h;
    if (!sweep(W, xp, frames, samples, perturbed) || perturbed.size() != disks) {
      out.method += "; a perturbed shot failed";
      return out;
    }
    // Scaled column: rows divided by their unit, the column multiplied by its unit.
    for (std::size_t j = 0; j < disks; ++j)
      J[j].col(c) = (perturbed[j] - nominal[j]).cwiseQuotient(unit) * (unit[c] / h);
  }
  const double undecided = std::max(kUndecided, 10.0 * rel);
  double margin = std::numeric_limits<double>::infinity();
  bool passed = false;  // a conjugate point lies before the current disk
  double det = J[0].determinant();  // the sign at s = 0, where no point is conjugate
  for (std::size_t j = 1; j < disks; ++j) {
    const Mat6& Js = J[j];
    const double d = Js.determinant();
    if ((d > 0.0) != (det > 0.0)) passed = true;
    det = d;
    const double smin = Eigen::JacobiSVD<Mat6>(Js).singularValues()[5];
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
