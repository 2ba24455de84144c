// The extension module tdcr._tdcr: the exception type and the module entry point.
#include <stdexcept>
#include <string>

#include <pybind11/pybind11.h>

#include "bindings.hpp"
#include "tdcr/core/error.hpp"

namespace py = pybind11;

namespace tdcr_python {

py::object json_loads(const std::string& text) { return py::module_::import("json").attr("loads")(text); }

}  // namespace tdcr_python

namespace {

/// numpy is required: the bindings' default arguments and results are numpy arrays (Eigen), so
/// the module cannot initialise without it. pybind11 would say only "initialization failed";
/// this says what is missing, for which interpreter, and which one the module was built for.
void require_numpy() {
  try {
    py::module_::import("numpy");
  } catch (py::error_already_set& e) {
    const py::module_ sys = py::module_::import("sys");
    const std::string version = py::str(sys.attr("version")).cast<std::string>();
    throw std::runtime_error(
        "tdcr needs numpy, and this Python (" + py::str(sys.attr("executable")).cast<std::string>() + ", Python " +
        version.substr(0, version.find(' ')) + ") cannot import it: " + e.what() +
        ". This tdcr module was built for " TDCR_PYTHON_EXECUTABLE " (Python " TDCR_PYTHON_VERSION
        "): run it with that interpreter, or install numpy for this one (python3 -m pip install numpy; "
        "Debian: apt-get install python3-numpy)");
  }
}

}  // namespace

PYBIND11_MODULE(_tdcr, m) {
  require_numpy();
  m.doc() = "tdcr: kineto-static models of tendon-driven continuum robots (C++ core)";

  // tdcr::InputError as a ValueError subclass carrying the offending field and value.
  static py::exception<tdcr::InputError> input_error(m, "InputError", PyExc_ValueError);
  input_error.doc() =
      "Invalid input: a scene, robot, option or file that cannot be used. `field` is the JSON-style "
      "path of the offending entry (e.g. 'robot.segments[1].length'), `value` its value as text.";
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const tdcr::InputError& e) {
      py::object err = py::handle(input_error.ptr())(e.what());
      err.attr("field") = e.field();
      err.attr("value") = e.value();
      PyErr_SetObject(input_error.ptr(), err.ptr());
    }
  });

  tdcr_python::bind_scene(m);
  tdcr_python::bind_solve(m);
  tdcr_python::bind_calibration(m);
  tdcr_python::bind_dynamics(m);
}
