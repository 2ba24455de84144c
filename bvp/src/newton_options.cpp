/// @file newton_options.cpp
/// @brief NewtonOptions::validate(): the bounds of the Newton settings.
#include <cmath>
#include <string>

#include "tdcr/bvp/newton_solver.hpp"
#include "tdcr/core/error.hpp"

namespace tdcr::bvp {

void NewtonOptions::validate() const {
  auto positive = [](double v, const char* field) {
    if (!(v > 0.0) || !std::isfinite(v))
      throw InputError(std::string("newton.") + field, format_value(v), "must be positive and finite");
  };
  positive(function_tolerance, "function_tolerance");
  positive(step_tolerance, "step_tolerance");
  if (max_iterations < 1)
    throw InputError("newton.max_iterations", std::to_string(max_iterations), "must be >= 1");
  if (!(max_newton_step >= 0.0) || !std::isfinite(max_newton_step))
    throw InputError("newton.max_newton_step", format_value(max_newton_step),
                     "must be >= 0 (0 = automatic)");
  if (max_setup_calls < 1)
    throw InputError("newton.max_setup_calls", std::to_string(max_setup_calls), "must be >= 1");
  if (!(freeze_jacobian_below >= 0.0) || !std::isfinite(freeze_jacobian_below) ||
      (freeze_jacobian_below > 0.0 && freeze_jacobian_below <= function_tolerance))
    throw InputError("newton.freeze_jacobian_below", format_value(freeze_jacobian_below),
                     "must be 0 (off) or above function_tolerance");
  if (dense_size_limit < 0)
    throw InputError("newton.dense_size_limit", std::to_string(dense_size_limit),
                     "must be >= 0");
}

}  // namespace tdcr::bvp
