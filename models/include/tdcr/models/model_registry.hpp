/// @file model_registry.hpp
/// @brief The one table of tdcr's models: kind, name, factory, capabilities, expected accuracy.
/// The scene checks, the CLI, model selection (`auto`) and verification read it; adding a model
/// is one header, one source file, one row here and one line in the conformance suite.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "tdcr/models/static_model.hpp"

namespace tdcr {

/// @brief What a model can take and compute.
struct ModelCapabilities {
  bool tension_input = true;        ///< Actuation by tendon tensions.
  bool displacement_input = false;  ///< Actuation by tendon displacements.
  bool external_loads = true;       ///< Tip wrench and gravity.
  bool backbone_wrench = false;     ///< Solutions carry internal force and moment samples.
  /// Tendons act on the backbone at the disks only, along straight chords between holes
  /// (Eq. 30-33); else along the backbone (fully constrained path, Eq. 24-29).
  bool tendon_forces_at_disks = false;
  /// Displacement input with statics: the tensions of the displacement-driven tendons are
  /// unknowns (solve/displacement_input.hpp); mixed input and elastic tendons. Else a model
  /// that takes displacements maps them kinematically (CC).
  bool displacement_statics = false;
  bool tendon_friction = false;  ///< Capstan tendon friction (Effects::tendon_friction).
};

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
  int cost_rank;                   ///< Order of typical solve time, cheapest first (auto).
  /// The same order with external loads, where it differs (-1: cost_rank).
  int loaded_cost_rank = -1;
};

/// @brief Every model, in ModelKind order.
const std::vector<ModelInfo>& model_registry();
/// @brief The row of `kind`.
const ModelInfo& model_info(ModelKind kind);
/// @brief "cc, ccsub, prb, vc, vcref": the registry names, for messages and usage texts.
std::string model_names();

}  // namespace tdcr
