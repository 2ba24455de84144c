// The model conformance suite: what every model of the registry promises through the one
// interface (StaticModel, ModelWorkspace, tdcr::solve), run for every registry row. A new model
// gets all of it from its registry row; what a model cannot take is read from its capabilities.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "tdcr/core/error.hpp"
#include "tdcr/core/lie.hpp"
#include "tdcr/core/paper_robot.hpp"
#include "tdcr/models/model_registry.hpp"
#include "tdcr/models/static_model.hpp"
#include "tdcr/models/verification.hpp"

using namespace tdcr;

namespace tdcr {
// Test names and failure messages show the registry name.
void PrintTo(const ModelInfo& info, std::ostream* os) { *os << info.name; }
}  // namespace tdcr

namespace {

class Conformance : public testing::TestWithParam<ModelInfo> {
 protected:
  const ModelInfo& info() const { return GetParam(); }
  const ModelCapabilities& can() const { return GetParam().capabilities; }
  std::unique_ptr<StaticModel> make(const Robot& robot) const { return make_model(info().kind, robot); }
  // A registry row of another kind than this one.
  const ModelInfo& other_row() const {
    for (const ModelInfo& m : model_registry())
      if (m.kind != info().kind) return m;
    return info();
  }
};

double T_M() { return paper::max_tension(paper::robot(5)); }

// Tensions of the paper robot bending it in the y-z plane: tendon 1 (segment 1, +y) and tendon 4
// (segment 2, -y): an S-shape.
ModelInput bent_input() {
  ModelInput in;
  in.actuation.values = {0.8 * T_M(), 0.0, 0.0, 0.5 * T_M()};
  return in;
}

// The same input with a tip force when the model takes loads: a spatial shape.
ModelInput loaded_input(const ModelCapabilities& c) {
  ModelInput in = bent_input();
  if (c.external_loads) in.loads.tip_force = Vec3(0.4, 0.3, -0.2);
  return in;
}

// The mirror y -> -y: tendon k of the robot goes to the tendon at (x, -y) of the same segment.
std::vector<int> mirror_tendons(const Robot& robot) {
  std::vector<int> map;
  int first = 0;
  for (const Segment& s : robot.segments) {
    for (const TendonSpec& t : s.tendons)
      for (std::size_t j = 0; j < s.tendons.size(); ++j)
        if (s.tendons[j].x == t.x && s.tendons[j].y == -t.y) {
          map.push_back(first + static_cast<int>(j));
          break;
        }
    first += static_cast<int>(s.tendons.size());
  }
  return map;
}

ModelInput mirrored(const ModelInput& in, const std::vector<int>& map) {
  ModelInput m = in;
  for (std::size_t k = 0; k < map.size(); ++k) m.actuation.values[map[k]] = in.actuation.values[k];
  m.loads.tip_force.y() = -in.loads.tip_force.y();
  return m;
}

// Solves `input` and checks that the mirrored input gives the mirrored shape (every disk).
void expect_mirror_shape(const StaticModel& model, const ModelInput& input) {
  const auto ws = model.make_workspace();
  const std::vector<int> map = mirror_tendons(model.robot());
  ASSERT_EQ(map.size(), input.actuation.values.size());
  const Solution a = solve(model, *ws, input);
  const Solution b = solve(model, *ws, mirrored(input, map));
  ASSERT_TRUE(a.converged()) << a.summary.brief_report();
  ASSERT_TRUE(b.converged()) << b.summary.brief_report();
  ASSERT_EQ(a.disk_frames.size(), b.disk_frames.size());
  const Mat3 S = Vec3(1.0, -1.0, 1.0).asDiagonal();
  EXPECT_GT(std::abs(a.tip().p.y()), 1e-3);  // bent indeed
  for (std::size_t j = 0; j < a.disk_frames.size(); ++j) {
    EXPECT_LT((S * a.disk_frames[j].p - b.disk_frames[j].p).norm(), 1e-9) << "disk " << j;
    EXPECT_LT(lie::rotation_angle(S * a.disk_frames[j].R * S, b.disk_frames[j].R), 1e-9) << "disk " << j;
  }
}

template <typename F>
std::string field_of(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.field();
  }
  return "(no InputError)";
}

