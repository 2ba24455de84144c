// The models' extension point, used as a research code outside the library would use it: a new
// model is one class (its header part), one residual system (its source part) and one registry
// row (register_model), with nothing else changed. The model here is the constant-curvature
// statics of tendon moments written as a residual system for Newton, EI u_s = sum of the moments
// of the tendons that reach segment s (Eq. 14-18): the same arcs as CC's closed form, so every
// answer is checked against CC to rounding. Once registered it is solved through every front
// door a built-in model has: make_model, the scene front door (tdcr::solve(scene)), the scene
// file, warm starts, the input checks its capabilities imply.
#include <cmath>
#include <memory>

#include <gtest/gtest.h>

#include "tdcr/bvp/continuation.hpp"
#include "tdcr/bvp/newton_solver.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/core/lie.hpp"
#include "tdcr/core/paper_robot.hpp"
#include "tdcr/core/scene_io.hpp"
#include "tdcr/models/cc.hpp"
#include "tdcr/models/model_problem.hpp"
#include "tdcr/models/model_registry.hpp"
#include "tdcr/models/model_selection.hpp"

using namespace tdcr;

namespace {

// --- The header part: the model class ------------------------------------------------------------

class ArcStaticsModel final : public StaticModel {
 public:
  ArcStaticsModel(const Robot& robot, const Effects& effects) : StaticModel(robot, effects) {}
  static ModelKind registered_kind;
  ModelKind kind() const override { return registered_kind; }
  ModelCapabilities capabilities() const override {
    ModelCapabilities c;  // tensions only, no external load, straight routing, no RK4 mesh
    c.external_loads = false;
    c.curved_routing = false;
    return c;
  }
  std::unique_ptr<ModelWorkspace> make_workspace() const override;

 private:
  ModelProblem& bind(ModelWorkspace& workspace, const ModelInput& input, const SolverOptions& options) const override;
};
ModelKind ArcStaticsModel::registered_kind = ModelKind::CC;

// --- The source part: its residual system and problem ---------------------------------------------

// F_s(u) = EI u_s - lambda m_s for every segment s (3 unknowns each), m_s the moment of the tendons
// that reach segment s at the bound tensions; lambda the load factor.
class ArcStaticsProblem final : public ModelProblem, public bvp::ParameterizedSystem {
 public:
  explicit ArcStaticsProblem(const ArcStaticsModel& model) : model_(model) {}

  void bind(const ModelInput& input) {
    const Robot& robot = model_.robot();
    const int nseg = static_cast<int>(robot.segments.size());
    moments_.assign(nseg, Vec3::Zero());
    for (int s = 0; s < nseg; ++s)
      for (const RoutedTendon& t : model_.routing().tendons)
        if (t.segment >= s) moments_[s] += input.actuation.values[t.index] * Vec3::UnitZ().cross(t.r);
    EI_ = robot.backbone.effective_stiffness().EI;
    tensions_ = input.actuation.values;
  }

  // ParameterizedSystem
  int size() const override { return 3 * static_cast<int>(moments_.size()); }
  void set_parameter(double lambda) override { lambda_ = lambda; }
  bool residual(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> f) override {
    for (std::size_t s = 0; s < moments_.size(); ++s)
      f.segment<3>(3 * s) = EI_ * x.segment<3>(3 * s) - lambda_ * moments_[s];
    return true;
  }
  bool has_jacobian() const override { return true; }
  bool jacobian(const Eigen::Ref<const Eigen::VectorXd>&, const Eigen::Ref<const Eigen::VectorXd>&,
                Eigen::Ref<Eigen::MatrixXd> J) override {
    J.setIdentity();
    J *= EI_;
    return true;
  }

