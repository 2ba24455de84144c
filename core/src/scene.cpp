#include "tdcr/core/scene.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "tdcr/core/contact_geometry.hpp"
#include "tdcr/core/error.hpp"

namespace tdcr {

namespace {
// `field` is a literal: no string is built unless there is an error to report.
void require_finite_vec(const char* field, const Vec3& v) {
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(v[i]))
      throw InputError(std::string(field) + "[" + std::to_string(i) + "]", format_value(v[i]), "must be a finite number");
}
}  // namespace

void Effects::validate() const {
  for (int i = 0; i < 4; ++i)
    if (!(std::isfinite(prb.gamma[i]) && prb.gamma[i] > 0.0))
      throw InputError("effects.prb.gamma[" + std::to_string(i) + "]", format_value(prb.gamma[i]), "must be positive");
  for (int i = 0; i < 3; ++i)
    if (!(std::isfinite(prb.k_theta[i]) && prb.k_theta[i] > 0.0))
      throw InputError("effects.prb.k_theta[" + std::to_string(i) + "]", format_value(prb.k_theta[i]),
                       "must be positive");
  const TendonFriction& tf = tendon_friction;
  if (!(std::isfinite(tf.coefficient) && tf.coefficient >= 0.0))
    throw InputError("effects.tendon_friction.coefficient", format_value(tf.coefficient),
                     "must be a finite number >= 0");
  for (std::size_t k = 0; k < tf.coefficients.size(); ++k)
    if (!(std::isfinite(tf.coefficients[k]) && tf.coefficients[k] >= 0.0))
      throw InputError("effects.tendon_friction.coefficients[" + std::to_string(k) + "]",
                       format_value(tf.coefficients[k]), "must be a finite number >= 0");
}

void Effects::validate(const Robot& robot) const {
  validate();
  const std::size_t n = tendon_friction.coefficients.size();
  if (n != 0 && static_cast<int>(n) != robot.tendon_count())
    throw InputError("effects.tendon_friction.coefficients", std::to_string(n) + " values",
                     "must list one coefficient per tendon (" + std::to_string(robot.tendon_count()) + " tendons)");
}

bool TendonFriction::on() const {
  if (coefficients.empty()) return coefficient > 0.0;
  for (double mu : coefficients)
    if (mu > 0.0) return true;
  return false;
}

void ModelInput::validate(const Robot& robot) const {
  // Called on every solve: one pass over the values for valid input; field names and the error
  // are found by the checks below only when something is wrong.
  environment.validate(robot);
  const int m = robot.tendon_count();
  if (static_cast<int>(actuation.values.size()) == m && !actuation.mixed()) {
    const bool tensions = actuation.kind == Actuation::Kind::Tensions;
    bool ok = loads.tip_force.allFinite() && loads.tip_moment.allFinite() && loads.gravity.allFinite();
    for (double v : actuation.values) ok = ok && std::isfinite(v) && !(tensions && v < 0.0);
    if (ok) return;
  }
  const auto key = [&](std::size_t k) {
    return actuation.kind_of(k) == Actuation::Kind::Tensions ? "actuation.tensions" : "actuation.displacements";
  };
  if (static_cast<int>(actuation.values.size()) != m)
    throw InputError(key(0), std::to_string(actuation.values.size()) + " values",
                     "must list one value per tendon (" + std::to_string(m) + " tendons)");
  if (actuation.mixed() && (actuation.kinds.size() != actuation.values.size() ||
                            actuation.kind != Actuation::Kind::Displacements))
    throw InputError("actuation", std::to_string(actuation.kinds.size()) + " kinds",
                     "mixed input needs one kind per value and kind Displacements");
  for (std::size_t k = 0; k < actuation.values.size(); ++k) {
    const double v = actuation.values[k];
    const bool tension = actuation.kind_of(k) == Actuation::Kind::Tensions;
    if (std::isfinite(v) && !(tension && v < 0.0)) continue;
    const std::string f = std::string(key(k)) + "[" + std::to_string(k) + "]";
    if (!std::isfinite(v)) throw InputError(f, format_value(v), "must be a finite number");
    throw InputError(f, format_value(v), "a tension must not be negative (tendons can only pull)");
  }
  require_finite_vec("loads.tip_force", loads.tip_force);
  require_finite_vec("loads.tip_moment", loads.tip_moment);
  require_finite_vec("loads.gravity", loads.gravity);
}