TEST_P(Conformance, RegistryRowIsConsistent) {
  const auto model = make(paper::robot(5));
  EXPECT_EQ(model->kind(), info().kind);
  EXPECT_EQ(model->name(), info().name);
  EXPECT_EQ(parse_model_kind(info().name), info().kind);
  EXPECT_STREQ(model_info(info().kind).name, info().name);
  EXPECT_NE(model_names().find(info().name), std::string::npos);
  EXPECT_TRUE(can().tension_input || can().displacement_input);
}

TEST_P(Conformance, StraightAtZeroLoad) {
  const auto model = make(paper::robot(5));
  const auto ws = model->make_workspace();
  ModelInput in;
  in.actuation.kind = can().tension_input ? Actuation::Kind::Tensions : Actuation::Kind::Displacements;
  in.actuation.values.assign(4, 0.0);
  const Solution sol = solve(*model, *ws, in);
  ASSERT_TRUE(sol.converged()) << sol.summary.brief_report();
  ASSERT_EQ(sol.disk_frames.size(), 11u);
  EXPECT_EQ(sol.model, info().name);
  EXPECT_EQ(sol.model_fingerprint, model->fingerprint());
  for (std::size_t j = 0; j < sol.disk_frames.size(); ++j) {
    const Frame& f = sol.disk_frames[j];
    EXPECT_LT(f.p.head<2>().norm(), 1e-12) << "disk " << j;
    EXPECT_LT((f.R - Mat3::Identity()).norm(), 1e-12) << "disk " << j;
    EXPECT_NEAR(f.p.z(), 0.01 * j, 1e-12) << "disk " << j;  // unstretched: no load
  }
}

TEST_P(Conformance, MirrorSymmetryOfTensions) {
  if (!can().tension_input) GTEST_SKIP() << "takes no tensions";
  const auto model = make(paper::robot(5));
  expect_mirror_shape(*model, loaded_input(can()));
}

TEST_P(Conformance, MirrorSymmetryOfDisplacements) {
  if (!can().displacement_input) GTEST_SKIP() << "takes no displacements";
  const auto model = make(paper::robot(5));
  ModelInput in;
  in.actuation.kind = Actuation::Kind::Displacements;
  in.actuation.values = {0.002, -0.002, -0.0005, 0.0005};
  expect_mirror_shape(*model, in);
}

TEST_P(Conformance, WarmStartGivesTheColdAnswer) {
  const auto model = make(paper::robot(5));
  const auto ws = model->make_workspace();
  const ModelInput in = loaded_input(can());
  const Solution cold = solve(*model, *ws, in);
  ASSERT_TRUE(cold.converged()) << cold.summary.brief_report();
  const Solution warm = solve(*model, *ws, in, SolverOptions(), &cold);
  ASSERT_TRUE(warm.converged()) << warm.summary.brief_report();
  EXPECT_LT((warm.tip().p - cold.tip().p).norm(), 1e-9);
  EXPECT_LE(warm.summary.iterations, cold.summary.iterations);
}

TEST_P(Conformance, FailureIsNeverReportedAsSuccess) {
  const auto model = make(paper::robot(5));
  const auto ws = model->make_workspace();
  const ModelInput in = loaded_input(can());
  const Solution full = solve(*model, *ws, in);
  ASSERT_TRUE(full.converged()) << full.summary.brief_report();
  if (full.summary.linear_solver == "none") GTEST_SKIP() << "closed form: no iteration to cut short";
  ASSERT_GT(full.summary.iterations, 1);
  SolverOptions o;
  o.max_iterations = 1;
  o.continuation = false;
  const Solution sol = solve(*model, *ws, in, o);
  const SolverSummary& sum = sol.summary;
  EXPECT_FALSE(sol.converged());
  EXPECT_NE(sum.termination, TerminationType::NotSolved);
  EXPECT_FALSE(sum.message.empty());
  EXPECT_GE(sum.iterations, 1);
  EXPECT_FALSE(sum.residual_norm <= o.function_tolerance) << sum.residual_norm;
  const std::string report = sum.brief_report();
  EXPECT_NE(report.find(std::to_string(sum.iterations) + " iterations"), std::string::npos) << report;
  EXPECT_NE(report.find("|F| = "), std::string::npos) << report;
  EXPECT_NE(report.find(sum.message), std::string::npos) << report;
}

