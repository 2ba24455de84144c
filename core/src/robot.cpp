#include "tdcr/core/robot.hpp"

#include <array>
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

void require_off_axis(const std::string& field, double x, double y) {
  // A tendon on the axis has no lever arm: it cannot bend the robot and makes the
  // constant-curvature maps singular.
  if (!(std::hypot(x, y) > 1e-9))
    throw InputError(field, "(" + format_value(x) + ", " + format_value(y) + ")",
                     "tendon lies on the backbone axis (distance must exceed 1e-9 m)");
}

void validate_routing(const std::string& tp, const TendonRoutingSpec& r, int disks_passed) {
  using Type = TendonRoutingSpec::Type;
  if (r.type == Type::Helical) require_finite(tp + ".routing.turns", r.turns);
  if (r.type != Type::Points) return;
  const std::string pp = tp + ".routing.positions";
  if (static_cast<int>(r.positions.size()) != disks_passed)
    throw InputError(pp, std::to_string(r.positions.size()) + " positions",
                     "must give one position per disk the tendon passes after the base disk: " +
                         std::to_string(disks_passed));
  for (std::size_t j = 0; j < r.positions.size(); ++j) {
    const std::string jp = pp + "[" + std::to_string(j) + "]";
    require_finite(jp, r.positions[j][0]);
    require_finite(jp, r.positions[j][1]);
    require_off_axis(jp, r.positions[j][0], r.positions[j][1]);
  }
}

/// Natural cubic spline through (x_i, y_i): per interval (y, y', y''/2, y'''/6) at its start.
void natural_spline(const std::vector<double>& x, const std::vector<double>& y, int column,
                    std::vector<std::array<double, 8>>& coef) {
  const int n = static_cast<int>(x.size()) - 1;
  std::vector<double> M(n + 1, 0.0), c(n + 1, 0.0), d(n + 1, 0.0);
  // Tridiagonal system for the interior second derivatives (Thomas algorithm).
  for (int i = 1; i < n; ++i) {
    const double h0 = x[i] - x[i - 1], h1 = x[i + 1] - x[i];
    const double a = h0, b = 2.0 * (h0 + h1), rhs = 6.0 * ((y[i + 1] - y[i]) / h1 - (y[i] - y[i - 1]) / h0);
    const double m = b - a * c[i - 1];
    c[i] = h1 / m;
    d[i] = (rhs - a * d[i - 1]) / m;
  }
  for (int i = n - 1; i >= 1; --i) M[i] = d[i] - c[i] * M[i + 1];
  for (int i = 0; i < n; ++i) {
    const double h = x[i + 1] - x[i];
    std::array<double, 8>& k = coef[i];
    k[4 * column + 0] = y[i];
    k[4 * column + 1] = (y[i + 1] - y[i]) / h - h * (2.0 * M[i] + M[i + 1]) / 6.0;
    k[4 * column + 2] = 0.5 * M[i];
    k[4 * column + 3] = (M[i + 1] - M[i]) / (6.0 * h);
  }
}

/// The routing data of `rt` (its segment and end disk set) from `spec`, over the disks `disk_s`.
void route(const TendonRoutingSpec& spec, const std::vector<double>& disk_s, RoutedTendon& rt) {
  using Type = TendonRoutingSpec::Type;
  rt.routing = spec.type;
  if (spec.type == Type::Helical) {
    rt.helix_radius = rt.r.norm();
    rt.helix_phase = std::atan2(rt.r.y(), rt.r.x());
    rt.helix_rate = 2.0 * M_PI * spec.turns / disk_s[rt.end_disk];
  } else if (spec.type == Type::Points) {
    rt.knots.assign(disk_s.begin(), disk_s.begin() + rt.end_disk + 1);
    std::vector<double> px{rt.r.x()}, py{rt.r.y()};
    for (const auto& q : spec.positions) {
      px.push_back(q[0]);
      py.push_back(q[1]);
    }
    rt.holes.clear();
    for (std::size_t j = 0; j < px.size(); ++j) rt.holes.emplace_back(px[j], py[j], 0.0);
    rt.spline.assign(rt.end_disk, std::array<double, 8>{});
    natural_spline(rt.knots, px, 0, rt.spline);
    natural_spline(rt.knots, py, 1, rt.spline);
  }
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
  int disks_passed = 0;  // disks after the base up to the current segment's end
  for (std::size_t i = 0; i < segments.size(); ++i) {
    const std::string sp = "robot.segments[" + std::to_string(i) + "]";
    const Segment& seg = segments[i];
    require_positive(sp + ".length", seg.length);
    if (seg.disks < 1)
      throw InputError(sp + ".disks", std::to_string(seg.disks), "must be at least 1");
    require_non_negative(sp + ".disk_mass", seg.disk_mass);
    require_non_negative(sp + ".disk_radius", seg.disk_radius);
    disks_passed += seg.disks;
    for (std::size_t k = 0; k < seg.tendons.size(); ++k) {
      const std::string tp = sp + ".tendons[" + std::to_string(k) + "]";
      require_finite(tp + ".x", seg.tendons[k].x);
      require_finite(tp + ".y", seg.tendons[k].y);
      if (seg.tendons[k].stiffness) require_positive(tp + ".stiffness", *seg.tendons[k].stiffness);
      require_off_axis(tp, seg.tendons[k].x, seg.tendons[k].y);
      validate_routing(tp, seg.tendons[k].routing, disks_passed);
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
      route(tendon.routing, t.disk_s, rt);
      t.tendons.push_back(rt);
    }
  }
  return t;
}

}  // namespace tdcr
