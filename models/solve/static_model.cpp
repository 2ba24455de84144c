// The StaticModel and ModelWorkspace base classes: what every model shares (validation, routing,
// fingerprint, the input checks its capabilities imply) and the ownership of workspaces.
#include "tdcr/models/static_model.hpp"

#include "solve/displacement_input.hpp"

#include <cstdio>

#include "tdcr/core/error.hpp"
#include "tdcr/core/scene_io.hpp"

namespace tdcr {

namespace {
// FNV-1a of the model's description: kind, robot and effects as the scene file writes them.
std::uint64_t fnv1a(const std::string& s, std::uint64_t h = 1469598103934665603ull) {
  for (unsigned char c : s) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}
}  // namespace

StaticModel::StaticModel(const Robot& robot, const Effects& effects)
    : robot_(robot), effects_(effects), token_(std::make_shared<const int>(0)) {
  robot_.validate();
  effects_.validate(robot_);
  routing_ = TendonRouting::from(robot_);
  Scene description;
  description.robot = robot_;
  description.effects = effects_;
  description.actuation.values.assign(robot_.tendon_count(), 0.0);
  fingerprint_ = fnv1a(scene_to_json(description));
}

StaticModel::~StaticModel() = default;

void StaticModel::check_input(const ModelInput& input) const {
  const ModelCapabilities caps = capabilities();
  const bool tensions = input.actuation.kind == Actuation::Kind::Tensions;
  if (tensions && !caps.tension_input)
    throw InputError("actuation.tensions", "given", "the " + name() + " model takes tendon displacements");
  if (!tensions && !caps.displacement_input)
    throw InputError("actuation.displacements", "given", "the " + name() + " model takes tendon tensions");
  if (!tensions && !caps.displacement_statics) {
    if (input.actuation.mixed())
      throw InputError("actuation", "tensions and displacements",
                       "the " + name() + " model is kinematic: give every tendon by displacement or every tendon by "
                       "tension (mixed input needs a static model)");
    for (std::size_t i = 0; i < robot_.segments.size(); ++i)
      for (std::size_t j = 0; j < robot_.segments[i].tendons.size(); ++j)
        if (robot_.segments[i].tendons[j].stiffness)
          throw InputError("robot.segments[" + std::to_string(i) + "].tendons[" + std::to_string(j) + "].stiffness",
                           format_value(*robot_.segments[i].tendons[j].stiffness),
                           "the " + name() + " model is kinematic: elastic tendons need a static model");
  }
  if (!caps.contact && !input.environment.obstacles.empty())
    throw InputError("environment.obstacles", std::to_string(input.environment.obstacles.size()) + " obstacles",
                     "the " + name() + " model does not model contact yet (CCsub, PRB, VC and VCref do)");
  if (!input.environment.obstacles.empty() && !tensions)
    throw InputError("environment.obstacles", std::to_string(input.environment.obstacles.size()) + " obstacles",
                     "contact is modelled with tension input only so far (give actuation.tensions)");
  if (!caps.external_loads) {
    const Loads& l = input.loads;
    auto refuse = [&](const char* field, const Vec3& v) {
      if (v.squaredNorm() > 0.0) {
        char b[96];
        std::snprintf(b, sizeof b, "[%g, %g, %g]", v.x(), v.y(), v.z());
        throw InputError(field, b, "the " + name() + " model is kinematic and takes no external load; use a static model");
      }
    };
    refuse("loads.tip_force", l.tip_force);
    refuse("loads.tip_moment", l.tip_moment);
    refuse("loads.gravity", l.gravity);
  }
}

ModelWorkspace::ModelWorkspace(const StaticModel& owner) : owner_(owner.ownership_token()) {}
ModelWorkspace::~ModelWorkspace() = default;

bool ModelWorkspace::belongs_to(const StaticModel& model) const {
  const std::shared_ptr<const int> owner = owner_.lock();
  return owner && owner == model.ownership_token();
}

}  // namespace tdcr
