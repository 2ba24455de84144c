// Bindings of the solve side: models, workspaces, solutions (numpy arrays), the solve functions and
// model selection. Solves release the GIL.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "tdcr/core/scene_io.hpp"
#include "tdcr/models/model_registry.hpp"
#include "tdcr/models/model_selection.hpp"
#include "tdcr/models/static_model.hpp"

namespace py = pybind11;
using namespace py::literals;

namespace tdcr_python {
namespace {

using Array = py::array_t<double>;

Array vector_array(const std::vector<double>& v) { return Array(static_cast<py::ssize_t>(v.size()), v.data()); }

/// (N, 4, 4) homogeneous transforms of `frames`.
template <typename Get>
Array frames_array(std::size_t n, Get frame_of) {
  Array out({static_cast<py::ssize_t>(n), py::ssize_t{4}, py::ssize_t{4}});
  auto a = out.mutable_unchecked<3>();
  for (std::size_t k = 0; k < n; ++k) {
    const tdcr::Mat4 T = frame_of(k).matrix();
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) a(k, i, j) = T(i, j);
  }
  return out;
}

/// (M, 3) rows of the 3-vectors `vec_of(k)`.
template <typename Get>
Array rows_array(std::size_t n, Get vec_of) {
  Array out({static_cast<py::ssize_t>(n), py::ssize_t{3}});
  auto a = out.mutable_unchecked<2>();
  for (std::size_t k = 0; k < n; ++k) {
    const tdcr::Vec3 v = vec_of(k);
    for (int i = 0; i < 3; ++i) a(k, i) = v[i];
  }
  return out;
}

/// The CLI's JSON of a solution (tdcr::solution_to_json).
std::string solution_json(const tdcr::Solution& s, bool include_disks, bool include_backbone) {
  tdcr::SolutionJsonOptions o;
  o.include_disks = include_disks;
  o.include_backbone = include_backbone;
  return tdcr::solution_to_json(s, o);
}

tdcr::ModelKind kind_of(const std::string& name) { return tdcr::parse_model_kind(name); }

/// The Python-facing solve: InputError checks happen inside tdcr::solve, with the GIL released.
tdcr::Solution solve_with(const tdcr::StaticModel& model, tdcr::ModelWorkspace& ws, const tdcr::ModelInput& input,
                          const std::optional<tdcr::SolverOptions>& options, const tdcr::Solution* warm) {
  py::gil_scoped_release release;
  return tdcr::solve(model, ws, input, options.value_or(tdcr::SolverOptions()), warm);
}

void bind_solution_parts(py::module_& m) {
  py::class_<tdcr::SolverSummary>(m, "SolverSummary", "Diagnostics of a solve (Ceres-like)")
      .def_property_readonly("termination", [](const tdcr::SolverSummary& s) { return tdcr::to_string(s.termination); })
      .def_readonly("message", &tdcr::SolverSummary::message)
      .def_readonly("solver_flag", &tdcr::SolverSummary::solver_flag)
      .def_readonly("iterations", &tdcr::SolverSummary::iterations)
      .def_readonly("residual_evaluations", &tdcr::SolverSummary::residual_evaluations)
      .def_readonly("jacobian_evaluations", &tdcr::SolverSummary::jacobian_evaluations)
      .def_readonly("residual_norm", &tdcr::SolverSummary::residual_norm)
      .def_readonly("physical_residual", &tdcr::SolverSummary::physical_residual)
      .def_readonly("unknowns", &tdcr::SolverSummary::unknowns)
      .def_readonly("continuation_steps", &tdcr::SolverSummary::continuation_steps)
      .def_readonly("linear_solver", &tdcr::SolverSummary::linear_solver)
      .def_readonly("integrator", &tdcr::SolverSummary::integrator)
      .def_readonly("tip_error_estimate", &tdcr::SolverSummary::tip_error_estimate)
      .def_readonly("rk4_refinements", &tdcr::SolverSummary::rk4_refinements)
      .def_readonly("rk4_halvings", &tdcr::SolverSummary::rk4_halvings)
      .def_readonly("tip_error_estimate_age", &tdcr::SolverSummary::tip_error_estimate_age)
      .def_readonly("function_tolerance", &tdcr::SolverSummary::function_tolerance)
      .def_readonly("tip_tolerance", &tdcr::SolverSummary::tip_tolerance)
      .def_readonly("solve_time_s", &tdcr::SolverSummary::solve_time_s)
      .def_property_readonly("converged", &tdcr::SolverSummary::converged)
      .def("brief_report", &tdcr::SolverSummary::brief_report)
      .def("__repr__", [](const tdcr::SolverSummary& s) { return "<SolverSummary " + s.brief_report() + ">"; });

  py::class_<tdcr::Stability>(m, "Stability", "Stability of a converged answer")
      .def_property_readonly("status", [](const tdcr::Stability& s) { return tdcr::to_string(s.status); })
      .def_readonly("margin", &tdcr::Stability::margin)
      .def_readonly("method", &tdcr::Stability::method);

  py::class_<tdcr::PathEvent>(m, "PathEvent", "A fold, bifurcation or snap on the loading path")
      .def_property_readonly("type", [](const tdcr::PathEvent& e) { return tdcr::to_string(e.type); })
      .def_readonly("load_fraction", &tdcr::PathEvent::load_fraction)
      .def_readonly("tip_jump", &tdcr::PathEvent::tip_jump)
      .def_readonly("note", &tdcr::PathEvent::note);

  py::class_<tdcr::GeometryWarning>(m, "GeometryWarning", "A shape a real robot cannot take")
      .def_readonly("what", &tdcr::GeometryWarning::what)
      .def_readonly("tendon", &tdcr::GeometryWarning::tendon)
      .def_readonly("disk", &tdcr::GeometryWarning::disk)
      .def_readonly("value", &tdcr::GeometryWarning::value);

  py::class_<tdcr::Contact>(m, "Contact", "A contact with an obstacle: where it pushes (m, base frame) and how hard (N)")
      .def_readonly("s", &tdcr::Contact::s, "arc length of the touching disk (m)")
      .def_readonly("point", &tdcr::Contact::point, "contact point on the robot (m)")
      .def_readonly("normal", &tdcr::Contact::normal, "unit direction of the force on the robot")
      .def_readonly("force", &tdcr::Contact::force, "force magnitude (N), >= 0")
      .def_readonly("gap", &tdcr::Contact::gap, "distance to the obstacle (m), <= 0 in contact")
      .def_property_readonly("body", [](const tdcr::Contact& c) { return c.disk ? "disk" : "backbone"; })
      .def_readonly("disk", &tdcr::Contact::disk_index, "the disk (1-based disk list)")
      .def_readonly("obstacle", &tdcr::Contact::obstacle, "index in the scene's environment.obstacles");
}

void bind_solution(py::module_& m) {
  using S = tdcr::Solution;
  py::class_<S>(m, "Solution", "The answer of a model: shape (m, base frame), tensions, summary")
      .def_readonly("model", &S::model)
      .def_readonly("model_fingerprint", &S::model_fingerprint)
      .def_readonly("model_selection", &S::model_selection)
      .def_readonly("summary", &S::summary)
      .def_readonly("stability", &S::stability)
      .def_readonly("path_events", &S::path_events)
      .def_readonly("geometry_warnings", &S::geometry_warnings)
      .def_readonly("contacts", &S::contacts, "contacts with obstacles that carry force")
      .def_property_readonly("loads", [](const S& s) { return tdcr::Loads(s.loads); }, "the input's loads (a copy)")
      .def_property_readonly("converged", &S::converged)
      .def_property_readonly("termination", [](const S& s) { return tdcr::to_string(s.summary.termination); })
      .def_property_readonly("message", [](const S& s) { return s.summary.message; })
      .def_property_readonly("iterations", [](const S& s) { return s.summary.iterations; })
      .def_property_readonly("residual_norm", [](const S& s) { return s.summary.residual_norm; })
      .def_property_readonly("solve_time_s", [](const S& s) { return s.summary.solve_time_s; })
      .def_property_readonly(
          "disk_frames",
          [](const S& s) { return frames_array(s.disk_frames.size(), [&](std::size_t k) { return s.disk_frames[k]; }); },
          "(N, 4, 4) homogeneous transforms of the disks, base disk first, tip last (m)")
      .def_property_readonly(
          "disk_positions",
          [](const S& s) { return rows_array(s.disk_frames.size(), [&](std::size_t k) { return s.disk_frames[k].p; }); },
          "(N, 3) disk centres (m)")
      .def_property_readonly(
          "tip",
          [](const S& s) -> py::object {
            if (s.disk_frames.empty()) return py::none();
            return py::cast(tdcr::Mat4(s.tip().matrix()));
          },
          "(4, 4) tip pose (m), None without frames")
      .def_property_readonly(
          "tip_position",
          [](const S& s) -> py::object { return s.disk_frames.empty() ? py::none() : py::cast(tdcr::Vec3(s.tip().p)); })
      .def_property_readonly(
          "tip_rotation",
          [](const S& s) -> py::object { return s.disk_frames.empty() ? py::none() : py::cast(tdcr::Mat3(s.tip().R)); })
      .def_property_readonly("tendon_displacements", [](const S& s) { return vector_array(s.tendon_displacements); },
                             "(m,) displacement of each tendon at the base (m), positive when pulled")
      .def_property_readonly("tensions", [](const S& s) { return vector_array(s.tensions); }, "(m,) tensions (N)")
      .def_property_readonly("tendon_end_tensions", [](const S& s) { return vector_array(s.tendon_end_tensions); },
                             "(m,) tension of each tendon at its end disk (N) with friction; empty without")
      .def_property_readonly("tendon_slack",
                             [](const S& s) {
                               py::array_t<bool> out(static_cast<py::ssize_t>(s.tendon_slack.size()));
                               for (std::size_t k = 0; k < s.tendon_slack.size(); ++k)
                                 out.mutable_at(k) = s.tendon_slack[k];
                               return out;
                             },
                             "(m,) bool: tendon went slack (displacement input); empty for tension input")
      .def_property_readonly("unknowns", [](const S& s) { return Eigen::VectorXd(s.unknowns); })
      .def_property_readonly("backbone_s",
                             [](const S& s) {
                               Array out(static_cast<py::ssize_t>(s.backbone.size()));
                               for (std::size_t k = 0; k < s.backbone.size(); ++k) out.mutable_at(k) = s.backbone[k].s;
                               return out;
                             },
                             "(M,) arc length of the backbone samples (m); empty for models without samples")
      .def_property_readonly(
          "backbone_positions",
          [](const S& s) { return rows_array(s.backbone.size(), [&](std::size_t k) { return s.backbone[k].frame.p; }); },
          "(M, 3) backbone sample positions (m)")
      .def_property_readonly("backbone_frames",
                             [](const S& s) {
                               return frames_array(s.backbone.size(),
                                                   [&](std::size_t k) { return s.backbone[k].frame; });
                             },
                             "(M, 4, 4) backbone sample frames")
      .def_property_readonly(
          "backbone_n", [](const S& s) { return rows_array(s.backbone.size(), [&](std::size_t k) { return s.backbone[k].n; }); },
          "(M, 3) internal force (N), base frame")
      .def_property_readonly(
          "backbone_m", [](const S& s) { return rows_array(s.backbone.size(), [&](std::size_t k) { return s.backbone[k].m; }); },
          "(M, 3) internal moment (N m), base frame")
      .def_property_readonly("tip_jacobian", [](const S& s) { return Eigen::MatrixXd(s.tip_jacobian); },
                             "(6, m) d(tip pose)/d(actuation) or an empty (0, 0) array")
      .def_property_readonly("tip_compliance", [](const S& s) { return Eigen::MatrixXd(s.tip_compliance); },
                             "(6, 6) d(tip pose)/d(tip wrench) or an empty (0, 0) array")
      .def(
          "to_json",
          &solution_json,
          "include_disks"_a = true, "include_backbone"_a = false, "the CLI's JSON (tdcr solve --json)")
      .def(
          "to_dict",
          [](const S& s, bool disks, bool backbone) { return json_loads(solution_json(s, disks, backbone)); },
          "include_disks"_a = true, "include_backbone"_a = false)
      .def("__repr__", [](const S& s) { return "<Solution " + s.model + ": " + s.summary.brief_report() + ">"; });
}

void bind_models(py::module_& m) {
  py::class_<tdcr::ModelWorkspace>(m, "ModelWorkspace", "Mutable memory of one model's solves")
      .def("belongs_to", &tdcr::ModelWorkspace::belongs_to, "model"_a);

  py::class_<tdcr::StaticModel>(m, "StaticModel", "An immutable model of a robot with its effects")
      .def_property_readonly("kind", &tdcr::StaticModel::name)
      .def_property_readonly("name", &tdcr::StaticModel::name)
      // Copies: the model is immutable.
      .def_property_readonly("robot", [](const tdcr::StaticModel& mo) { return tdcr::Robot(mo.robot()); })
      .def_property_readonly("effects", [](const tdcr::StaticModel& mo) { return tdcr::Effects(mo.effects()); })
      .def_property_readonly("fingerprint", &tdcr::StaticModel::fingerprint)
      .def_property_readonly("disk_s", [](const tdcr::StaticModel& mo) { return vector_array(mo.routing().disk_s); },
                             "arc length of every disk, base disk first (m)")
      .def("make_workspace", &tdcr::StaticModel::make_workspace, py::keep_alive<0, 1>())
      .def("check_input", &tdcr::StaticModel::check_input, "input"_a)
      .def("solve", &solve_with, "workspace"_a, "input"_a, "options"_a = py::none(), "warm_start"_a = py::none(),
           "tdcr::solve(model, workspace, input, options, warm_start)")
      .def("__repr__", [](const tdcr::StaticModel& mo) { return "<StaticModel " + mo.name() + ">"; });

  m.def("solve_with", &solve_with, "model"_a, "workspace"_a, "input"_a, "options"_a = py::none(),
        "warm_start"_a = py::none(), "tdcr::solve(model, workspace, input, options, warm_start); releases the GIL");
  m.def(
      "make_model",
      [](const std::string& kind, const tdcr::Robot& robot, const tdcr::Effects& effects) {
        return tdcr::make_model(kind_of(kind), robot, effects);
      },
      "kind"_a, "robot"_a, "effects"_a = tdcr::Effects());
  m.def(
      "make_model", [](const std::string& kind, const tdcr::Scene& scene) { return tdcr::make_model(kind_of(kind), scene); },
      "kind"_a, "scene"_a, "the model of the scene's robot and effects (the scene's input is not used)");
  m.def("validate_scene", &tdcr::validate_scene, "scene"_a);
  m.def(
      "solve_scene",
      [](const tdcr::Scene& scene, double accuracy, const tdcr::Solution* warm) {
        py::gil_scoped_release release;
        return tdcr::solve_scene(scene, accuracy, warm);
      },
      "scene"_a, "accuracy"_a = 0.01, "warm_start"_a = py::none());

  py::class_<tdcr::ModelChoice>(m, "ModelChoice", "The model `auto` chose and why")
      .def_property_readonly("kind", [](const tdcr::ModelChoice& c) { return tdcr::to_string(c.kind); })
      .def_readonly("expected_error", &tdcr::ModelChoice::expected_error)
      .def_readonly("reason", &tdcr::ModelChoice::reason)
      .def("__repr__", [](const tdcr::ModelChoice& c) { return "<ModelChoice " + tdcr::to_string(c.kind) + ": " + c.reason + ">"; });
  m.def("choose_model", &tdcr::choose_model, "scene"_a, "tolerance"_a = 0.01,
        "`--model auto`: the cheapest model expected to meet `tolerance` (fraction of the robot length)");
  m.def(
      "expected_model_error",
      [](const std::string& kind, int disks, bool loaded) { return tdcr::expected_model_error(kind_of(kind), disks, loaded); },
      "kind"_a, "disks"_a, "loaded"_a = false);
  m.def("model_names", []() {
    std::vector<std::string> names;
    for (const tdcr::ModelInfo& i : tdcr::model_registry()) names.emplace_back(i.name);
    return names;
  });
  m.def(
      "solution_to_json",
      &solution_json,
      "solution"_a, "include_disks"_a = true, "include_backbone"_a = false);
}

}  // namespace

void bind_solve(py::module_& m) {
  bind_solution_parts(m);
  bind_solution(m);
  bind_models(m);
  bind_inverse(m);
}

}  // namespace tdcr_python