  // ModelProblem: the six members every model gives; the rest keep their defaults.
  bvp::ParameterizedSystem* system() override { return this; }
  bvp::NewtonSolver& newton() override { return newton_; }
  void cold_guess(Eigen::VectorXd& x) override { x.setZero(size()); }
  void rest_state(Eigen::VectorXd& x) override { x.setZero(size()); }
  bool warm_guess(const Solution& previous, Eigen::VectorXd& x) override {
    if (previous.unknowns.size() != size() || !previous.unknowns.allFinite()) return false;
    x = previous.unknowns;
    return true;
  }
  void extract(const Eigen::VectorXd& x, bool, Solution& solution) override {
    const Robot& robot = model_.robot();
    solution.disk_frames.assign(1, Frame{});
    Frame current;
    for (std::size_t s = 0; s < robot.segments.size(); ++s) {
      const double ds = robot.segments[s].length / robot.segments[s].disks;
      const Frame step = lie::exp_se3(x.segment<3>(3 * s) * ds, Vec3(0.0, 0.0, ds));
      for (int j = 0; j < robot.segments[s].disks; ++j) solution.disk_frames.push_back(current = current * step);
    }
    solution.tensions = tensions_;
    solution.unknowns = x;
  }

 private:
  const ArcStaticsModel& model_;
  std::vector<Vec3> moments_;
  std::vector<double> tensions_;
  double EI_ = 0.0, lambda_ = 1.0;
  bvp::NewtonSolver newton_;
};

class ArcStaticsWorkspace final : public ModelWorkspace {
 public:
  explicit ArcStaticsWorkspace(const ArcStaticsModel& owner) : ModelWorkspace(owner), problem(owner) {}
  ArcStaticsProblem problem;
};

std::unique_ptr<ModelWorkspace> ArcStaticsModel::make_workspace() const {
  return std::make_unique<ArcStaticsWorkspace>(*this);
}

ModelProblem& ArcStaticsModel::bind(ModelWorkspace& workspace, const ModelInput& input, const SolverOptions&) const {
  ArcStaticsProblem& problem = static_cast<ArcStaticsWorkspace&>(workspace).problem;
  problem.bind(input);
  return problem;
}

// --- The registry row ------------------------------------------------------------------------------

ModelKind arc_statics() {
  static const ModelKind kind = [] {
    ModelInfo row{};
    row.name = "arc_statics";
    row.description = "constant curvature per segment from tendon moments, solved by Newton (test model)";
    row.make = [](const Robot& robot, const Effects& effects) -> std::unique_ptr<StaticModel> {
      return std::make_unique<ArcStaticsModel>(robot, effects);
    };
    row.capabilities = ArcStaticsModel(paper::robot(1), Effects()).capabilities();
    row.accuracy = {{25.7, 4.27, 0.605, 0.151}, 2.0, INFINITY};
    row.cost_rank = -1;  // never chosen by auto
    const ModelKind k = register_model(row);
    ArcStaticsModel::registered_kind = k;
    return k;
  }();
  return kind;
}

// The paper robot with tensions on both segments' tendons: a spatial two-segment bend.
Scene two_segment_scene(const std::string& model) {
  Scene s;
  s.robot = paper::robot(5);
  s.actuation.kind = Actuation::Kind::Tensions;
  s.actuation.values.assign(static_cast<std::size_t>(s.robot.tendon_count()), 0.0);
  s.actuation.values[0] = 2.0;
  s.actuation.values[1] = 0.5;
  s.actuation.values[s.actuation.values.size() - 2] = 1.0;
  s.effects.shear_extension = false;  // the test model's arcs are inextensible
  s.model = model;
  return s;
}

}  // namespace

TEST(ModelExtension, RegisteredModelIsNamedLikeABuiltInOne) {
  const ModelKind k = arc_statics();
  EXPECT_GE(static_cast<int>(k), 5);
  EXPECT_EQ(to_string(k), "arc_statics");
  EXPECT_EQ(parse_model_kind("ARC_statics"), k);
  EXPECT_NE(model_names().find("arc_statics"), std::string::npos);
  EXPECT_EQ(model_info(k).kind, k);
}

