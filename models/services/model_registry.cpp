// The registry table, the StaticModel and ModelWorkspace base classes, and the scene front door.
#include "tdcr/models/model_registry.hpp"

#include "solve/displacement_input.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>

#include "tdcr/core/error.hpp"
#include "tdcr/core/scene_io.hpp"
#include "tdcr/models/cc.hpp"
#include "tdcr/models/ccsub.hpp"
#include "tdcr/models/model_selection.hpp"
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

const std::vector<ModelInfo>& model_registry() {
  // Expected accuracy: bench_case_study, scenario 1 (mean tip error against VCref, % of 2L) and
  // scenario 2 (loaded factor), docs/benchmarks.md. The constant-curvature family's error falls
  // as 1/n^2 beyond n = 10 (second-order chord approximation of the tendon path); CC from
  // tensions equals VC without external load; CCsub is within 1.2x of VC. With loads PRB is
  // slower than VCref (bench_case_study, scenario 2).
  static const std::vector<ModelInfo> table = {
      {ModelKind::CC, "cc", "constant curvature per segment, kinematic (closed form)", make<CcModel>,
       {true, true, false, false}, {{25.7, 4.27, 0.605, 0.151}, 2.0, INFINITY}, 0},
      {ModelKind::CCsub, "ccsub", "constant curvature per subsegment with twist, static", make<CcsubModel>,
       {true, true, true, false, true, true, true}, {{30.8, 5.12, 0.726, 0.181}, 2.0, 3.2}, 2},
      {ModelKind::PRB, "prb", "3R pseudo-rigid body per subsegment with twist, static", make<PrbModel>,
       {true, true, true, false, true, true, true}, {{1.21, 0.231, 0.0165, 0.0345}, 0.0, 3.2}, 3, 5},
      {ModelKind::VC, "vc", "Cosserat rod with fully constrained tendons (Rucker & Webster 2011)",
       make<VcModel>, {true, true, true, true, false, true, true}, {{25.7, 4.27, 0.605, 0.151}, 2.0, 3.2}, 1},
      {ModelKind::VCref, "vcref", "Cosserat rod per subsegment with discrete disk forces (reference)",
       make<VcrefModel>, {true, true, true, true, true, true, true}, {{0.0, 0.0, 0.0, 0.0}, 0.0, 1.0}, 4},
  };
  return table;
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

// --- StaticModel, ModelWorkspace ---------------------------------------------------------------

namespace {
// FNV-1a of the model's description: kind, robot and effects as the scene file writes them.
std::uint64_t fnv1a(const std::string& s, std::uint64_t h = 1469598103934665603ull) {
  for (unsigned char c : s) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}
}  // namespace

StaticModel::StaticModel(const Robot& robot, const Effects& effects)
    : robot_(robot), effects_(effects), token_(std::make_shared<const int>(0)) {
  robot_.validate();
  effects_.validate(robot_);
  routing_ = TendonRouting::from(robot_);
  Scene description;
  description.robot = robot_;
  description.effects = effects_;
  description.actuation.values.assign(robot_.tendon_count(), 0.0);
  fingerprint_ = fnv1a(scene_to_json(description));
}

StaticModel::~StaticModel() = default;

void StaticModel::check_input(const ModelInput& input) const {
  const ModelInfo& info = model_info(kind());
  const bool tensions = input.actuation.kind == Actuation::Kind::Tensions;
  if (tensions && !info.capabilities.tension_input)
    throw InputError("actuation.tensions", "given", "the " + name() + " model takes tendon displacements");
  if (!tensions && !info.capabilities.displacement_input)
    throw InputError("actuation.displacements", "given", "the " + name() + " model takes tendon tensions");
  if (!tensions && !info.capabilities.displacement_statics) {
    if (input.actuation.mixed())
      throw InputError("actuation", "tensions and displacements",
                       "the " + name() + " model is kinematic: give every tendon by displacement or every tendon by "
                       "tension (mixed input needs a static model)");
    for (std::size_t i = 0; i < robot_.segments.size(); ++i)
      for (std::size_t j = 0; j < robot_.segments[i].tendons.size(); ++j)
        if (robot_.segments[i].tendons[j].stiffness)
          throw InputError("robot.segments[" + std::to_string(i) + "].tendons[" + std::to_string(j) + "].stiffness",
                           format_value(*robot_.segments[i].tendons[j].stiffness),
                           "the " + name() + " model is kinematic: elastic tendons need a static model");
  }
  if (!info.capabilities.external_loads) {
    const Loads& l = input.loads;
    auto refuse = [&](const char* field, const Vec3& v) {
      if (v.squaredNorm() > 0.0) {
        char b[96];
        std::snprintf(b, sizeof b, "[%g, %g, %g]", v.x(), v.y(), v.z());
        throw InputError(field, b, "the " + name() + " model is kinematic and takes no external load; use a static model");
      }
    };
    refuse("loads.tip_force", l.tip_force);
    refuse("loads.tip_moment", l.tip_moment);
    refuse("loads.gravity", l.gravity);
  }
}

ModelWorkspace::ModelWorkspace(const StaticModel& owner) : owner_(owner.ownership_token()) {}
ModelWorkspace::~ModelWorkspace() = default;

bool ModelWorkspace::belongs_to(const StaticModel& model) const {
  const std::shared_ptr<const int> owner = owner_.lock();
  return owner && owner == model.ownership_token();
}

// --- Factories and the scene front door -------------------------------------------------------

std::unique_ptr<StaticModel> make_model(ModelKind kind, const Robot& robot, const Effects& effects) {
  return model_info(kind).make(robot, effects);
}

std::unique_ptr<StaticModel> make_model(ModelKind kind, const Scene& scene) {
  return make_model(kind, scene.robot, scene.effects);
}

void validate_scene(const Scene& scene) {
  scene.validate();
  if (scene.model == "auto") return;
  const ModelKind kind = parse_model_kind(scene.model);
  make_model(kind, scene)->check_input(scene.input());
}

Solution solve(const Scene& scene, const Solution* warm_start) {
  scene.validate();
  if (scene.model == "auto") return solve_auto(scene, 0.01, warm_start);  // default accuracy: 1 %
  const auto model = make_model(parse_model_kind(scene.model), scene);
  const auto workspace = model->make_workspace();
  return solve(*model, *workspace, scene.input(), scene.solver, warm_start);
}

}  // namespace tdcr
