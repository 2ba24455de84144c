// The VC model: construction, the per-input choice of formulation, and its workspace (vc.hpp).
#include "tdcr/models/vc.hpp"

#include "tdcr/core/error.hpp"
#include "vc/vc_shooting.hpp"

namespace tdcr {

VcWorkspace::VcWorkspace(const VcModel& owner) : ModelWorkspace(owner), impl_(std::make_unique<Impl>(owner)) {}

VcWorkspace::~VcWorkspace() = default;

long VcWorkspace::rhs_evaluations() const {
  long n = impl_->retired_rhs;
  if (impl_->shot_integrator) n += impl_->shot_integrator->rhs_evaluations();
  if (impl_->final_integrator) n += impl_->final_integrator->rhs_evaluations();
  if (impl_->stability_integrator) n += impl_->stability_integrator->rhs_evaluations();
  return n;
}

VcModel::VcModel(const Robot& robot, const Effects& effects, VcOptions options)
    : StaticModel(robot, effects), options_(options) {
  options_.kink_forces = options_.kink_forces && effects.kink_forces;  // either turns them off
  // Friction (vc_friction.hpp): single shooting only (multiple shooting has no tension states).
  if (effects.tendon_friction.on() && options_.formulation == VcFormulation::MultipleShooting)
    throw InputError("effects.tendon_friction", "on",
                     "VC's multiple shooting has no tension states; use single shooting or the automatic formulation");
  if (!(options_.multiple_shooting_threshold >= 0.0))
    throw InputError("multiple_shooting_threshold", format_value(options_.multiple_shooting_threshold),
                     "must be a number >= 0");
}

VcModel::~VcModel() = default;

std::unique_ptr<ModelWorkspace> VcModel::make_workspace() const { return std::make_unique<VcWorkspace>(*this); }

double VcModel::load_parameter(const ModelInput& input) const {
  physics::LoadCase loads;
  loads.bind(robot(), routing(), input);
  return loads.load_parameter();
}

bool VcModel::uses_multiple_shooting(const ModelInput& input) const {
  return multiple_shooting(load_parameter(input));
}

bool VcModel::multiple_shooting(double load_parameter) const {
  if (effects().tendon_friction.on()) return false;
  switch (options_.formulation) {
    case VcFormulation::SingleShooting: return false;
    case VcFormulation::MultipleShooting: return true;
    case VcFormulation::Automatic: break;
  }
  return load_parameter > options_.multiple_shooting_threshold;
}

detail::ModelProblem& VcModel::bind(ModelWorkspace& workspace, const ModelInput& input,
                                    const SolverOptions& options) const {
  VcWorkspace::Impl& W = static_cast<VcWorkspace&>(workspace).impl();
  vc::bind_input(W, *this, input, options);
  // Contact is modelled in single shooting (vc_single_shooting.cpp, docs/contact.md).
  if (multiple_shooting(W.loads.load_parameter()) && input.environment.obstacles.empty()) {
    if (!W.multiple) W.multiple = vc::make_multiple_shooting(W);
    return *W.multiple;
  }
  if (!W.single) W.single = vc::make_single_shooting(W);
  return *W.single;
}


}  // namespace tdcr
