/// @file model_registry.hpp
/// @brief The one table of tdcr's models: kind, name, factory, capabilities, expected accuracy.
/// The scene checks, the CLI, model selection (`auto`) and verification read it; adding a model
/// is one header, one source file, one row here and one line in the conformance suite.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "tdcr/models/static_model.hpp"

namespace tdcr {

/// @brief Mean tip position error of a model against VCref (% of the robot length) on the
/// paper's case study, measured by bench_case_study (docs/benchmarks.md), at 1, 2, 5 and 10
/// disks per segment without external load. Used by model selection.
struct ExpectedAccuracy {
  double percent_at[4] = {0.0, 0.0, 0.0, 0.0};  ///< At n = 1, 2, 5, 10.
  /// Beyond n = 10: the error falls as (10 / n)^tail_exponent (0: stays at the n = 10 value).
  double tail_exponent = 0.0;
  /// With tip forces (scenario 2, n = 10): the loaded error is at most this times the unloaded
  /// one (infinite: the model cannot take loads).
  double loaded_factor = 1.0;
};

/// @brief One row of the registry.
struct ModelInfo {
  ModelKind kind;               ///< The enumerator.
  const char* name;             ///< Registry name, as in scene files and on the command line.
  const char* description;      ///< One line for usage texts.
  /// Builds the model (validates robot and effects, throws InputError).
  std::unique_ptr<StaticModel> (*make)(const Robot& robot, const Effects& effects);
  ModelCapabilities capabilities;  ///< What it takes.
  ExpectedAccuracy accuracy;       ///< Expected error against VCref.
  /// Order of typical solve time, cheapest first (auto); negative: never chosen by auto.
  int cost_rank;
  /// The same order with external loads, where it differs (-1: cost_rank).
  int loaded_cost_rank = -1;
};

/// @brief The most models the registry holds (the five built in and those registered).
inline constexpr std::size_t kMaxModels = 32;

/// @brief Every model, in ModelKind order: the five built-in models, then the registered ones.
const std::vector<ModelInfo>& model_registry();

/// @brief The extension point: add a model to the registry. A new model is one header (its class,
/// derived from StaticModel, with its `kCapabilities`), one source (its residual system, a
/// ModelProblem, model_problem.hpp) and this one row; tests/test_model_extension.cpp builds one in the test
/// tree. `info.kind` is ignored: the new row's kind is returned, and scene files, the CLI, sweeps
/// and Python then name the model by `info.name` like a built-in one. Model selection (`auto`)
/// considers it only with `cost_rank >= 0`.
///
/// Registration is not synchronised with solves in other threads: register at start-up.
/// Throws InputError for a missing, reserved ("auto") or taken name, a missing factory, or a
/// full registry (kMaxModels).
ModelKind register_model(ModelInfo info);
/// @brief The row of `kind`.
const ModelInfo& model_info(ModelKind kind);
/// @brief "cc, ccsub, prb, vc, vcref": the registry names, for messages and usage texts.
std::string model_names();

}  // namespace tdcr
