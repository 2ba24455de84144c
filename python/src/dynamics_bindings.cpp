// Bindings of robots that move: tdcr.simulate (tdcr/models/dynamics.hpp), the trajectory as
// numpy arrays.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <optional>
#include <string>

#include "bindings.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/core/lie.hpp"
#include "tdcr/models/dynamics.hpp"
#include "tdcr/models/static_model.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace tdcr_python {

void bind_dynamics(py::module_& m) {
  m.def(
      "simulate",
      [](const tdcr::Scene& scene, double duration, double dt, const std::optional<std::string>& model) {
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
        {
          py::gil_scoped_release release;
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
        return py::dict("t"_a = t, "tip"_a = tip, "rot"_a = rot, "status"_a = status, "iterations"_a = iterations,
                        "kinetic_energy"_a = ke, "potential_energy"_a = pe, "completed"_a = r.completed,
                        "message"_a = r.message);
      },
      "scene"_a, "duration"_a, "dt"_a = 1.0 / 60.0, "model"_a = py::none(),
      "The scene's robot in motion under its timeline (docs/dynamics.md): a dict of numpy arrays, one "
      "row per output step (t, tip, rot as rotation vectors, iterations, kinetic_energy, "
      "potential_energy), the steps' status, completed and message.");
}

}  // namespace tdcr_python
