// Bindings of the inverse solve: tensions that put the tip at a target. The solve releases the GIL.
#include <array>
#include <optional>
#include <string>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/models/inverse_solve.hpp"

namespace py = pybind11;
using namespace py::literals;

namespace tdcr_python {
namespace {

// Positions come in as 3 numbers (a list or a numpy array); GCC warns (-Wmaybe-uninitialized, a
// false positive) in pybind11's Eigen caster when it is inlined here.
using Point = std::array<double, 3>;
tdcr::Vec3 vec(const Point& p) { return tdcr::Vec3(p[0], p[1], p[2]); }

/// A target orientation given as a rotation vector (3,) or a rotation matrix (3, 3), as the
/// rotation vector InverseTarget holds. A matrix must be a rotation (InverseTarget::
/// rotation_from_matrix: orthonormal to 1e-9, det +1), else InputError naming target.rotation.
std::optional<tdcr::Vec3> rotation_vector(const py::object& rotation) {
  if (rotation.is_none()) return std::nullopt;
  const auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(rotation);
  if (a && a.ndim() == 1 && a.shape(0) == 3) return tdcr::Vec3(a.at(0), a.at(1), a.at(2));
  if (a && a.ndim() == 2 && a.shape(0) == 3 && a.shape(1) == 3) {
    tdcr::Mat3 R;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) R(i, j) = a.at(i, j);
    return tdcr::InverseTarget::rotation_from_matrix(R);
  }
  throw tdcr::InputError("target.rotation", py::str(rotation),
                         "must be a rotation vector (3,) or a rotation matrix (3, 3)");
}

tdcr::InverseResult solve_inverse(const tdcr::StaticModel& model, tdcr::ModelWorkspace& ws,
                                  const tdcr::ModelInput& start, const tdcr::InverseTarget& target,
                                  const std::optional<tdcr::SolverOptions>& options,
                                  const std::optional<tdcr::InverseOptions>& inverse_options) {
  py::gil_scoped_release release;
  return tdcr::inverse_solve(model, ws, start, target, options.value_or(tdcr::SolverOptions()),
                             inverse_options.value_or(tdcr::InverseOptions()));
}

}  // namespace

void bind_inverse(py::module_& m) {
  py::class_<tdcr::InverseTarget>(m, "InverseTarget", "Where the tip should be (base frame)")
      .def(py::init([](const Point& position, const py::object& rotation, double rotation_weight) {
             return tdcr::InverseTarget{vec(position), rotation_vector(rotation), rotation_weight};
           }),
           "position"_a = Point{0.0, 0.0, 0.0}, "rotation"_a = py::none(), "rotation_weight"_a = 0.0)
      .def_property(
          "position", [](const tdcr::InverseTarget& t) { return t.position; },
          [](tdcr::InverseTarget& t, const Point& p) { t.position = vec(p); }, "tip position (m)")
      .def_property(
          "rotation", [](const tdcr::InverseTarget& t) { return t.rotation; },
          [](tdcr::InverseTarget& t, const py::object& r) { t.rotation = rotation_vector(r); },
          "tip orientation as a rotation vector (rad), or None (orientation free); a (3, 3) rotation matrix is "
          "accepted (orthonormal to 1e-9, det +1, else InputError naming target.rotation)")
      .def_readwrite("rotation_weight", &tdcr::InverseTarget::rotation_weight,
                     "m per rad in the least-squares steps; 0: the robot's length")
      .def("validate", &tdcr::InverseTarget::validate);

  py::class_<tdcr::InverseOptions>(m, "InverseOptions", "Settings of the inverse iteration")
      .def(py::init<>())
      .def_readwrite("max_iterations", &tdcr::InverseOptions::max_iterations)
      .def_readwrite("position_tolerance", &tdcr::InverseOptions::position_tolerance, "m")
      .def_readwrite("rotation_tolerance", &tdcr::InverseOptions::rotation_tolerance, "rad")
      .def_readwrite("tension_tolerance", &tdcr::InverseOptions::tension_tolerance, "N")
      .def("validate", &tdcr::InverseOptions::validate);

  using R = tdcr::InverseResult;
  py::class_<R>(m, "InverseResult", "The answer of an inverse solve; a failure carries the closest pose found")
      .def_property_readonly("status", [](const R& r) { return tdcr::to_string(r.status); },
                             "'converged', 'unreachable', 'max_iterations' or 'forward_failed'")
      .def_readonly("message", &R::message)
      .def_readonly("solution", &R::solution, "the forward solve at `tensions`")
      .def_property_readonly(
          "tensions", [](const R& r) { return py::array_t<double>(static_cast<py::ssize_t>(r.tensions.size()), r.tensions.data()); },
          "(m,) tensions (N), all >= 0")
      .def_readonly("position_error", &R::position_error, "|tip - target| (m)")
      .def_readonly("rotation_error", &R::rotation_error, "rad; 0 without a rotation target")
      .def_readonly("iterations", &R::iterations)
      .def_readonly("accepted_steps", &R::accepted_steps)
      .def_readonly("forward_solves", &R::forward_solves, "all forward solves, the Jacobian's differences included")
      .def_readonly("minimum_norm", &R::minimum_norm,
                    "converged and verified to be a local minimum of |T| on the target (first and second order)")
      .def_readonly("optimality", &R::optimality, "N: the last Newton step of the minimum-norm problem")
      .def_readonly("tension_resolution", &R::tension_resolution,
                    "N: tensions this far apart in the least controllable direction both meet the target")
      .def_property_readonly("converged", &R::converged)
      .def("brief_report", &R::brief_report)
      .def("__repr__", [](const R& r) { return "<InverseResult " + r.brief_report() + ">"; });

  m.def("inverse_solve", &solve_inverse, "model"_a, "workspace"_a, "start_input"_a, "target"_a,
        "options"_a = py::none(), "inverse_options"_a = py::none(),
        "tdcr::inverse_solve: non-negative tensions putting the tip at `target`, starting from the tensions of "
        "`start_input` (its loads are kept); releases the GIL");
  m.def(
      "inverse_solve",
      [](const tdcr::StaticModel& model, tdcr::ModelWorkspace& ws, const tdcr::ModelInput& start,
         const Point& position, const py::object& rotation, const std::optional<tdcr::SolverOptions>& options,
         const std::optional<tdcr::InverseOptions>& inverse_options, double rotation_weight) {
        const tdcr::InverseTarget target{vec(position), rotation_vector(rotation), rotation_weight};
        return solve_inverse(model, ws, start, target, options, inverse_options);
      },
      "model"_a, "workspace"_a, "start_input"_a, "position"_a, "rotation"_a = py::none(), "options"_a = py::none(),
      "inverse_options"_a = py::none(), "rotation_weight"_a = 0.0,
      "the same with the target given as a position (3,) and optionally a rotation vector or matrix");
}

}  // namespace tdcr_python
