/// @file sweep_file.hpp
/// @brief Sweep files (JSON): a base scene, the axes to vary and the models to run. Everything
/// is validated when the file is read, before any solve (docs/sweeps.md):
///
/// @code{.json}
/// {"scene": "../paper_robot_tip_force.json",
///  "models": ["vc", "vcref"],
///  "axes": [{"field": "actuation.tensions[0]", "from": 0, "to": 4, "count": 9},
///           {"field": "loads.tip_force[1]", "values": [0, 0.25, 0.5]}]}
/// @endcode
///
/// "sampling": "grid" (default; the Cartesian product of the axes, the last axis fastest) or
/// "random" with "samples" and "seed" (each axis drawn uniformly from [from, to], or from its
/// "values"); the values of sample i depend only on (seed, i, axis), never on threads or shards.
/// "order": "warm_start" (default: random samples are solved in neighbour order, see
/// sweep_solve_order) or "sample" (solved in sample order).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "tdcr/core/scene.hpp"
#include "tdcr/models/static_model.hpp"

namespace tdcr {

/// @brief One swept field.
struct SweepAxis {
  /// @brief What the field changes: the per-call input (no model rebuild) or the scene (robot,
  /// effects, solver: the models are rebuilt).
  enum class Target {
    Tension,       ///< actuation.tensions[index]
    Displacement,  ///< actuation.displacements[index]
    TipForce,      ///< loads.tip_force[index]
    TipMoment,     ///< loads.tip_moment[index]
    Gravity,       ///< loads.gravity[index]
    Scene          ///< A robot., effects. or solver. field: the scene is parsed again.
  };
  std::string field;           ///< Scene-file path, e.g. `actuation.tensions[0]`.
  Target target = Target::Scene;  ///< What the field changes.
  int index = 0;               ///< Tendon or vector component for the input targets.
  std::vector<double> values;  ///< Grid values, or the choices of a random axis (may be empty).
  double from = 0.0;           ///< Random axis without values: uniform in [from, to].
  double to = 0.0;             ///< Upper end of a random range.
  /// @brief True if the axis changes the scene (robot, effects, solver) rather than the input.
  bool rebuilds_model() const { return target == Target::Scene; }
};

/// @brief A parsed and validated sweep file.
struct SweepSpec {
  std::string source;             ///< The sweep file's name (messages).
  std::string base_scene_json;    ///< The base scene, canonical JSON text.
  Scene base;                     ///< The base scene, parsed.
  std::vector<SweepAxis> axes;    ///< At least one.
  std::vector<ModelKind> models;  ///< At least one, no repeats.
  bool random = false;            ///< Random sampling (else grid).
  std::uint64_t random_samples = 0;  ///< Random sampling: number of samples.
  std::uint64_t seed = 0;            ///< Random sampling: the seed.
  bool warm_order = true;  ///< "order": "warm_start" (default) or "sample" (random samples unsorted).
  std::uint64_t hash = 0;  ///< FNV-1a of the canonical sweep (axes, models, base scene): resume check.

  /// @brief Number of samples (grid: product of the axis sizes).
  std::uint64_t sample_count() const;
  /// @brief The axis values of sample i (size axes.size()).
  void sample_values(std::uint64_t i, std::vector<double>& out) const;
  /// @brief The base scene with the scene axes set to `values` (all axes' values, in axis
  /// order; input axes are ignored here). Throws InputError naming the field and value.
  Scene scene_with(const std::vector<double>& values) const;
  /// @brief `scene`'s input with the input axes set to `values`.
  ModelInput input_with(const Scene& scene, const std::vector<double>& values) const;
  /// @brief True if some axis rebuilds the models.
  bool has_scene_axes() const;
};

/// @brief Parse a sweep from JSON text; relative scene paths are taken from `base_dir`. Throws
/// InputError naming the field and value (unknown key, missing scene file, an axis field that
/// does not exist, an axis value outside the field's valid range: the scene is validated for
/// every model with each axis at its extreme values).
SweepSpec parse_sweep(const std::string& json_text, const std::string& source = "<string>",
                      const std::string& base_dir = ".");

/// @brief Read and parse a sweep file (scene paths relative to the file's folder).
SweepSpec load_sweep(const std::string& path);

}  // namespace tdcr
