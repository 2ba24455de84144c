/// @file arclength_options.cpp
/// @brief ArclengthOptions::validate(): the bounds of the step control and event settings.
#include <cmath>
#include <string>

#include "tdcr/bvp/arclength.hpp"
#include "tdcr/core/error.hpp"

namespace tdcr::bvp {

void ArclengthOptions::validate() const {
  auto fail = [](const char* name, double v, const char* why) {
    throw InputError(std::string("arclength.") + name, format_value(v), why);
  };
  auto positive = [&](const char* name, double v) {
    if (!(v > 0.0 && std::isfinite(v))) fail(name, v, "must be positive and finite");
  };
  if (!std::isfinite(start)) fail("start", start, "must be finite");
  if (!std::isfinite(target) || target == start) fail("target", target, "must be finite and differ from start");
  positive("initial_step", initial_step);
  positive("min_step", min_step);
  positive("max_step", max_step);
  if (min_step > initial_step) fail("min_step", min_step, "must not exceed initial_step");
  if (initial_step > max_step) fail("initial_step", initial_step, "must not exceed max_step");
  if (!(growth >= 1.0 && std::isfinite(growth))) fail("growth", growth, "must be >= 1 and finite");
  if (!(shrink > 0.0 && shrink < 1.0)) fail("shrink", shrink, "must be in (0, 1)");
  if (easy_iterations < 0) fail("easy_iterations", easy_iterations, "must not be negative");
  if (!(max_turn > 0.0 && max_turn <= std::acos(-1.0))) fail("max_turn", max_turn, "must be in (0, pi]");
  if (max_steps < 1) fail("max_steps", max_steps, "must be at least 1");
  if (!(window >= 0.0 && std::isfinite(window))) fail("window", window, "must be >= 0 and finite");
  if (!(event_tolerance > 0.0 && event_tolerance < 1.0))
    fail("event_tolerance", event_tolerance, "must be in (0, 1)");
  if (max_refine_iterations < 1) fail("max_refine_iterations", max_refine_iterations, "must be at least 1");
  if (!(snap_overshoot > 0.0 && snap_overshoot < 1.0)) fail("snap_overshoot", snap_overshoot, "must be in (0, 1)");
  positive("snap_perturbation", snap_perturbation);
  if (snap_tries < 1) fail("snap_tries", snap_tries, "must be at least 1");
  if (snap_max_iterations < 1) fail("snap_max_iterations", snap_max_iterations, "must be at least 1");
  if (damped_landing_steps < 0) fail("damped_landing_steps", damped_landing_steps, "must not be negative");
  positive("damped_landing_rate", damped_landing_rate);
  positive("damped_landing_move", damped_landing_move);
  if (corrector_max_iterations < 1) fail("corrector_max_iterations", corrector_max_iterations, "must be at least 1");
  if (!(corrector_freeze_jacobian_below >= 0.0 && std::isfinite(corrector_freeze_jacobian_below)))
    fail("corrector_freeze_jacobian_below", corrector_freeze_jacobian_below, "must be >= 0 and finite");
}

}  // namespace tdcr::bvp
