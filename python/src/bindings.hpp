// Shared declarations of the pybind11 bindings of tdcr (module _tdcr, wrapped by tdcr/__init__.py).
#pragma once

#include <vector>

#include <pybind11/pybind11.h>

#include "tdcr/core/robot.hpp"

// Segments and tendons are bound as mutable lists (robot.segments[0].length = ... changes the robot).
PYBIND11_MAKE_OPAQUE(std::vector<tdcr::Segment>)
PYBIND11_MAKE_OPAQUE(std::vector<tdcr::TendonSpec>)

namespace tdcr_python {

/// Robot, Backbone, Segment, TendonSpec, Actuation, Loads, Effects, SolverOptions, ModelInput, Scene
/// and the scene I/O functions.
void bind_scene(pybind11::module_& m);
/// StaticModel, ModelWorkspace, Solution and its parts, the solve functions, model selection.
void bind_solve(pybind11::module_& m);
/// InverseTarget, InverseOptions, InverseResult and inverse_solve (after bind_solve: uses Solution).
void bind_inverse(pybind11::module_& m);
/// Calibration data, options and result, read_calibration_data, _calibrate (after bind_solve).
void bind_calibration(pybind11::module_& m);
/// tdcr.simulate (dynamics_bindings.cpp).
void bind_dynamics(pybind11::module_& m);
/// json.loads(text): a Python object from JSON text.
pybind11::object json_loads(const std::string& text);

}  // namespace tdcr_python