TEST_P(Conformance, WorkspaceOfAnotherModelIsRefused) {
  const Robot robot = paper::robot(5);
  const auto model = make(robot);
  const ModelInput in = bent_input();
  // Another model of the same kind and robot.
  const auto twin = make(robot);
  EXPECT_EQ(field_of([&] { solve(*model, *twin->make_workspace(), in); }), "workspace");
  // A model of another kind.
  const auto other = make_model(other_row().kind, robot);
  EXPECT_EQ(field_of([&] { solve(*model, *other->make_workspace(), in); }), "workspace");
  // A destroyed model.
  auto gone = make(robot);
  const auto orphan = gone->make_workspace();
  gone.reset();
  EXPECT_FALSE(orphan->belongs_to(*model));
  EXPECT_EQ(field_of([&] { solve(*model, *orphan, in); }), "workspace");
  // Its own workspace still works.
  EXPECT_TRUE(solve(*model, *model->make_workspace(), in).converged());
}

TEST_P(Conformance, WarmStartOfAnotherModelOrRobotIsRefused) {
  const auto model = make(paper::robot(5));
  const auto ws = model->make_workspace();
  const ModelInput in = bent_input();
  // A Solution of another model of the same robot.
  const auto other = make_model(other_row().kind, paper::robot(5));
  const Solution of_other = solve(*other, *other->make_workspace(), in);
  EXPECT_EQ(field_of([&] { solve(*model, *ws, in, SolverOptions(), &of_other); }), "warm_start");
  // A Solution of the same model kind on another robot.
  const auto longer = make(paper::robot(6));
  const Solution of_robot = solve(*longer, *longer->make_workspace(), in);
  EXPECT_EQ(field_of([&] { solve(*model, *ws, in, SolverOptions(), &of_robot); }), "warm_start");
}

TEST_P(Conformance, EquilibriumIsVerifiedWhereTheModelCarriesTheBackboneWrench) {
  const auto model = make(paper::robot(5));
  const ModelInput in = loaded_input(can());
  const Solution sol = solve(*model, *model->make_workspace(), in);
  ASSERT_TRUE(sol.converged()) << sol.summary.brief_report();
  const EquilibriumCheck c = verify_equilibrium(*model, in, sol);
  if (!can().backbone_wrench) {
    EXPECT_FALSE(c.evaluated);
    EXPECT_FALSE(c.reason.empty());
    return;
  }
  ASSERT_TRUE(c.evaluated) << c.reason;
  // As the hard cases: RK4 integration error only.
  EXPECT_LT(c.relative_error(), 1e-6) << "force " << c.force.transpose() << " moment " << c.moment.transpose();
}

TEST_P(Conformance, BadInputIsNamed) {
  const auto model = make(paper::robot(5));
  const auto ws = model->make_workspace();
  ModelInput in = bent_input();
  in.actuation.values[2] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(field_of([&] { solve(*model, *ws, in); }), "actuation.tensions[2]");
  in = bent_input();
  in.actuation.values[1] = -1.0;
  EXPECT_EQ(field_of([&] { solve(*model, *ws, in); }), "actuation.tensions[1]");
  in = bent_input();
  in.actuation.values.pop_back();
  EXPECT_EQ(field_of([&] { solve(*model, *ws, in); }), "actuation.tensions");
  in = bent_input();
  in.loads.tip_force.x() = std::numeric_limits<double>::infinity();
  EXPECT_EQ(field_of([&] { solve(*model, *ws, in); }), "loads.tip_force[0]");
  if (!can().external_loads) {
    in = bent_input();
    in.loads.tip_force = Vec3(0.1, 0, 0);
    EXPECT_EQ(field_of([&] { solve(*model, *ws, in); }), "loads.tip_force");
  }
  if (!can().displacement_input) {
    in = bent_input();
    in.actuation.kind = Actuation::Kind::Displacements;
    in.actuation.values.assign(4, 0.0);
    EXPECT_EQ(field_of([&] { solve(*model, *ws, in); }), "actuation.displacements");
  }
  // The scene front door: the model name is checked against the registry.
  Scene s = paper::scene(5, 2, info().name);
  EXPECT_NO_THROW(validate_scene(s));
  s.model = std::string(info().name) + "_unknown";
  EXPECT_EQ(field_of([&] { validate_scene(s); }), "model");
}

INSTANTIATE_TEST_SUITE_P(Registry, Conformance, testing::ValuesIn(model_registry()),
                         [](const testing::TestParamInfo<ModelInfo>& p) { return std::string(p.param.name); });

}  // namespace
