// Transitional: wraps a scene-bound model (legacy_model.hpp) as a StaticModel, so that every
// model is reachable through the registry and tdcr::solve while the models move to the
// ModelProblem interface one by one. A model that has moved defines its make_<model>_model in
// its own folder and its line below goes.
#include <string>

#include "common/model_factories.hpp"
#include "common/model_problem.hpp"

namespace tdcr {

namespace {

using LegacyFactory = std::unique_ptr<LegacyStaticModel> (*)(const Scene&);

class LegacyProblem final : public detail::ModelProblem {
 public:
  LegacyProblem(const Scene& scene, LegacyFactory make) : scene_(scene), make_(make) {}
  bvp::ParameterizedSystem* system() override { return nullptr; }
  bvp::NewtonSolver& newton() override { return newton_; }
  void cold_guess(Eigen::VectorXd&) override {}
  void rest_state(Eigen::VectorXd&) override {}
  bool warm_guess(const Solution&, Eigen::VectorXd&) override { return false; }
  void extract(const Eigen::VectorXd&, bool, Solution&) override {}
  bool solve_whole(const Solution* warm_start, Solution& solution) override {
    const auto model = make_(scene_);
    const auto ws = model->make_workspace();
    solution = model->solve(*ws, warm_start);
    return true;
  }

 private:
  Scene scene_;
  LegacyFactory make_;
  bvp::NewtonSolver newton_;
};

class LegacyWorkspaceAdapter final : public ModelWorkspace {
 public:
  explicit LegacyWorkspaceAdapter(const StaticModel& owner) : ModelWorkspace(owner) {}
  std::unique_ptr<LegacyProblem> problem;
};

class LegacyModelAdapter final : public StaticModel {
 public:
  LegacyModelAdapter(ModelKind kind, const Robot& robot, const Effects& effects, LegacyFactory make)
      : StaticModel(robot, effects), kind_(kind), make_(make) {}
  ModelKind kind() const override { return kind_; }
  std::unique_ptr<ModelWorkspace> make_workspace() const override {
    return std::make_unique<LegacyWorkspaceAdapter>(*this);
  }

 private:
  detail::ModelProblem& bind(ModelWorkspace& workspace, const ModelInput& input,
                             const SolverOptions& options) const override {
    auto& ws = static_cast<LegacyWorkspaceAdapter&>(workspace);
    Scene scene;
    scene.robot = robot();
    scene.effects = effects();
    scene.actuation = input.actuation;
    scene.loads = input.loads;
    scene.model = name();
    scene.solver = options;
    ws.problem = std::make_unique<LegacyProblem>(scene, make_);
    return *ws.problem;
  }
  ModelKind kind_;
  LegacyFactory make_;
};

}  // namespace

namespace detail {
std::unique_ptr<StaticModel> make_cc_model(const Robot& r, const Effects& e) {
  return std::make_unique<LegacyModelAdapter>(ModelKind::CC, r, e, make_legacy_cc_model);
}
std::unique_ptr<StaticModel> make_ccsub_model(const Robot& r, const Effects& e) {
  return std::make_unique<LegacyModelAdapter>(ModelKind::CCsub, r, e, make_legacy_ccsub_model);
}
std::unique_ptr<StaticModel> make_prb_model(const Robot& r, const Effects& e) {
  return std::make_unique<LegacyModelAdapter>(ModelKind::PRB, r, e, make_legacy_prb_model);
}
std::unique_ptr<StaticModel> make_vc_model(const Robot& r, const Effects& e) {
  return std::make_unique<LegacyModelAdapter>(ModelKind::VC, r, e, make_legacy_vc_model);
}
}  // namespace detail

}  // namespace tdcr
