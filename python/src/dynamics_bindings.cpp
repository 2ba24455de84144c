// Bindings of robots that move: tdcr.simulate (tdcr/models/dynamics.hpp), the trajectory as
// numpy arrays.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <memory>
#include <optional>
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

/// The disk positions of a shape: what `tdcr plot --animate` draws of each step.
std::vector<tdcr::Vec3> disk_positions(const tdcr::Solution& s) {
  std::vector<tdcr::Vec3> p;
  p.reserve(s.disk_frames.size());
  for (const tdcr::Frame& f : s.disk_frames) p.push_back(f.p);
  return p;
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
          tdcr::SimulationObserver keep_shapes;
          if (shapes)
            keep_shapes = [&disks](const tdcr::SimulationStep&, const tdcr::Solution& shape) {
              disks.push_back(disk_positions(shape));
            };
          r = tdcr::simulate(*m, *sc.dynamics, timeline, options, sc.solver, keep_shapes);
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
        // Per tendon: the tensions of every step (given, or solved for displacement input; a
        // slack tendon's exactly 0), and the tendon paths' pulls where the model reports them.
        const auto m_t = static_cast<py::ssize_t>(m->robot().tendon_count());
        py::array_t<double> tensions({n, m_t}), pulls({n, m_t});
        bool have_pulls = n > 0;
        {
          auto TT = tensions.mutable_unchecked<2>();
          auto D = pulls.mutable_unchecked<2>();
          for (py::ssize_t k = 0; k < n; ++k) {
            const tdcr::SimulationStep& s = r.steps[static_cast<std::size_t>(k)];
            have_pulls = have_pulls && static_cast<py::ssize_t>(s.tendon_displacements.size()) == m_t;
            for (py::ssize_t j = 0; j < m_t; ++j) {
              const auto u = static_cast<std::size_t>(j);
              TT(k, j) = u < s.tensions.size() ? s.tensions[u] : std::nan("");
              D(k, j) = u < s.tendon_displacements.size() ? s.tendon_displacements[u] : std::nan("");
            }
          }
        }
        py::dict out("t"_a = t, "tip"_a = tip, "rot"_a = rot, "status"_a = status, "iterations"_a = iterations,
                        "kinetic_energy"_a = ke, "potential_energy"_a = pe, "completed"_a = r.completed,
                     "message"_a = r.message, "tensions"_a = tensions);
        if (have_pulls) out["tendon_displacements"] = pulls;
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
      "potential_energy, tensions (steps, tendons) in N; tendon_displacements (steps, tendons) in m for "
      "VC and VCref), the steps' status, completed and message; with shapes=True also disks, the "
      "disk positions of each step (steps, disks, 3) in m, disk 0 the base (for pictures: tdcr.plot).");
}

}  // namespace tdcr_python
