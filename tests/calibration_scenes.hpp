// The calibration tests' shared scene and solver (tests/test_calibration.cpp,
// tests/test_calibration_fit.cpp): the paper robot with tension input, and the forward solves
// the calibration makes.
#pragma once

#include "tdcr/core/paper_robot.hpp"
#include "tdcr/core/scene.hpp"
#include "tdcr/core/solver_options.hpp"

namespace tdcr_test {

// The paper robot (n disks per segment) with tension input, scene-file defaults otherwise.
inline tdcr::Scene paper_scene(int n) {
  tdcr::Scene s = tdcr::paper::scene(n, 1, "vc");
  s.effects = tdcr::paper::effects("vc");  // every model with shear and extension
  return s;
}

// The forward solves the calibration makes (calibration.hpp): tight Newton, RK4 on a fixed mesh.
inline tdcr::SolverOptions data_solver(const tdcr::Scene& s) {
  tdcr::SolverOptions o = s.solver;
  o.function_tolerance = 1e-12;
  o.integrator = tdcr::IntegratorKind::FixedStepRK4;
  o.stability = tdcr::StabilityCheck::Never;
  return o;
}

}  // namespace tdcr_test
