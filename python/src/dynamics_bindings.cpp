// Bindings of robots that move: tdcr.simulate (tdcr/models/dynamics.hpp), the trajectory as
// numpy arrays.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "bindings.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/core/lie.hpp"
#include "tdcr/models/dynamics.hpp"
#include "tdcr/models/static_model.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace tdcr_python {

namespace {

/// tdcr::simulate (models/dynamics/simulate.cpp), step for step the same, that also keeps the disk
/// positions of each output step (the integrator's shape()): what `tdcr plot --animate` draws.
/// Kept here, not in SimulationStep, so the CLI's CSV run and the C++ API pay nothing for it.
tdcr::SimulationResult simulate_with_shapes(const tdcr::StaticModel& model, const tdcr::DynamicsSettings& settings,
                                            const tdcr::Timeline& timeline, const tdcr::SimulationOptions& options,
                                            const tdcr::SolverOptions& solver,
                                            std::vector<std::vector<tdcr::Vec3>>& disks) {
  options.validate();
  settings.validate();
  timeline.validate(model.robot());
  for (std::size_t i = 0; i < timeline.entries.size(); ++i)
    if (timeline.entries[i].input.actuation.kind != tdcr::Actuation::Kind::Tensions)
      throw tdcr::InputError("timeline[" + std::to_string(i) + "].actuation", "displacements",
                             "simulation takes tension input only so far (displacement input and tendon slack are "
                             "not supported yet)");
  auto positions = [](const tdcr::Solution& s) {
    std::vector<tdcr::Vec3> p;
    p.reserve(s.disk_frames.size());
    for (const tdcr::Frame& f : s.disk_frames) p.push_back(f.p);
    return p;
  };
  std::unique_ptr<tdcr::DynamicsIntegrator> integrator =
      tdcr::make_dynamics_integrator(model, settings, options.dt, solver);
  tdcr::SimulationResult result;
  const tdcr::ModelInput first = timeline.at(0.0);
  std::unique_ptr<tdcr::ModelWorkspace> ws = model.make_workspace();
  const tdcr::Solution rest = tdcr::solve(model, *ws, first, solver);
  tdcr::SimulationStep s0;
  s0.status = rest.summary.termination;
  s0.iterations = rest.summary.iterations;
  s0.residual = rest.summary.residual_norm;
  if (!rest.disk_frames.empty()) s0.tip = rest.disk_frames.back();
  result.steps.push_back(s0);
  disks.push_back(positions(rest));
  if (!rest.converged()) {
    std::ostringstream msg;
    msg << "the static answer at t = 0 did not converge (" << tdcr::to_string(rest.summary.termination)
        << ", residual " << rest.summary.residual_norm << ", " << rest.summary.iterations << " iterations)";
    result.message = msg.str();
    return result;
  }
  integrator->initialize(rest, first);
  const long steps = std::lround(std::ceil(options.duration / options.dt - 1e-9));
  for (long k = 1; k <= steps; ++k) {
    const double t = std::min(options.duration, static_cast<double>(k) * options.dt);
    tdcr::SimulationStep s = integrator->advance(t, timeline);
    result.steps.push_back(s);
    disks.push_back(positions(integrator->shape()));
    if (s.status != tdcr::TerminationType::Converged) {
      std::ostringstream msg;
      msg << "step to t = " << t << " s failed at t = " << s.t << " s (" << tdcr::to_string(s.status)
          << ", residual " << s.residual << ", " << s.iterations << " iterations)";
      result.message = msg.str();
      return result;
    }
  }
  result.completed = true;
  return result;
}

}  // namespace

void bind_dynamics(py::module_& m) {
  m.def(
      "simulate",
      [](const tdcr::Scene& scene, double duration, double dt, const std::optional<std::string>& model,
         bool shapes) {
        tdcr::Scene sc = scene;
        if (model) sc.model = *model;
        tdcr::validate_scene(sc);
        if (!sc.dynamics) throw tdcr::InputError("dynamics", "", "missing: a scene to simulate gives a \"dynamics\" object");
        tdcr::Timeline timeline = sc.timeline;
        if (timeline.entries.empty()) timeline.entries.push_back(tdcr::TimelineEntry{0.0, sc.input()});
        tdcr::SimulationOptions options;
        options.duration = duration;
        options.dt = dt;
        const auto m = tdcr::make_model(tdcr::parse_model_kind(sc.model), sc);
        tdcr::SimulationResult r;
        std::vector<std::vector<tdcr::Vec3>> disks;  // shapes=True: the disk positions of each step
        {
          py::gil_scoped_release release;
          if (shapes)
            r = simulate_with_shapes(*m, *sc.dynamics, timeline, options, sc.solver, disks);
          else
            r = tdcr::simulate(*m, *sc.dynamics, timeline, options, sc.solver);
        }
        const auto n = static_cast<py::ssize_t>(r.steps.size());
        py::array_t<double> t(n), tip({n, py::ssize_t{3}}), rot({n, py::ssize_t{3}}), ke(n), pe(n);
        py::array_t<int> iterations(n);
        py::list status;
        auto T = t.mutable_unchecked<1>();
        auto P = tip.mutable_unchecked<2>();
        auto W = rot.mutable_unchecked<2>();
        auto K = ke.mutable_unchecked<1>();
        auto U = pe.mutable_unchecked<1>();
        auto I = iterations.mutable_unchecked<1>();
        for (py::ssize_t k = 0; k < n; ++k) {
          const tdcr::SimulationStep& s = r.steps[static_cast<std::size_t>(k)];
          const tdcr::Vec3 w = tdcr::lie::log_so3(s.tip.R);
          T(k) = s.t;
          for (int i = 0; i < 3; ++i) P(k, i) = s.tip.p[i], W(k, i) = w[i];
          K(k) = s.kinetic_energy;
          U(k) = s.potential_energy;
          I(k) = s.iterations;
          status.append(tdcr::to_string(s.status));
        }
        py::dict out("t"_a = t, "tip"_a = tip, "rot"_a = rot, "status"_a = status, "iterations"_a = iterations,
                        "kinetic_energy"_a = ke, "potential_energy"_a = pe, "completed"_a = r.completed,
                     "message"_a = r.message);
        if (shapes) {
          const auto nd = static_cast<py::ssize_t>(disks.empty() ? 0 : disks.front().size());
          py::array_t<double> D({n, nd, py::ssize_t{3}});
          auto A = D.mutable_unchecked<3>();
          for (py::ssize_t k = 0; k < n; ++k)
            for (py::ssize_t j = 0; j < nd; ++j) {
              const auto& row = disks[static_cast<std::size_t>(k)];
              const bool have = static_cast<std::size_t>(j) < row.size();
              for (int i = 0; i < 3; ++i)
                A(k, j, i) = have ? row[static_cast<std::size_t>(j)][i] : std::nan("");
            }
          out["disks"] = D;
        }
        return out;
      },
      "scene"_a, "duration"_a, "dt"_a = 1.0 / 60.0, "model"_a = py::none(), "shapes"_a = false,
      "The scene's robot in motion under its timeline (docs/dynamics.md): a dict of numpy arrays, one "
      "row per output step (t, tip, rot as rotation vectors, iterations, kinetic_energy, "
      "potential_energy), the steps' status, completed and message; with shapes=True also disks, the "
      "disk positions of each step (steps, disks, 3) in m, disk 0 the base (for pictures: tdcr.plot).");
}

}  // namespace tdcr_python
