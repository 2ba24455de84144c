#include "physics/geometry_check.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "physics/tendon_path.hpp"

namespace tdcr::physics {

namespace {

// Curvature x offset of tendon t between disks j-1 and j (see the header).
double curvature_offset(const std::vector<Frame>& f, const TendonRouting& rt, const RoutedTendon& t, int j) {
  const Vec3 dp = f[j].p - f[j - 1].p;
  const Vec3 dh = hole_position(f[j], t, rt.disk_s[j]) - hole_position(f[j - 1], t, rt.disk_s[j - 1]);
  return 1.0 - dh.dot(dp) / dp.squaredNorm();
}

// Distance between the segments [a0, a1] and [b0, b1] (closest points, clamped parameters).
double segment_distance(const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1) {
  const Vec3 d1 = a1 - a0, d2 = b1 - b0, r = a0 - b0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  double s = 0.0, t = 0.0;
  if (a <= 1e-300 && e <= 1e-300) return r.norm();
  if (a <= 1e-300) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= 1e-300) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2), den = a * e - b * b;
      s = den > 1e-300 ? std::clamp((b * f - c * e) / den, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0.0) {
        t = 0.0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1.0) {
        t = 1.0;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  return (a0 + s * d1 - b0 - t * d2).norm();
}

// Length over which two thin disks of radius R (centres and normals from the frames) overlap
// along the line where their planes meet; <= 0: they do not touch.
double disk_overlap(const Frame& A, const Frame& B, double R) {
  const Vec3 na = A.R.col(2), nb = B.R.col(2);
  const Vec3 d = na.cross(nb);
  const double d2 = d.squaredNorm();
  if (d2 < 1e-20) {  // parallel planes: only coplanar disks can meet
    const Vec3 ab = B.p - A.p;
    return std::abs(ab.dot(na)) <= 1e-12 * R ? 2.0 * R - ab.norm() : -1.0;
  }
  const double c = na.dot(nb), ha = na.dot(A.p), hb = nb.dot(B.p);
  const Vec3 x0 = ((ha - hb * c) * na + (hb - ha * c) * nb) / d2;
  const Vec3 e = d / std::sqrt(d2);
  double lo = -INFINITY, hi = INFINITY;
  for (const Vec3* p : {&A.p, &B.p}) {
    const double t = (*p - x0).dot(e);
    const double dist2 = (*p - x0).squaredNorm() - t * t;
    if (dist2 > R * R) return -1.0;
    const double half = std::sqrt(R * R - dist2);
    lo = std::max(lo, t - half);
    hi = std::min(hi, t + half);
  }
  return hi - lo;
}

// True if disks a and b (spacing h) turn so little against each other that no finding is
// possible between them: a relative rotation angle theta with r_max theta <= h / 2 keeps every
// tendon's curvature x offset below about 1/2, leaves the disk rims (radius r_max) apart and
// cannot twist a chord onto the backbone. Tested on 1 - cos(theta) = (3 - tr(Ra^T Rb)) / 2
// against a^2/2 (1 - a^2/12) <= 1 - cos(a), a = h / (2 r_max), so it needs no trigonometry.
bool quiet(const Frame& a, const Frame& b, double h, double r_max) {
  const double x = h / (2.0 * r_max);
  if (x >= 1.5) return false;  // the series bound holds for small angles only
  const double one_minus_cos = 0.5 * (3.0 - a.R.cwiseProduct(b.R).sum());
  return one_minus_cos <= 0.5 * x * x * (1.0 - x * x / 12.0);
}

std::string tendon_name(int k) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "tendon T%d (index %d)", k + 1, k);
  return buf;
}

std::string between(const TendonRouting& rt, int j) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "between disks %d and %d (s = %.4g .. %.4g m)", j - 1, j, rt.disk_s[j - 1],
                rt.disk_s[j]);
  return buf;
}

}  // namespace

std::string tendon_limit_message(int tendon, double value, const std::string& where) {
  char buf[64];
  std::snprintf(buf, sizeof buf, ": curvature x offset %.4f ", value);
  return "infeasible actuation: " + tendon_name(tendon) + " at its geometric limit" + buf + where +
         " (at 1 the tendon reaches the centre of curvature; beyond, it would have to cross the backbone)";
}

