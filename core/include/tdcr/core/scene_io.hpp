/// @file scene_io.hpp
/// @brief Scene files (JSON) in and solutions (JSON) out. Every key and value is validated; an
/// error names the JSON path and the value (InputError).
///
/// Keys (docs/scene-file.md lists every key with unit and default):
/// @code{.json}
/// {"robot": {"backbone": {"youngs_modulus": 2.11e11, "poisson_ratio": 0.3, "outer_radius": 0.0004},
///            "segments": [{"length": 0.05, "disks": 10,
///                          "tendons": [{"x": 0.0, "y": 0.008}, {"x": 0.0, "y": -0.008}]}]},
///  "actuation": {"tensions": [1.0, 0.0]},
///  "loads": {"tip_force": [0, 0, 0], "tip_moment": [0, 0, 0], "gravity": [0, 0, -9.81]},
///  "effects": {"shear_extension": true, "disk_normal_force": "removed"},
///  "model": "vc", "solver": {"integrator": "rk4"}}
/// @endcode
#pragma once

#include <string>

#include "tdcr/core/scene.hpp"
#include "tdcr/core/solution.hpp"

namespace tdcr {

/// @brief Parse a scene from JSON text. `source` names the origin in messages (file name).
/// Throws InputError (field = JSON path such as `robot.segments[0].disks`) on any bad input.
Scene parse_scene(const std::string& json_text, const std::string& source = "<string>");

/// @brief Read and parse a scene file. A missing or unreadable file is an InputError whose
/// field is the path.
Scene load_scene(const std::string& path);

/// @brief Serialise a scene back to JSON (round-trips through parse_scene).
std::string scene_to_json(const Scene& scene);

/// @brief Options for solution_to_json.
struct SolutionJsonOptions {
  bool include_disks = true;     ///< Include every disk frame.
  bool include_backbone = false; ///< Include dense backbone samples.
  int repeat = 1;                ///< Number of timed solves (for the "timing" object).
  double median_us = 0.0;        ///< Median solve time (us).
  double min_us = 0.0;           ///< Minimum solve time (us).
};

/// @brief The CLI's JSON contract: {"model", "status", "reason", "iterations", "residual_norm",
/// "tip": {"position", "rotation"}, "disks": [...], "tendon_displacements", "timing"}.
std::string solution_to_json(const Solution& solution, const SolutionJsonOptions& options = {});

}  // namespace tdcr
