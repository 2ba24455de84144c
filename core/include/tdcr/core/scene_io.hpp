/// @file scene_io.hpp
/// @brief Scene files (JSON) in and solutions (JSON) out. Every key and value is validated; an
/// error names the JSON path and the value (InputError).
///
/// Keys (docs/scene-file.md lists every key with unit, default, constraints and the models that
/// honour it, the error messages and the CLI's JSON output):
/// @code{.json}
/// {"robot": {"backbone": {"youngs_modulus": 2.11e11, "poisson_ratio": 0.3, "outer_radius": 0.0004},
///            "segments": [{"length": 0.05, "disks": 10,
///                          "tendons": [{"x": 0.0, "y": 0.008}, {"x": 0.0, "y": -0.008}]}]},
///  "actuation": {"tensions": [1.0, 0.0]},
///  "loads": {"tip_force": [0, 0, 0], "tip_moment": [0, 0, 0], "gravity": [0, 0, -9.81]},
///  "effects": {"shear_extension": true, "disk_normal_force": "removed"},
///  "model": "vc", "solver": {"integrator": "rk4"}}
/// @endcode
///
/// Every key (SI units; defaults are those of the C++ structs, see Backbone, Segment, Actuation,
/// Loads, Effects, SolverOptions):
/// - `robot` (required)
///   - `backbone`: `youngs_modulus` (Pa), `poisson_ratio` or `shear_modulus` (Pa, not both),
///     `outer_radius`, `inner_radius` (m), `density` (kg/m^3) or `mass_per_length` (kg/m, not
///     both); or `stiffness`: {`EI`, `GJ`, `EA`, `GA`} (all four required) instead of the
///     material and radii (then only `mass_per_length` gives a mass).
///   - `segments` (required, non-empty): [{`length` (m, required), `disks` (integer, required),
///     `tendons` (required, may be empty): [{`x`, `y`} (m, both required)], `disk_mass` (kg)}].
/// - `actuation` (required): exactly one of `tensions` (N, >= 0) and `displacements` (m, positive
///   when pulled), one value per tendon in global order; with displacements optionally
///   `displacement_convention`: `"at_base"` (default) or `"per_segment"`.
/// - `loads`: `tip_force` (N), `tip_moment` (N m), `gravity` (m/s^2): 3-vectors, base frame.
/// - `effects`: `shear_extension` (bool), `disk_normal_force` (`"removed"` | `"kept"`),
///   `tendon_path` (`"fully_constrained"` | `"partially_constrained"`), `prb`: {`gamma`: [4],
///   `k_theta`: [3]}.
/// - `model`: `"cc"` | `"ccsub"` | `"prb"` | `"vc"` | `"vcref"` | `"auto"`.
/// - `solver`: `integrator` (`"rk4"` | `"cvode"`), `rk4_steps` (integer), `cvode_rtol`,
///   `cvode_atol`, `function_tolerance`, `step_tolerance`, `max_iterations` (integer),
///   `linear_solver` (`"auto"` | `"dense"` | `"klu"`), `continuation` (bool),
///   `max_continuation_steps` (integer).
/// - `description`: free text for the reader of the file; ignored.
///
/// Rules: an unknown key at any level is an error (with the closest known key suggested), as is
/// a duplicate key; numbers must be JSON numbers (not strings, not booleans) and finite
/// (1e999 is rejected); integers must be written without a fraction; malformed JSON is
/// reported with its byte position and the source name as the field.
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

/// @brief The CLI's JSON contract, keys in this order:
/// - `model` (string), `status` (`"converged"` or `"failed"`), `reason` (the termination name,
///   then ": " and the summary message if any), `iterations`, `residual_norm`;
/// - `tip`: {`position`: [3] (m, base frame), `rotation`: [[3], [3], [3]] (rows of R: rotation[i][j]
///   = R(i, j), columns are the tip frame's axes)}; both null when the solution has no frames;
/// - `disks`: [{`position`, `rotation`}, ...] from the base disk to the tip (if include_disks);
/// - `tendon_displacements`: [m per tendon], `tensions`: [N per tendon];
/// - `backbone`: [{`s`, `position`, `rotation`, `n`, `m`}, ...] (only if include_backbone);
/// - `timing`: {`repeat`, `median_us`, `min_us`};
/// - `summary`: every SolverSummary field (`termination`, `message`, `solver_flag`, `iterations`,
///   `residual_evaluations`, `jacobian_evaluations`, `residual_norm`, `physical_residual`,
///   `unknowns`, `continuation_steps`, `linear_solver`, `integrator`, `solve_time_s`);
/// - `model_selection` (string): only if Solution::model_selection is not empty (model "auto").
/// Non-finite numbers are written as null: the text is always valid JSON.
std::string solution_to_json(const Solution& solution, const SolutionJsonOptions& options = {});

}  // namespace tdcr
