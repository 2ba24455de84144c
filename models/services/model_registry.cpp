// The registry table: one row per model (built in, or added through register_model), names, factories.
#include "tdcr/models/model_registry.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>

#include "tdcr/core/error.hpp"
#include "tdcr/models/cc.hpp"
#include "tdcr/models/ccsub.hpp"
#include "tdcr/models/prb.hpp"
#include "tdcr/models/vc.hpp"
#include "tdcr/models/vcref.hpp"

namespace tdcr {

namespace {
// The registry's factory of a model class constructible from (robot, effects).
template <class Model>
std::unique_ptr<StaticModel> make(const Robot& robot, const Effects& effects) {
  return std::make_unique<Model>(robot, effects);
}
}  // namespace

namespace {
// The table, built-in rows first. Its capacity is reserved once: rows never move, so references
// from model_info() stay valid while models are registered.
std::vector<ModelInfo>& table() {
  // Expected accuracy: bench_case_study, scenario 1 (mean tip error against VCref, % of 2L) and
  // scenario 2 (loaded factor), docs/benchmarks.md. The constant-curvature family's error falls
  // as 1/n^2 beyond n = 10 (second-order chord approximation of the tendon path); CC from
  // tensions equals VC without external load; CCsub is within 1.2x of VC. With loads PRB is
  // slower than VCref (bench_case_study, scenario 2).
  static std::vector<ModelInfo> rows = [] {
    std::vector<ModelInfo> v;
    v.reserve(kMaxModels);
    v.assign({
      {ModelKind::CC, "cc", "constant curvature per segment, kinematic (closed form)", make<CcModel>,
       CcModel::kCapabilities, {{25.7, 4.27, 0.605, 0.151}, 2.0, INFINITY}, 0},
      {ModelKind::CCsub, "ccsub", "constant curvature per subsegment with twist, static", make<CcsubModel>,
       CcsubModel::kCapabilities, {{30.8, 5.12, 0.726, 0.181}, 2.0, 3.2}, 2},
      {ModelKind::PRB, "prb", "3R pseudo-rigid body per subsegment with twist, static", make<PrbModel>,
       PrbModel::kCapabilities, {{1.21, 0.231, 0.0165, 0.0345}, 0.0, 3.2}, 3, 5},
      {ModelKind::VC, "vc", "Cosserat rod with fully constrained tendons (Rucker & Webster 2011)",
       make<VcModel>, VcModel::kCapabilities, {{25.7, 4.27, 0.605, 0.151}, 2.0, 3.2}, 1},
      {ModelKind::VCref, "vcref", "Cosserat rod per subsegment with discrete disk forces (reference)",
       make<VcrefModel>, VcrefModel::kCapabilities, {{0.0, 0.0, 0.0, 0.0}, 0.0, 1.0}, 4},
    });
    return v;
  }();
  return rows;
}
}  // namespace

const std::vector<ModelInfo>& model_registry() { return table(); }

ModelKind register_model(ModelInfo info) {
  std::vector<ModelInfo>& rows = table();
  const std::string name = info.name ? info.name : "";
  if (name.empty() || name == "auto" ||
      std::any_of(name.begin(), name.end(), [](unsigned char c) { return !(std::islower(c) || std::isdigit(c) || c == '_'); }))
    throw InputError("model.name", "\"" + name + "\"", "must be a new lowercase name of letters, digits and '_' (not auto)");
  for (const ModelInfo& m : rows)
    if (name == m.name) throw InputError("model.name", "\"" + name + "\"", "is already registered");
  if (!info.make) throw InputError("model.make", "null", "a registered model needs a factory");
  if (rows.size() >= kMaxModels)
    throw InputError("model", "\"" + name + "\"", "the registry holds at most " + std::to_string(kMaxModels) + " models");
  info.kind = static_cast<ModelKind>(rows.size());
  rows.push_back(info);
  return info.kind;
}

const ModelInfo& model_info(ModelKind kind) {
  // Called on every solve: the table is in ModelKind order, so the entry is found by index.
  const std::vector<ModelInfo>& table = model_registry();
  const auto i = static_cast<std::size_t>(kind);
  if (i < table.size() && table[i].kind == kind) return table[i];
  throw InputError("model", std::to_string(static_cast<int>(kind)), "not in the model registry");
}

std::string model_names() {
  std::string s;
  for (const ModelInfo& m : model_registry()) s += (s.empty() ? "" : ", ") + std::string(m.name);
  return s;
}

std::string to_string(ModelKind kind) { return model_info(kind).name; }

ModelKind parse_model_kind(const std::string& name) {
  std::string n = name;
  std::transform(n.begin(), n.end(), n.begin(), [](unsigned char c) { return std::tolower(c); });
  for (const ModelInfo& m : model_registry())
    if (n == m.name) return m.kind;
  throw InputError("model", "\"" + name + "\"", "unknown model (expected " + model_names() + ")");
}

// --- Factories ----------------------------------------------------------------------------------

std::unique_ptr<StaticModel> make_model(ModelKind kind, const Robot& robot, const Effects& effects) {
  return model_info(kind).make(robot, effects);
}

std::unique_ptr<StaticModel> make_model(ModelKind kind, const Scene& scene) {
  return make_model(kind, scene.robot, scene.effects);
}

}  // namespace tdcr