void check_geometry(const Robot& robot, const TendonRouting& rt, Solution& sol, double max_curvature) {
  const std::vector<Frame>& f = sol.disk_frames;
  if (static_cast<int>(f.size()) != rt.disk_count() || rt.tendons.empty()) return;
  const double rb = robot.backbone.outer_radius;
  double disk_radius = 0.0;
  for (const RoutedTendon& t : rt.tendons) disk_radius = std::max(disk_radius, max_offset(t));
  // A known curvature bound kappa turns disks h apart by at most kappa h: quiet() for every pair.
  if (max_curvature >= 0.0 && max_curvature * disk_radius <= 0.5) return;
  // Most shapes turn gently between every pair of disks: then there is nothing to find.
  bool all_quiet = true;
  for (int j = 1; j < rt.disk_count() && all_quiet; ++j)
    all_quiet = quiet(f[j - 1], f[j], rt.disk_s[j] - rt.disk_s[j - 1], disk_radius);
  if (all_quiet) return;
  char buf[160];
  for (const RoutedTendon& t : rt.tendons) {
    // The worst interval of each tendon for each finding. Every hole is computed once; the exact
    // chord distance only where a cheap lower bound (midpoint distance minus the half chord
    // lengths) does not already clear the backbone radius.
    int jc = -1, jd = -1;
    double worst_c = kTendonLimitWarn, worst_d = rb;
    Vec3 h0 = hole_position(f[0], t, rt.disk_s[0]);
    for (int j = 1; j <= t.end_disk; ++j) {
      if (quiet(f[j - 1], f[j], rt.disk_s[j] - rt.disk_s[j - 1], disk_radius)) {
        if (j < t.end_disk) h0 = hole_position(f[j], t, rt.disk_s[j]);
        continue;
      }
      const Vec3 h1 = hole_position(f[j], t, rt.disk_s[j]);
      const Vec3 dp = f[j].p - f[j - 1].p, dh = h1 - h0;
      const double c = 1.0 - dh.dot(dp) / dp.squaredNorm();
      if (c >= worst_c) worst_c = c, jc = j;
      const double bound = (0.5 * (h0 + h1 - f[j - 1].p - f[j].p)).norm() - 0.5 * (dh.norm() + dp.norm());
      if (bound < worst_d) {
        const double d = segment_distance(h0, h1, f[j - 1].p, f[j].p);
        if (d < worst_d) worst_d = d, jd = j;
      }
      h0 = h1;
    }
    if (jc > 0) {
      if (worst_c >= 1.0)
        std::snprintf(buf, sizeof buf, ": curvature x offset %.4f >= 1, the tendon would cross the backbone", worst_c);
      else
        std::snprintf(buf, sizeof buf,
                      ": curvature x offset %.4f, at its geometric limit (>= %g: the models disagree whether the "
                      "actuation is feasible)",
                      worst_c, kTendonLimitWarn);
      sol.geometry_warnings.push_back({tendon_name(t.index) + " " + between(rt, jc) + buf, t.index, jc, worst_c});
    }
    if (jd > 0) {
      std::snprintf(buf, sizeof buf, ": its chord passes %.3g m from the backbone chord (backbone radius %.3g m)",
                    worst_d, rb);
      sol.geometry_warnings.push_back({tendon_name(t.index) + " " + between(rt, jd) + buf, t.index, jd, worst_d});
    }
  }
  int pairs = 0, jw = -1;
  double worst = 0.0;
  for (int j = 1; j < rt.disk_count(); ++j) {
    if (quiet(f[j - 1], f[j], rt.disk_s[j] - rt.disk_s[j - 1], disk_radius)) continue;
    const double o = disk_overlap(f[j - 1], f[j], disk_radius);
    if (o <= 0.0) continue;
    ++pairs;
    if (o > worst) worst = o, jw = j;
  }
  if (pairs > 0) {
    std::snprintf(buf, sizeof buf,
                  "disks %d and %d interpenetrate (radius %.3g m, overlap %.3g m along their planes' "
                  "intersection); %d neighbouring pairs in all",
                  jw - 1, jw, disk_radius, worst, pairs);
    sol.geometry_warnings.push_back({buf, -1, jw, worst});
  }
}

bool tendon_limit(const TendonRouting& rt, const Solution& sol, double threshold, std::string& why) {
  const std::vector<Frame>& f = sol.disk_frames;
  if (static_cast<int>(f.size()) != rt.disk_count()) return false;
  int k = -1, jw = -1;
  double worst = threshold;
  for (const RoutedTendon& t : rt.tendons) {
    if (t.index >= static_cast<int>(sol.tensions.size()) || !(sol.tensions[t.index] > 0.0)) continue;
    for (int j = 1; j <= t.end_disk; ++j) {
      const double c = curvature_offset(f, rt, t, j);
      if (c >= worst) worst = c, k = t.index, jw = j;
    }
  }
  if (k < 0) return false;
  why = tendon_limit_message(k, worst, between(rt, jw));
  return true;
}

}  // namespace tdcr::physics
