// The shared services of robots that move (tdcr/models/dynamics.hpp): the options' checks, the
// choice of a model's integrator, and the loop over the output times that every front end calls.
#include <cmath>
#include <sstream>
#include <string>

#include "tdcr/core/error.hpp"
#include "tdcr/models/dynamics.hpp"
#include "tdcr/models/lumped_model.hpp"
#include "tdcr/models/static_model.hpp"
#include "vc/vc_dynamics.hpp"

namespace tdcr {

namespace {
// More output steps than this is a typo in --duration or --dt, not a simulation.
constexpr double kMaxSteps = 1e7;
}  // namespace

void SimulationOptions::validate() const {
  if (!std::isfinite(duration) || duration <= 0.0)
    throw InputError("duration", format_value(duration), "must be a finite time > 0 (s)");
  if (!std::isfinite(dt) || dt <= 0.0) throw InputError("dt", format_value(dt), "must be a finite time step > 0 (s)");
  if (duration / dt > kMaxSteps)
    throw InputError("dt", format_value(dt),
                     "gives more than 1e7 output steps over the duration " + format_value(duration) + " s");
}

std::unique_ptr<DynamicsIntegrator> make_dynamics_integrator(const StaticModel& model,
                                                             const DynamicsSettings& settings, double dt,
                                                             const SolverOptions& solver) {
  settings.validate();
  if (!std::isfinite(dt) || dt <= 0.0) throw InputError("dt", format_value(dt), "must be a finite time step > 0 (s)");
  switch (model.kind()) {
    case ModelKind::CCsub:
    case ModelKind::PRB:
      return static_cast<const LumpedModel&>(model).make_dynamics_integrator(settings, dt, solver);
    case ModelKind::VC:
    case ModelKind::VCref:
      return make_cosserat_dynamics_integrator(model, settings, dt);
    case ModelKind::CC:
      break;
  }
  throw InputError("model", model.name(), "has no dynamics (CCsub, PRB, VC and VCref have)");
}

SimulationResult simulate(const StaticModel& model, const DynamicsSettings& settings, const Timeline& timeline,
                          const SimulationOptions& options, const SolverOptions& solver,
                          const SimulationObserver& observer) {
  options.validate();
  settings.validate();
  timeline.validate(model.robot());
  std::unique_ptr<DynamicsIntegrator> integrator = make_dynamics_integrator(model, settings, options.dt, solver);
  if (integrator->takes_displacement_input()) integrator->check_displacement_input(timeline);
  if (!integrator->takes_displacement_input())
    for (std::size_t i = 0; i < timeline.entries.size(); ++i) {
      const Actuation& a = timeline.entries[i].input.actuation;
      if (a.kind != Actuation::Kind::Tensions || a.mixed())
        throw InputError("timeline[" + std::to_string(i) + "].actuation", "displacements",
                         model.name() + "'s dynamics take tension input only so far (VC and VCref take displacements)");
    }
  SimulationResult result;
  // t = 0: at rest on the static answer of the first input.
  const ModelInput first = timeline.at(0.0);
  std::unique_ptr<ModelWorkspace> ws = model.make_workspace();
  const Solution rest = solve(model, *ws, first, solver);
  SimulationStep s0;
  s0.status = rest.summary.termination;
  s0.iterations = rest.summary.iterations;
  s0.residual = rest.summary.residual_norm;
  if (!rest.disk_frames.empty()) s0.tip = rest.disk_frames.back();
  if (!rest.converged()) {
    result.steps.push_back(s0);
    if (observer) observer(s0, rest);
    std::ostringstream m;
    m << "the static answer at t = 0 did not converge (" << to_string(rest.summary.termination) << ", residual "
      << rest.summary.residual_norm << ", " << rest.summary.iterations << " iterations)";
    result.message = m.str();
    return result;
  }
  integrator->initialize(rest, first);
  const long steps = std::lround(std::ceil(options.duration / options.dt - 1e-9));
  result.steps.reserve(static_cast<std::size_t>(steps) + 1);
  {
    // At rest: no kinetic energy; the potential energy of the start from the integrator.
    s0.kinetic_energy = 0.0;
    s0.potential_energy = integrator->potential_energy();
    s0.tensions = rest.tensions;
    s0.tendon_displacements = rest.tendon_displacements;
    result.steps.push_back(s0);
    if (observer) observer(s0, rest);
  }
  for (long k = 1; k <= steps; ++k) {
    const double t = std::min(options.duration, static_cast<double>(k) * options.dt);
    SimulationStep s = integrator->advance(t, timeline);
    if (s.tensions.empty()) {  // tension input (the integrators without displacement input): as given
      const ModelInput in = timeline.at(s.t);
      if (in.actuation.kind == Actuation::Kind::Tensions && !in.actuation.mixed()) s.tensions = in.actuation.values;
    }
    result.steps.push_back(s);
    if (observer) observer(s, integrator->shape());
    if (s.status != TerminationType::Converged) {
      std::ostringstream m;
      m << "step to t = " << t << " s failed at t = " << s.t << " s (" << to_string(s.status) << ", residual "
        << s.residual << ", " << s.iterations << " iterations)";
      result.message = m.str();
      return result;
    }
  }
  result.completed = true;
  return result;
}

}  // namespace tdcr
