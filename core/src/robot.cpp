#include "tdcr/core/robot.hpp"

#include <cmath>
#include <string>

#include "tdcr/core/error.hpp"

namespace tdcr {

namespace {

void require_finite(const std::string& field, double v) {
  if (!std::isfinite(v)) throw InputError(field, format_value(v), "must be a finite number");
}
void require_positive(const std::string& field, double v) {
  require_finite(field, v);
  if (!(v > 0.0)) throw InputError(field, format_value(v), "must be positive");
}
void require_non_negative(const std::string& field, double v) {
  require_finite(field, v);
  if (v < 0.0) throw InputError(field, format_value(v), "must not be negative");
}

}  // namespace

BackboneStiffness Backbone::effective_stiffness() const {
  if (stiffness) return *stiffness;
  const double ro = outer_radius, ri = inner_radius;
  const double I = M_PI / 4.0 * (ro * ro * ro * ro - ri * ri * ri * ri);
  const double A = M_PI * (ro * ro - ri * ri);
  const double G = shear_modulus ? *shear_modulus : youngs_modulus / (2.0 * (1.0 + poisson_ratio));
  return BackboneStiffness{youngs_modulus * I, G * 2.0 * I, youngs_modulus * A, G * A};
}

double Backbone::linear_mass() const {
  if (mass_per_length) return *mass_per_length;
  if (stiffness) return 0.0;  // no section known: only mass_per_length can give a mass
  return density * M_PI * (outer_radius * outer_radius - inner_radius * inner_radius);
}

void Robot::validate() const {
  const std::string bb = "robot.backbone";
  if (backbone.stiffness) {
    const auto& k = *backbone.stiffness;
    require_positive(bb + ".EI", k.EI);
    require_positive(bb + ".GJ", k.GJ);
    require_positive(bb + ".EA", k.EA);
    require_positive(bb + ".GA", k.GA);
  } else {
    require_positive(bb + ".youngs_modulus", backbone.youngs_modulus);
    require_positive(bb + ".outer_radius", backbone.outer_radius);
    require_non_negative(bb + ".inner_radius", backbone.inner_radius);
    if (!(backbone.inner_radius < backbone.outer_radius))
      throw InputError(bb + ".inner_radius", format_value(backbone.inner_radius),
                       "must be smaller than outer_radius " + format_value(backbone.outer_radius));
    if (backbone.shear_modulus) {
      require_positive(bb + ".shear_modulus", *backbone.shear_modulus);
    } else {
      require_finite(bb + ".poisson_ratio", backbone.poisson_ratio);
      if (!(backbone.poisson_ratio > -1.0 && backbone.poisson_ratio < 0.5))
        throw InputError(bb + ".poisson_ratio", format_value(backbone.poisson_ratio),
                         "must lie in (-1, 0.5)");
    }
  }
  require_non_negative(bb + ".density", backbone.density);
  if (backbone.mass_per_length) require_non_negative(bb + ".mass_per_length", *backbone.mass_per_length);

  if (segments.empty()) throw InputError("robot.segments", "[]", "must list at least one segment");
  for (std::size_t i = 0; i < segments.size(); ++i) {
    const std::string sp = "robot.segments[" + std::to_string(i) + "]";
    const Segment& seg = segments[i];
    require_positive(sp + ".length", seg.length);
    if (seg.disks < 1)
      throw InputError(sp + ".disks", std::to_string(seg.disks), "must be at least 1");
    require_non_negative(sp + ".disk_mass", seg.disk_mass);
    for (std::size_t k = 0; k < seg.tendons.size(); ++k) {
      const std::string tp = sp + ".tendons[" + std::to_string(k) + "]";
      require_finite(tp + ".x", seg.tendons[k].x);
      require_finite(tp + ".y", seg.tendons[k].y);
      if (seg.tendons[k].stiffness) require_positive(tp + ".stiffness", *seg.tendons[k].stiffness);
      const double r = std::hypot(seg.tendons[k].x, seg.tendons[k].y);
      // A tendon on the axis has no lever arm: it cannot bend the robot and makes the
      // constant-curvature maps singular.
      if (!(r > 1e-9))
        throw InputError(tp, "(" + format_value(seg.tendons[k].x) + ", " + format_value(seg.tendons[k].y) + ")",
                         "tendon lies on the backbone axis (distance must exceed 1e-9 m)");
    }
  }
}

double Robot::total_length() const {
  double L = 0.0;
  for (const auto& s : segments) L += s.length;
  return L;
}

int Robot::total_disks() const {
  int n = 0;
  for (const auto& s : segments) n += s.disks;
  return n;
}

int Robot::tendon_count() const {
  int n = 0;
  for (const auto& s : segments) n += static_cast<int>(s.tendons.size());
  return n;
}

TendonRouting TendonRouting::from(const Robot& robot) {
  TendonRouting t;
  t.disk_s.push_back(0.0);
  t.disk_segment.push_back(0);
  double s0 = 0.0;
  int global = 0;
  for (std::size_t i = 0; i < robot.segments.size(); ++i) {
    const Segment& seg = robot.segments[i];
    t.segment_start_s.push_back(s0);
    for (int j = 1; j <= seg.disks; ++j) {
      // The last disk sits exactly at the segment end, without rounding drift.
      t.disk_s.push_back(j == seg.disks ? s0 + seg.length : s0 + seg.length * j / seg.disks);
      t.disk_segment.push_back(static_cast<int>(i));
    }
    s0 += seg.length;
    t.segment_end_s.push_back(s0);
    t.segment_end_disk.push_back(static_cast<int>(t.disk_s.size()) - 1);
    for (const auto& tendon : seg.tendons) {
      RoutedTendon rt;
      rt.index = global++;
      rt.segment = static_cast<int>(i);
      rt.r = Vec3(tendon.x, tendon.y, 0.0);
      rt.end_disk = t.segment_end_disk.back();
      t.tendons.push_back(rt);
    }
  }
  return t;
}

}  // namespace tdcr
