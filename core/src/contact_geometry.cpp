#include "tdcr/core/contact_geometry.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace tdcr {

namespace {

// A unit vector perpendicular to the unit vector u: the normal where the gradient is undefined
// (a point on an axis), any choice being as good.
Vec3 perpendicular(const Vec3& u) { return u.unitOrthogonal(); }

// A ball of radius r about q: the signed distance of x (capsules, spheres).
SignedDistance around_point(const Vec3& x, const Vec3& q, double r, const Vec3& axis) {
  SignedDistance d;
  const Vec3 v = x - q;
  const double rho = v.norm();
  d.normal = rho > 0.0 ? Vec3(v / rho) : perpendicular(axis);
  d.distance = rho - r;
  d.closest = q + r * d.normal;
  return d;
}

// Closest point to x on the segment a-b, with the parameter clamped to [lo, hi] (an open end:
// an infinite bound).
Vec3 closest_on_segment(const Vec3& x, const Vec3& a, const Vec3& b, double lo, double hi) {
  const Vec3 ab = b - a;
  const double t = std::clamp((x - a).dot(ab) / ab.squaredNorm(), lo, hi);
  return a + t * ab;
}

SignedDistance cylinder(const Obstacle& o, const Vec3& x) {
  const Vec3 a = o.ends[0];
  const Vec3 axis = o.ends[1] - a;
  const double h = axis.norm();
  const Vec3 u = axis / h;
  const double t = (x - a).dot(u);
  const Vec3 w = (x - a) - t * u;
  const double rho = w.norm();
  const Vec3 e = rho > 0.0 ? Vec3(w / rho) : perpendicular(u);
  const double dr = rho - o.radius;              // > 0 outside the mantle
  const double da = std::max(-t, t - h);         // > 0 beyond a cap
  const Vec3 cap = (t > 0.5 * h ? 1.0 : -1.0) * u;  // outward normal of the nearer cap
  SignedDistance d;
  if (dr > 0.0 && da > 0.0) {  // beyond the rim: distance to the circle
    d.distance = std::hypot(dr, da);
    d.normal = (dr * e + da * cap) / d.distance;
  } else if (dr > 0.0 || (dr <= 0.0 && da <= 0.0 && dr >= da)) {
    d.distance = dr;  // outside the mantle, or inside and nearest to it
    d.normal = e;
  } else {
    d.distance = da;  // beyond a cap, or inside and nearest to it
    d.normal = cap;
  }
  d.closest = x - d.distance * d.normal;
  return d;
}

SignedDistance lumen(const Obstacle& o, const Vec3& x) {
  const std::vector<Vec3>& c = o.centreline;
  const int segments = static_cast<int>(c.size()) - 1;
  constexpr double inf = std::numeric_limits<double>::infinity();
  double best = inf;
  Vec3 q = c[0], dir = c[1] - c[0];
  for (int i = 0; i < segments; ++i) {
    // The tube is open at both ends: the end segments continue straight.
    const Vec3 p = closest_on_segment(x, c[i], c[i + 1], i == 0 ? -inf : 0.0, i == segments - 1 ? inf : 1.0);
    const double d2 = (x - p).squaredNorm();
    if (d2 < best) best = d2, q = p, dir = c[i + 1] - c[i];
  }
  const Vec3 v = x - q;
  const double rho = v.norm();
  const Vec3 e = rho > 0.0 ? Vec3(v / rho) : perpendicular(dir.normalized());
  SignedDistance d;
  d.distance = o.radius - rho;
  d.normal = -e;  // free space is towards the centreline
  d.closest = q + o.radius * e;
  return d;
}

}  // namespace

SignedDistance signed_distance(const Obstacle& o, const Vec3& x) {
  switch (o.type) {
    case Obstacle::Type::Plane: {
      SignedDistance d;
      d.normal = o.normal.normalized();
      d.distance = (x - o.point).dot(d.normal);
      d.closest = x - d.distance * d.normal;
      return d;
    }
    case Obstacle::Type::Sphere:
      return around_point(x, o.center, o.radius, Vec3::UnitZ());
    case Obstacle::Type::Capsule: {
      const Vec3 q = closest_on_segment(x, o.ends[0], o.ends[1], 0.0, 1.0);
      return around_point(x, q, o.radius, (o.ends[1] - o.ends[0]).normalized());
    }
    case Obstacle::Type::Cylinder:
      return cylinder(o, x);
    case Obstacle::Type::Lumen:
      return lumen(o, x);
  }
  return {};
}

ContactPoint contact_point(const Obstacle& obstacle, const Frame& frame, ContactBody body, double radius) {
  const SignedDistance at_centre = signed_distance(obstacle, frame.p);
  ContactPoint c;
  if (body == ContactBody::Backbone) {
    c.gap = at_centre.distance - radius;
    c.normal = at_centre.normal;
    c.point = frame.p - radius * c.normal;
    return c;
  }
  // The rim point facing the obstacle: minus the normal projected on the disk plane.
  const Vec3 z = frame.R.col(2);
  const Vec3 w = -(at_centre.normal - at_centre.normal.dot(z) * z);
  const double wn = w.norm();
  if (wn < 1e-12) {  // the disk faces the obstacle squarely: its centre is as near as any point
    c.gap = at_centre.distance;
    c.normal = at_centre.normal;
    c.point = frame.p;
    return c;
  }
  c.point = frame.p + (radius / wn) * w;
  const SignedDistance at_rim = signed_distance(obstacle, c.point);
  c.gap = at_rim.distance;
  c.normal = at_rim.normal;
  return c;
}

const char* to_string(ContactBody body) { return body == ContactBody::Backbone ? "backbone" : "disk"; }

}  // namespace tdcr