TEST(ModelExtension, SolvesToCcsClosedForm) {
  const Scene scene = two_segment_scene("arc_statics");
  const auto model = make_model(arc_statics(), scene);
  auto ws = model->make_workspace();
  const Solution s = solve(*model, *ws, scene.input(), scene.solver);
  ASSERT_TRUE(s.converged()) << s.summary.message;
  EXPECT_EQ(s.model, "arc_statics");
  EXPECT_EQ(s.model_fingerprint, model->fingerprint());

  Scene cc_scene = scene;
  cc_scene.model = "cc";
  const Solution cc = solve(cc_scene);
  ASSERT_TRUE(cc.converged());
  ASSERT_EQ(s.disk_frames.size(), cc.disk_frames.size());
  EXPECT_GT(cc.tip().p.head<2>().norm(), 0.01);  // a real bend, not the straight robot
  for (std::size_t j = 0; j < s.disk_frames.size(); ++j) {
    EXPECT_LT((s.disk_frames[j].p - cc.disk_frames[j].p).norm(), 1e-12) << "disk " << j;
    EXPECT_LT((s.disk_frames[j].R - cc.disk_frames[j].R).norm(), 1e-12) << "disk " << j;
  }
}

TEST(ModelExtension, SceneFrontDoorAndSceneFileTakeIt) {
  arc_statics();
  const Scene scene = two_segment_scene("arc_statics");
  const Scene read = parse_scene(scene_to_json(scene));
  EXPECT_EQ(read.model, "arc_statics");
  EXPECT_NO_THROW(validate_scene(read));
  const Solution s = solve(read);
  ASSERT_TRUE(s.converged()) << s.summary.message;
  EXPECT_EQ(s.model, "arc_statics");
  EXPECT_TRUE(s.model_selection.empty());
  const SceneModel chosen = make_scene_model(read);
  EXPECT_FALSE(chosen.automatic);
  EXPECT_EQ(chosen.model->name(), "arc_statics");
}

TEST(ModelExtension, WarmStartFromItsOwnAnswerNeedsNoIteration) {
  const Scene scene = two_segment_scene("arc_statics");
  const auto model = make_model(arc_statics(), scene);
  auto ws = model->make_workspace();
  const Solution cold = solve(*model, *ws, scene.input(), scene.solver);
  ASSERT_TRUE(cold.converged());
  EXPECT_GE(cold.summary.iterations, 1);
  const Solution warm = solve(*model, *ws, scene.input(), scene.solver, &cold);
  ASSERT_TRUE(warm.converged());
  EXPECT_EQ(warm.summary.iterations, 0);
  EXPECT_LT((warm.tip().p - cold.tip().p).norm(), 1e-15);
}

TEST(ModelExtension, CapabilitiesDecideItsInputChecks) {
  arc_statics();
  Scene scene = two_segment_scene("arc_statics");
  scene.loads.tip_force = Vec3(0.0, 0.0, -0.1);
  try {
    solve(scene);
    FAIL() << "a tip force was accepted by a model without external loads";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "loads.tip_force");
  }
  scene.loads.tip_force.setZero();
  scene.actuation.kind = Actuation::Kind::Displacements;
  try {
    solve(scene);
    FAIL() << "displacements were accepted by a model that takes tensions only";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "actuation.displacements");
  }
}

TEST(ModelExtension, AutoNeverChoosesAModelWithoutACostRank) {
  arc_statics();
  for (double tol : {0.5, 0.01, 1e-6}) {
    Scene scene = two_segment_scene("auto");
    const SceneModel chosen = make_scene_model(scene, tol);
    EXPECT_TRUE(chosen.automatic);
    EXPECT_NE(chosen.model->name(), "arc_statics") << "tolerance " << tol;
    EXPECT_NE(chosen.selection().find("auto: "), std::string::npos);
  }
}

TEST(ModelExtension, RegistrationRefusesTakenReservedAndUnnamedRows) {
  arc_statics();
  ModelInfo row{};
  row.make = model_info(ModelKind::CC).make;
  for (const char* name : {"arc_statics", "vc", "auto", "", "Has Space"}) {
    row.name = name;
    try {
      register_model(row);
      FAIL() << "registered \"" << name << "\"";
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), "model.name") << name;
    }
  }
  row.name = "no_factory";
  row.make = nullptr;
  EXPECT_THROW(register_model(row), InputError);
}
