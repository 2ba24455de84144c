// The contact law and the candidate pairs shared by the models with contact (docs/contact.md):
// CCsub and PRB (models/lumped/lumped_contact*.cpp) and VCref (models/vcref/vcref_contact.cpp).
//
// A candidate is one body part at one disk (the backbone's surface about the disk centre, the
// disk's rim) against one obstacle; its force magnitude f = b F_s (F_s = EI / L^2) is an unknown
// with one residual:
// - rigid: gap g >= 0, b >= 0, g b = 0 as the Fischer-Burmeister equation
//   phi(a, b) = a + b - sqrt(a^2 + b^2) = 0, a = g / r_o (or min(a, b) = 0, the active set's
//   semismooth form, for a solve's first steps);
// - compliant (stiffness k > 0, N/m): b - k max(0, -g) / F_s = 0.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "tdcr/core/contact_geometry.hpp"
#include "tdcr/core/lie.hpp"
#include "tdcr/core/scene.hpp"
#include "tdcr/core/solution.hpp"

namespace tdcr::contact {

// A candidate contact and its state at the last evaluation.
struct Candidate {
  int disk = 0;
  int obstacle = 0;
  ContactBody body = ContactBody::Backbone;
  double lambda = 0.0;  // scaled force magnitude b = f / F_s
  ContactPoint at;      // contact point, gap and normal at the last evaluation
};

// The complementarity residual of one candidate and its derivatives.
struct Law {
  double stiffness = 0.0;     // N/m; 0: rigid
  double force_scale = 1.0;   // F_s (N)
  double length_scale = 1.0;  // r_o (m)
  bool use_min = false;       // rigid contact as min(a, b) = 0

  double residual(double gap, double b) const {
    if (stiffness > 0.0) return b - stiffness * std::max(0.0, -gap) / force_scale;
    const double a = gap / length_scale;
    if (use_min) return std::min(a, b);
    return a + b - std::sqrt(a * a + b * b);
  }
  // d residual / d gap (1/m) and d residual / d b; at the corner a = b = 0 an element of the
  // generalised gradient.
  void derivatives(double gap, double b, double& dgap, double& db) const {
    if (stiffness > 0.0) {
      dgap = gap < 0.0 ? stiffness / force_scale : 0.0;
      db = 1.0;
      return;
    }
    const double rs = length_scale, a = gap / rs;
    if (use_min) {
      dgap = a <= b ? 1.0 / rs : 0.0;
      db = a <= b ? 0.0 : 1.0;
      return;
    }
    const double r = std::sqrt(a * a + b * b);
    const double ca = r > 0.0 ? a / r : M_SQRT1_2, cb = r > 0.0 ? b / r : M_SQRT1_2;
    dgap = (1.0 - ca) / rs;
    db = 1.0 - cb;
  }
};

// The contact surfaces of the robot: the backbone's outer radius and each disk's radius
// (index 0..N; 0: no disk contact).
struct Surfaces {
  double backbone_radius = 0.0;
  std::vector<double> disk_radius;
  double radius(int disk, ContactBody body) const { return body == ContactBody::Disk ? disk_radius[disk] : backbone_radius; }
};

// What scan() found in one shape.
struct Scan {
  bool penetrates = false;      // some pair that is not a candidate is penetrated (by more than kPenetration)
  bool passed_through = false;  // a finite obstacle (not plane, not lumen) penetrated deeper than a quarter of its radius
  double deepest = 0.0;         // the deepest penetration (m) of a pair that is not a candidate
};

// The disk frames a fraction t of the way between two shapes (frames 0..N, `from` and `to`): each
// disk along the screw between its two poses, position linear, rotation by the geodesic (the
// sweeps that look for obstacles a step of the robot passed).
inline void frames_between(const std::vector<Frame>& from, const std::vector<Frame>& to, double t,
                           std::vector<Frame>& between) {
  between.resize(from.size());
  for (std::size_t j = 0; j < from.size(); ++j) {
    between[j].p = (1.0 - t) * from[j].p + t * to[j].p;
    between[j].R = from[j].R * lie::exp_so3(t * lie::log_so3(from[j].R.transpose() * to[j].R));
  }
}

// A shape penetrating an obstacle deeper than this (m) is not an answer.
constexpr double kPenetration = 1e-12;

// The pairs of disks 1..N (frames[0..N]) with the obstacles that are not candidates: whether any
// is penetrated; with `add` and a penetration, every such pair with a gap below `margin` joins
// the candidates (force 0).
inline Scan scan(const std::vector<Obstacle>& obstacles, const Surfaces& surfaces, const Frame* frames, int N,
                 double margin, bool add, std::vector<Candidate>& candidates) {
  Scan out;
  const auto is_candidate = [&](int j, int o, ContactBody b) {
    for (const Candidate& c : candidates)
      if (c.disk == j && c.obstacle == o && c.body == b) return true;
    return false;
  };
  for (int pass = 0; pass < (add ? 2 : 1); ++pass) {
    for (int j = 1; j <= N; ++j)
      for (int o = 0; o < static_cast<int>(obstacles.size()); ++o)
        for (ContactBody b : {ContactBody::Backbone, ContactBody::Disk}) {
          const double radius = surfaces.radius(j, b);
          if (b == ContactBody::Disk && radius <= 0.0) continue;
          if (is_candidate(j, o, b)) continue;
          const double gap = contact_point(obstacles[o], frames[j], b, radius).gap;
          if (pass == 0 && gap < -kPenetration) {
            out.penetrates = true;
            out.deepest = std::max(out.deepest, -gap);
            const Obstacle& ob = obstacles[o];
            if (ob.type != Obstacle::Type::Plane && ob.type != Obstacle::Type::Lumen && -gap > 0.25 * ob.radius)
              out.passed_through = true;
          }
          if (pass == 1 && gap < margin) {
            Candidate c;
            c.disk = j, c.obstacle = o, c.body = b;
            candidates.push_back(c);
          }
        }
    if (!out.penetrates) break;
  }
  return out;
}

// Solution::contacts from the candidates that carry force (b above `reported`), disk arc
// lengths `disk_s`.
inline void report(const std::vector<Candidate>& candidates, const std::vector<double>& disk_s, double force_scale,
                   double reported, std::vector<Contact>& out) {
  out.clear();
  for (const Candidate& c : candidates) {
    if (!(c.lambda > reported)) continue;
    Contact r;
    r.s = disk_s[c.disk];
    r.point = c.at.point;
    r.normal = c.at.normal;
    r.force = c.lambda * force_scale;
    r.gap = c.at.gap;
    r.disk = c.body == ContactBody::Disk;
    r.disk_index = c.disk;
    r.obstacle = c.obstacle;
    out.push_back(r);
  }
}

}  // namespace tdcr::contact
