/// @file scene_io.hpp
/// @brief Scene files (JSON) in and solutions (JSON) out. Every key and value is validated; an
/// error names the JSON path and the value (InputError).
///
/// A scene file (docs/scene-file.md: the keys, the error messages and the CLI's JSON output):
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
/// docs/scene-file.md lists every key (type, unit, default, constraints, the models that honour
/// it); its tables are generated from the parser's own field table (scene_key_reference), and a
/// test fails when the page and the table disagree.
///
/// Rules: an unknown key at any level is an error (with the closest known key suggested), as is
/// a duplicate key; numbers must be JSON numbers (not strings, not booleans) and finite
/// (1e999 is rejected); integers must be written without a fraction; malformed JSON is
/// reported with its byte position and the source name as the field.
#pragma once

#include <string>
#include <vector>

#include "tdcr/core/scene.hpp"
#include "tdcr/core/solution.hpp"

namespace tdcr {

/// @brief Parse a scene from JSON text. `source` names the origin in messages (file name).
/// Throws InputError (field = JSON path such as `robot.segments[0].disks`) on any bad input.
/// `model` is only checked to be a string here (core knows no model names): tdcr::validate_scene
/// (models layer) checks it against the model registry.
Scene parse_scene(const std::string& json_text, const std::string& source = "<string>");

/// @brief Read and parse a scene file. A missing or unreadable file is an InputError whose
/// field is the path.
Scene load_scene(const std::string& path);

/// @brief Serialise a scene back to JSON (round-trips through parse_scene).
std::string scene_to_json(const Scene& scene);

/// @brief A member that a caller of solution_to_json adds to the object it writes, such as the
/// CLI's `timing`: core writes what a Solution holds, the caller what it knows besides.
struct JsonMember {
  std::string key;   ///< Its key; not one of the contract's own keys (solution_to_json).
  std::string json;  ///< Its value as JSON text, e.g. `{"repeat": 3}` (printed like the rest).
};

/// @brief Options for solution_to_json.
struct SolutionJsonOptions {
  bool include_disks = true;     ///< Include every disk frame. Default true.
  bool include_backbone = false; ///< Include dense backbone samples. Default false.
  /// The caller's own members, written in this order after the solution's geometry and actuation
  /// (`tensions` ... `backbone`) and before its diagnostics (`stability` ...). `tdcr solve` adds
  /// `timing` here. Default: none.
  std::vector<JsonMember> extra;
};

/// @brief The CLI's JSON contract, keys in this order:
/// - `model` (string), `model_fingerprint` (Solution::model_fingerprint as 16 lower-case hex
///   digits: JSON numbers cannot hold 64 bits exactly), `status` (`"converged"` or `"failed"`), `reason` (the termination name,
///   then ": " and the summary message if any), `iterations`, `residual_norm`;
/// - `tip`: {`position`: [3] (m, base frame), `rotation`: [[3], [3], [3]] (rows of R: rotation[i][j]
///   = R(i, j), columns are the tip frame's axes)}; both null when the solution has no frames;
/// - `disks`: [{`position`, `rotation`}, ...] from the base disk to the tip (if include_disks);
/// - `tendon_displacements`: [m per tendon], `tensions`: [N per tendon];
/// - `backbone`: [{`s`, `position`, `rotation`, `n`, `m`}, ...] (only if include_backbone);
/// - the members of SolutionJsonOptions::extra, in their order (`tdcr solve` writes `timing`:
///   {`repeat`, `median_us`, `min_us`} here);
/// - `stability`, `path_events`, `geometry_warnings`, `tip_jacobian` and `tip_compliance` (when
///   computed);
/// - `summary`: every SolverSummary field (`termination`, `message`, `solver_flag`, `iterations`,
///   `residual_evaluations`, `jacobian_evaluations`, `residual_norm`, `physical_residual`,
///   `unknowns`, `continuation_steps`, `linear_solver`, `integrator`, `solve_time_s`);
/// - `model_selection` (string): only if Solution::model_selection is not empty (model "auto").
/// Non-finite numbers are written as null: the text is always valid JSON. Throws
/// std::invalid_argument if an extra member's key is one of the keys above or another extra
/// member's, or its text is not JSON.
std::string solution_to_json(const Solution& solution, const SolutionJsonOptions& options = {});

/// @brief One table of the scene-file key reference.
struct SceneKeyTable {
  /// JSON path of the object whose keys the table lists: "" for the top level, `robot`,
  /// `robot.segments[i]`, ... Nested objects without a table of their own are listed in their
  /// parent's (`robot.backbone.stiffness.EI` in `robot.backbone`'s).
  std::string object;
  std::string markdown;  ///< The table: key, type, unit, default, constraints, honoured by.
};

/// @brief The reference of every scene-file key, generated from the table that parse_scene and
/// scene_to_json use. docs/scene-file.md holds each table verbatim inside a pair of
/// `scene-keys` HTML comments naming its object (`top` for the top level); test_scene_io
/// compares them.
std::vector<SceneKeyTable> scene_key_reference();

}  // namespace tdcr