void Environment::validate(const Robot& robot) const {
  if (!(std::isfinite(contact.stiffness) && contact.stiffness >= 0.0))
    throw InputError("environment.contact.stiffness", format_value(contact.stiffness),
                     "must be a finite number >= 0 (0: rigid contact)");
  for (std::size_t i = 0; i < obstacles.size(); ++i) {
    const Obstacle& o = obstacles[i];
    const std::string p = "environment.obstacles[" + std::to_string(i) + "]";
    const auto vec = [&](const char* key, const Vec3& v) {
      require_finite_vec((p + "." + key).c_str(), v);
    };
    const auto positive = [&](const char* key, double v) {
      if (!(std::isfinite(v) && v > 0.0)) throw InputError(p + "." + key, format_value(v), "must be positive");
    };
    using T = Obstacle::Type;
    switch (o.type) {
      case T::Plane:
        vec("point", o.point);
        vec("normal", o.normal);
        if (o.normal.norm() == 0.0) throw InputError(p + ".normal", "[0, 0, 0]", "must not be zero");
        break;
      case T::Sphere:
        vec("center", o.center);
        positive("radius", o.radius);
        break;
      case T::Cylinder:
      case T::Capsule:
        vec("ends[0]", o.ends[0]);
        vec("ends[1]", o.ends[1]);
        positive("radius", o.radius);
        if ((o.ends[1] - o.ends[0]).norm() == 0.0)
          throw InputError(p + ".ends", "two equal points", "the axis end points must differ");
        break;
      case T::Lumen:
        positive("radius", o.radius);
        if (o.centreline.size() < 2)
          throw InputError(p + ".centreline", std::to_string(o.centreline.size()) + " points",
                           "must list at least 2 points");
        for (std::size_t k = 0; k < o.centreline.size(); ++k) {
          vec(("centreline[" + std::to_string(k) + "]").c_str(), o.centreline[k]);
          if (k > 0 && (o.centreline[k] - o.centreline[k - 1]).norm() == 0.0)
            throw InputError(p + ".centreline[" + std::to_string(k) + "]", "a repeated point",
                             "consecutive centreline points must differ");
        }
        break;
    }
    // The base is clamped: an obstacle it already penetrates has no answer.
    const double disk = robot.segments.empty() ? 0.0 : robot.segments[0].disk_radius;
    const ContactPoint bb = contact_point(o, Frame{}, ContactBody::Backbone, robot.backbone.outer_radius);
    const ContactPoint dk = contact_point(o, Frame{}, ContactBody::Disk, disk);
    const double gap = std::min(bb.gap, disk > 0.0 ? dk.gap : bb.gap);
    if (!(gap > 0.0))
      throw InputError(p, "gap " + format_value(gap) + " m at the base",
                       "the obstacle intersects the robot's base (its backbone or base disk at s = 0)");
  }
}

void Scene::validate() const {
  robot.validate();
  input().validate(robot);
  effects.validate(robot);
  solver.validate();
  if (dynamics) dynamics->validate();
  if (!timeline.entries.empty()) timeline.validate(robot);
}

SceneEffects active_effects(const Robot& robot, const Effects& effects, const ModelInput& input) {
  SceneEffects e;
  const Loads& loads = input.loads;
  e.tip_wrench = loads.tip_force.squaredNorm() > 0.0 || loads.tip_moment.squaredNorm() > 0.0;
  const bool g = loads.gravity.squaredNorm() > 0.0;
  e.backbone_weight = g && robot.backbone.linear_mass() > 0.0;
  bool disks = false;
  for (const auto& s : robot.segments) disks = disks || s.disk_mass > 0.0;
  e.disk_weight = g && disks;
  e.gravity = e.backbone_weight || e.disk_weight;
  e.shear_extension = effects.shear_extension;
  e.disk_normal_force_removed = effects.disk_normal_force == DiskNormalForce::Removed;
  e.tendon_friction = effects.tendon_friction.on();
  e.contact = !input.environment.obstacles.empty();
  return e;
}

}  // namespace tdcr
