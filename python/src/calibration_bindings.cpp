// Bindings of the calibration service (tdcr/models/calibration.hpp). The fit releases the GIL;
// tdcr.calibrate (tdcr/__init__.py) is the keyword-argument front door over these.
#include <string>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/models/calibration.hpp"

namespace py = pybind11;
using namespace py::literals;

namespace tdcr_python {

void bind_calibration(py::module_& m) {
  py::class_<tdcr::CalibrationSample>(m, "CalibrationSample", "One measurement: its input and what was measured")
      .def_readonly("input", &tdcr::CalibrationSample::input)
      .def_readonly("line", &tdcr::CalibrationSample::line, "line of the data file (1-based)")
      .def_property_readonly("tip", [](const tdcr::CalibrationSample& s) { return s.tip; }, "tip position (m) or None")
      .def_property_readonly("rotation", [](const tdcr::CalibrationSample& s) { return s.rotation; },
                             "tip rotation vector (rad) or None");

  py::class_<tdcr::CalibrationData>(m, "CalibrationData", "Measurements of one robot (calibration data file)")
      .def_readonly("source", &tdcr::CalibrationData::source)
      .def_readonly("samples", &tdcr::CalibrationData::samples)
      .def_readonly("has_std", &tdcr::CalibrationData::has_std)
      .def("__len__", [](const tdcr::CalibrationData& d) { return d.samples.size(); });

  m.def("read_calibration_data", &tdcr::read_calibration_data, "path"_a, "scene"_a,
        "Read a calibration data file (CSV in the sweep CSV's columns) for the robot of `scene`; InputError names "
        "the line and column of a bad row");
  m.def("parse_calibration_data", &tdcr::parse_calibration_data, "text"_a, "scene"_a, "source"_a = "<string>",
        "Parse calibration data from CSV text");

  using FP = tdcr::FittedParameter;
  py::class_<FP>(m, "FittedParameter", "A fitted parameter with its standard error")
      .def_readonly("name", &FP::name)
      .def_readonly("unit", &FP::unit)
      .def_readonly("initial", &FP::initial)
      .def_readonly("value", &FP::value)
      .def_readonly("std_error", &FP::std_error, "inf if not identifiable")
      .def_readonly("lower", &FP::lower)
      .def_readonly("upper", &FP::upper)
      .def_readonly("identifiable", &FP::identifiable)
      .def_readonly("at_bound", &FP::at_bound)
      .def("__repr__", [](const FP& p) {
        return "<FittedParameter " + p.name + " = " + tdcr::format_value(p.value) + " +- " + tdcr::format_value(p.std_error) +
               (p.unit.empty() ? "" : " " + p.unit) + ">";
      });

  using SR = tdcr::SampleResidual;
  py::class_<SR>(m, "SampleResidual", "The residual of one measurement")
      .def_readonly("line", &SR::line)
      .def_readonly("tip_error", &SR::tip_error, "m")
      .def_readonly("rotation_error", &SR::rotation_error, "rad")
      .def_readonly("point_error", &SR::point_error, "m, largest over the measured points")
      .def_readonly("standardised", &SR::standardised)
      .def_readonly("solved", &SR::solved);

  using RS = tdcr::ResidualStatistics;
  py::class_<RS>(m, "ResidualStatistics", "Errors over all measurements")
      .def_readonly("rms_position", &RS::rms_position, "m")
      .def_readonly("max_position", &RS::max_position, "m")
      .def_readonly("rms_rotation", &RS::rms_rotation, "rad")
      .def_readonly("max_rotation", &RS::max_rotation, "rad")
      .def_readonly("rms_standardised", &RS::rms_standardised);

  using CS = tdcr::CalibrationSummary;
  py::class_<CS>(m, "CalibrationSummary", "Diagnostics of a calibration")
      .def_readonly("converged", &CS::converged)
      .def_readonly("termination", &CS::termination)
      .def_readonly("message", &CS::message)
      .def_readonly("iterations", &CS::iterations)
      .def_readonly("forward_solves", &CS::forward_solves)
      .def_readonly("failed_solves", &CS::failed_solves)
      .def_readonly("linearised_answers", &CS::linearised_answers)
      .def_readonly("initial_cost", &CS::initial_cost)
      .def_readonly("final_cost", &CS::final_cost)
      .def_readonly("before", &CS::before)
      .def_readonly("after", &CS::after)
      .def_readonly("time_s", &CS::time_s)
      .def("brief_report", &CS::brief_report);

  using CR = tdcr::CalibrationResult;
  py::class_<CR>(m, "CalibrationResult", "The answer of a calibration")
      .def_readonly("scene", &CR::scene, "the calibrated scene")
      .def_property_readonly("base", [](const CR& r) { return r.base.matrix(); },
                             "(4, 4) fitted base frame (identity unless base_offset/base_rotation were fitted)")
      .def_readonly("parameters", &CR::parameters)
      .def_property_readonly("values", [](const CR& r) {
        py::dict d;
        for (const FP& p : r.parameters) d[py::str(p.name)] = p.value;
        return d;
      }, "{name: fitted value}")
      .def_readonly("covariance", &CR::covariance)
      .def_readonly("correlation", &CR::correlation)
      .def_readonly("singular_values", &CR::singular_values)
      .def_readonly("non_identifiable", &CR::non_identifiable)
      .def_readonly("warning", &CR::warning)
      .def_readonly("residuals_before", &CR::residuals_before)
      .def_readonly("residuals_after", &CR::residuals_after)
      .def_readonly("summary", &CR::summary)
      .def_property_readonly("converged", &CR::converged)
      .def("__repr__", [](const CR& r) { return "<CalibrationResult " + r.summary.brief_report() + ">"; });

  m.def(
      "_calibrate",
      [](const tdcr::Scene& scene, const tdcr::CalibrationData& data, const std::string& model, const std::string& fit,
         const std::string& loss, double loss_scale, double position_std, double rotation_std, int max_iterations,
         bool warm_start, bool differences) {
        tdcr::CalibrationOptions o;
        o.model = tdcr::parse_model_kind(model);
        o.parameters = tdcr::parse_calibration_parameters(fit);
        if (loss == "huber") o.loss = tdcr::CalibrationLoss::Huber;
        else if (loss == "cauchy") o.loss = tdcr::CalibrationLoss::Cauchy;
        else if (loss == "none") o.loss = tdcr::CalibrationLoss::None;
        else throw tdcr::InputError("loss", loss, "must be huber, cauchy or none");
        o.loss_scale = loss_scale;
        o.position_std = position_std;
        o.rotation_std = rotation_std;
        o.max_iterations = max_iterations;
        o.warm_start = warm_start;
        if (differences) o.jacobian = tdcr::CalibrationJacobian::Differences;
        o.validate();
        py::gil_scoped_release release;
        return tdcr::calibrate(scene, data, o);
      },
      "scene"_a, "data"_a, "model"_a, "fit"_a, "loss"_a, "loss_scale"_a, "position_std"_a, "rotation_std"_a,
      "max_iterations"_a, "warm_start"_a, "differences"_a = false);
}

}  // namespace tdcr_python
