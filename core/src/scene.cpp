#include "tdcr/core/scene.hpp"

#include <cmath>
#include <string>

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
  return e;
}

}  // namespace tdcr
