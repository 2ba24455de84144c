// Displacement input for the static models (CCsub, PRB, VC, VCref): the tensions of the
// displacement-driven tendons as unknowns, slack tendons, mixed input, elastic tendons.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tdcr/core/error.hpp"
#include "tdcr/core/paper_robot.hpp"
#include "tdcr/core/scene_io.hpp"
#include "tdcr/models/model_registry.hpp"
#include "tdcr/models/static_model.hpp"
#include "fixed_mesh_settings.hpp"

using namespace tdcr;

namespace {

using K = Actuation::Kind;

// Every tendon by tension.
ModelInput tension_input(const std::vector<double>& t, const Loads& loads = {}) {
  ModelInput in;
  in.actuation.values = t;
  in.loads = loads;
  return in;
}

// The displacements of `sol` for the tendons of `kinds` (Displacements), the tensions for the others.
ModelInput from_solution(const Solution& sol, const std::vector<K>& kinds, const Loads& loads) {
  ModelInput in;
  in.loads = loads;
  in.actuation.kind = K::Displacements;
  bool mixed = false;
  for (std::size_t k = 0; k < kinds.size(); ++k) {
    const bool d = kinds[k] == K::Displacements;
    in.actuation.values.push_back(d ? sol.tendon_displacements[k] : sol.tensions[k]);
    mixed = mixed || !d;
  }
  if (mixed) in.actuation.kinds = kinds;
  return in;
}

double max_relative(const std::vector<double>& a, const std::vector<double>& b) {
  double scale = 0.0, diff = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    scale = std::max(scale, std::abs(b[k]));
    diff = std::max(diff, std::abs(a[k] - b[k]));
  }
  return diff / scale;
}

Loads tip_load() {
  Loads l;
  l.tip_force = Vec3(0.2, -0.1, -0.3);
  return l;
}

const std::vector<K> kAllDisplaced(4, K::Displacements);
const std::vector<K> kMixed = {K::Displacements, K::Tensions, K::Displacements, K::Tensions};
// Tendons 1 and 4 pulled, their antagonists without tension.
const std::vector<double> kPulled = {2.0, 0.0, 1.5, 0.0};

class DisplacementInput : public ::testing::TestWithParam<ModelKind> {
 protected:
  // The paper robot, 5 disks per segment (10: VC, whose cost does not grow with them).
  std::unique_ptr<StaticModel> model(const Robot& robot) const { return make_model(GetParam(), robot, Effects{}); }
  Robot robot() const { return paper::robot(GetParam() == ModelKind::VC ? 10 : 5); }

  // Solve by tension, feed the answer's displacements back (tendons without tension let out by
  // `let_out` beyond their path: slack), expect the tensions to 1e-8 and the slack tendons.
  void expect_round_trip(const Robot& r, const std::vector<double>& t, const Loads& loads, const std::vector<K>& kinds,
                         double let_out = 1e-3) const {
    const auto m = model(r);
    const auto ws = m->make_workspace();
    const Solution ref = solve(*m, *ws, tension_input(t, loads), test::fixed_mesh_settings());
    ASSERT_TRUE(ref.converged()) << ref.summary.brief_report();
    EXPECT_TRUE(ref.tendon_slack.empty());
    ModelInput in = from_solution(ref, kinds, loads);
    for (std::size_t k = 0; k < t.size(); ++k)
      if (kinds[k] == K::Displacements && t[k] == 0.0) in.actuation.values[k] -= let_out;
    const Solution back = solve(*m, *ws, in, test::fixed_mesh_settings());
    ASSERT_TRUE(back.converged()) << back.summary.message;
    EXPECT_LT(max_relative(back.tensions, t), 1e-8) << back.summary.message;
    EXPECT_LT((back.tip().p - ref.tip().p).norm(), 1e-9);
    ASSERT_EQ(back.tendon_slack.size(), t.size());
    for (std::size_t k = 0; k < t.size(); ++k) {
      EXPECT_EQ(back.tendon_slack[k], kinds[k] == K::Displacements && t[k] == 0.0) << "tendon " << k;
      if (back.tendon_slack[k]) {
        EXPECT_EQ(back.tensions[k], 0.0);
      }
    }
    EXPECT_GT(back.summary.iterations, 0);
    // Unknowns: the model's with every driven tendon acting, and one tension per driven tendon.
    std::vector<double> acting = t;
    for (std::size_t k = 0; k < t.size(); ++k)
      if (kinds[k] == K::Displacements) acting[k] = 1.0;
    const Solution all = solve(*m, *ws, tension_input(acting, loads), test::fixed_mesh_settings());
    EXPECT_EQ(back.summary.unknowns,
              all.summary.unknowns + static_cast<int>(std::count(kinds.begin(), kinds.end(), K::Displacements)));
  }
};

// Every tendon by displacement; the unpulled ones let out 1 mm beyond their paths: slack.
TEST_P(DisplacementInput, DisplacementsOfATensionSolveGiveTheTensionsBack) {
  expect_round_trip(robot(), kPulled, Loads{}, kAllDisplaced);
}

TEST_P(DisplacementInput, LoadedRoundTrip) { expect_round_trip(robot(), kPulled, tip_load(), kAllDisplaced); }

// The paper robot example (examples/paper_robot_vc.json, T1 = T_M, the rest at zero).
TEST_P(DisplacementInput, PaperRobotExample) {
  const Scene s = load_scene(std::string(TDCR_EXAMPLES_DIR) + "/paper_robot_vc.json");
  Robot r = s.robot;
  if (GetParam() != ModelKind::VC)
    for (Segment& seg : r.segments) seg.disks = 5;
  expect_round_trip(r, s.actuation.values, Loads{}, kAllDisplaced);
}

// Antagonists by tension (co-contraction), the others by displacement.
TEST_P(DisplacementInput, MixedInput) { expect_round_trip(robot(), {2.0, 0.5, 1.5, 0.3}, tip_load(), kMixed); }

// Tendon 2 commanded 1 mm below the pull of its path at zero tension: slack, T = 0, and the rest
// is the tension solve with that tension 0 (tendons 3 and 4 by tension).
TEST_P(DisplacementInput, SlackTendon) {
  const auto m = model(robot());
  const auto ws = m->make_workspace();
  const Solution ref = solve(*m, *ws, tension_input({2.0, 0.0, 1.5, 0.3}, tip_load()), test::fixed_mesh_settings());
  ASSERT_TRUE(ref.converged());
  ModelInput in = from_solution(ref, {K::Displacements, K::Displacements, K::Tensions, K::Tensions}, tip_load());
  in.actuation.values[1] -= 1e-3;
  const Solution sol = solve(*m, *ws, in, test::fixed_mesh_settings());
  ASSERT_TRUE(sol.converged()) << sol.summary.message;
  EXPECT_EQ(sol.tensions[1], 0.0);
  EXPECT_TRUE(sol.tendon_slack[1]);
  EXPECT_FALSE(sol.tendon_slack[0]);
  EXPECT_LT(max_relative(sol.tensions, ref.tensions), 1e-8);
  EXPECT_NE(sol.summary.message.find("slack: 1"), std::string::npos) << sol.summary.message;
  // The slack tendon's path pulls more than commanded (it has length to spare).
  EXPECT_NEAR(sol.tendon_displacements[1], in.actuation.values[1] + 1e-3, 1e-9);
}

// A warm start from a previous displacement solve starts at its unknowns and tensions.
TEST_P(DisplacementInput, WarmStart) {
  const auto m = model(robot());
  const auto ws = m->make_workspace();
  const Solution ref = solve(*m, *ws, tension_input(kPulled), test::fixed_mesh_settings());
  ModelInput in = from_solution(ref, kAllDisplaced, Loads{});
  in.actuation.values[1] -= 1e-3;
  in.actuation.values[3] -= 1e-3;
  const Solution cold = solve(*m, *ws, in, test::fixed_mesh_settings());
  ASSERT_TRUE(cold.converged()) << cold.summary.message;
  in.actuation.values[0] += 1e-5;
  const Solution warm = solve(*m, *ws, in, test::fixed_mesh_settings(), &cold);
  ASSERT_TRUE(warm.converged()) << warm.summary.message;
  // From the previous answer and its Jacobian (modified Newton): no new Jacobian (the costly
  // part, a Jacobian of the tensions' border is one residual per driven tendon and one pull per
  // unknown), at most one more iteration than the cold solve took with fresh ones.
  EXPECT_LT(warm.summary.jacobian_evaluations, cold.summary.jacobian_evaluations);
  EXPECT_LE(warm.summary.iterations, cold.summary.iterations + 1);
  EXPECT_GT(warm.tensions[0], cold.tensions[0]);
}

// Elastic tendon 1: a stiff one gives the inextensible answer (error falling as 1 / EA); a soft
// one's tension is EA / L times its stretch; let out beyond its path it is slack.
TEST_P(DisplacementInput, ElasticTendons) {
  Robot r = robot();
  const auto rigid = model(r);
  const auto ws0 = rigid->make_workspace();
  const Solution ref = solve(*rigid, *ws0, tension_input(kPulled), test::fixed_mesh_settings());
  ModelInput in = from_solution(ref, kAllDisplaced, Loads{});
  in.actuation.values[1] -= 1e-3;
  in.actuation.values[3] -= 1e-3;
  const double l_free = r.segments[0].length;  // tendon 1 ends at segment 1's end

  double error[2];
  for (int i = 0; i < 2; ++i) {
    r.segments[0].tendons[0].stiffness = i == 0 ? 1e7 : 1e9;  // N: stretch 1e-8 m, 1e-10 m at 2 N
    const auto stiff = model(r);
    const auto ws = stiff->make_workspace();
    const Solution s = solve(*stiff, *ws, in, test::fixed_mesh_settings());
    ASSERT_TRUE(s.converged()) << s.summary.message;
    EXPECT_LT(s.tensions[0], ref.tensions[0]);  // a stretching tendon pulls less
    error[i] = max_relative(s.tensions, ref.tensions);
  }
  EXPECT_LT(error[1], 1e-6);
  EXPECT_NEAR(error[0] / error[1], 100.0, 5.0);

  r.segments[0].tendons[0].stiffness = 200.0;  // N: stretch ~ 0.5 mm at 2 N
  const auto soft = model(r);
  const auto ws2 = soft->make_workspace();
  const Solution s2 = solve(*soft, *ws2, in, test::fixed_mesh_settings());
  ASSERT_TRUE(s2.converged()) << s2.summary.message;
  // The motor sets the commanded pull: the path's pull plus the tendon's stretch. The path's
  // pull at these tensions is the inextensible tendon's (a tension solve of the rigid model).
  EXPECT_NEAR(s2.tendon_displacements[0], in.actuation.values[0], 1e-12);
  const Solution path = solve(*rigid, *ws0, tension_input(s2.tensions), test::fixed_mesh_settings());
  ASSERT_TRUE(path.converged());
  const double stretch = in.actuation.values[0] - path.tendon_displacements[0];
  EXPECT_GT(stretch, 1e-4);
  EXPECT_NEAR(s2.tensions[0], 200.0 / l_free * stretch, 1e-8 * s2.tensions[0]);
  EXPECT_LT(s2.tensions[0], 0.9 * ref.tensions[0]);
  EXPECT_FALSE(s2.tendon_slack[0]);

  ModelInput slack = in;
  slack.actuation.values[0] = -1e-3;  // let out: the soft tendon has slack
  const Solution s3 = solve(*soft, *ws2, slack, test::fixed_mesh_settings());
  ASSERT_TRUE(s3.converged()) << s3.summary.message;
  EXPECT_EQ(s3.tensions[0], 0.0);
  EXPECT_TRUE(s3.tendon_slack[0]);
}

// A helically routed elastic tendon: its free length is the helix's, L sqrt(1 + (rho phi')^2),
// not the segments' (a quarter turn over the two segments), so its tension is EA / L_helix times the stretch of its routed path.
TEST_P(DisplacementInput, ElasticHelicalTendonStretchesOverTheHelixLength) {
  Robot r = robot();
  TendonSpec& t = r.segments[1].tendons[0];
  t.routing.type = TendonRoutingSpec::Type::Helical;
  t.routing.turns = 0.25;
  t.stiffness = 200.0;  // N
  const auto m = model(r);
  const auto ws = m->make_workspace();
  const Solution ref = solve(*m, *ws, tension_input({0.0, 0.0, 1.5, 0.0}), test::fixed_mesh_settings());
  ASSERT_TRUE(ref.converged()) << ref.summary.brief_report();
  std::vector<K> kinds(4, K::Tensions);
  kinds[2] = K::Displacements;
  ModelInput in = from_solution(ref, kinds, Loads{});
  in.actuation.values[2] += 1e-3;  // 1 mm more than the inextensible answer's pull
  const Solution s = solve(*m, *ws, in, test::fixed_mesh_settings());
  ASSERT_TRUE(s.converged()) << s.summary.message;
  const double L = r.total_length(), rho = std::hypot(t.x, t.y), rate = 2.0 * 3.14159265358979323846 * 0.25 / L;
  const double l_free = L * std::hypot(1.0, rho * rate);
  // The path's pull at the answer's tensions: the same routing, inextensible.
  Robot rigid_robot = r;
  rigid_robot.segments[1].tendons[0].stiffness.reset();
  const auto rigid = model(rigid_robot);
  const auto ws_rigid = rigid->make_workspace();
  const Solution path = solve(*rigid, *ws_rigid, tension_input(s.tensions), test::fixed_mesh_settings());
  ASSERT_TRUE(path.converged());
  EXPECT_NEAR(s.tendon_displacements[2], in.actuation.values[2], 1e-12);
  const double stretch = in.actuation.values[2] - path.tendon_displacements[2];
  EXPECT_GT(stretch, 1e-4);
  EXPECT_NEAR(s.tensions[2], 200.0 / l_free * stretch, 1e-8 * s.tensions[2]);
  EXPECT_GT(std::abs(s.tensions[2] - 200.0 / L * stretch), 1e-3 * s.tensions[2]);  // the helix length matters
}

// A solve cut short says so: failed, with its iterations and residual.
TEST_P(DisplacementInput, NonConvergenceIsReported) {
  const auto m = model(robot());
  const auto ws = m->make_workspace();
  const Solution ref = solve(*m, *ws, tension_input({2.0, 0.5, 1.5, 0.3}, tip_load()), test::fixed_mesh_settings());
  SolverOptions o;
  o.max_iterations = 1;
  o.continuation = false;
  const Solution sol = solve(*m, *ws, from_solution(ref, kMixed, tip_load()), o);
  EXPECT_FALSE(sol.converged());
  EXPECT_GT(sol.summary.iterations, 0);
  EXPECT_GT(sol.summary.residual_norm, sol.summary.function_tolerance);
  EXPECT_NE(sol.summary.message.find("displacement input"), std::string::npos) << sol.summary.message;
}

INSTANTIATE_TEST_SUITE_P(StaticModels, DisplacementInput,
                         ::testing::Values(ModelKind::CCsub, ModelKind::PRB, ModelKind::VC, ModelKind::VCref),
                         [](const auto& info) { return to_string(info.param); });

// Loaded scenes a user drove by displacement (default options, cold solves): the displacements
// of a tension solve give its tensions back to 1e-8 T_M and its tip to 1e-9 m in every static
// model. T_M is the paper robot's tension of Eq. 55 at E = 2.11e11 Pa (5.5533 N).
class DisplacementInputLoaded : public ::testing::TestWithParam<ModelKind> {
 protected:
  void expect_round_trip(const Robot& r, const std::vector<double>& t, const Vec3& tip_force,
                         const std::vector<K>& kinds = kAllDisplaced) const {
    const double tm = paper::max_tension(paper::robot(10));
    const auto m = make_model(GetParam(), r, Effects{});
    const auto ws = m->make_workspace();
    Loads loads;
    loads.tip_force = tip_force;
    const Solution ref = solve(*m, *ws, tension_input(t, loads), test::fixed_mesh_settings());
    ASSERT_TRUE(ref.converged()) << ref.summary.brief_report();
    const Solution back = solve(*m, *ws, from_solution(ref, kinds, loads), test::fixed_mesh_settings());
    ASSERT_TRUE(back.converged()) << back.summary.message;
    EXPECT_LT((back.tip().p - ref.tip().p).norm(), 1e-9);
    for (std::size_t k = 0; k < t.size(); ++k) {
      EXPECT_NEAR(back.tensions[k], ref.tensions[k], 1e-8 * tm) << "tendon " << k << "; " << back.summary.message;
      if (back.tendon_slack[k]) {
        EXPECT_EQ(back.tensions[k], 0.0) << "a slack tendon carries no tension";
      }
    }
  }
};

// The soft robot (E x 0.25, 20 disks per segment) bent by T1 = T_M under a compressive tip force
// of 0.3 N, above the straight column's buckling load (about 0.26 N).
TEST_P(DisplacementInputLoaded, SoftRobotUnderCompression) {
  const double tm = paper::max_tension(paper::robot(10));
  expect_round_trip(paper::robot(20, 0.25), {tm, 0.0, 0.0, 0.0}, Vec3(0.0, 0.0, -0.3));
}

// The paper robot at 20 disks, T = (2, 1, 0, 0) N (co-contraction on segment 1, which the
// displacements decide only through the tip force), tip force (0.1, 0.1, 0.1) N.
TEST_P(DisplacementInputLoaded, CoContractionUnderATipForce) {
  expect_round_trip(paper::robot(20), {2.0, 1.0, 0.0, 0.0}, Vec3(0.1, 0.1, 0.1));
}

// The soft robot with T1 = 1 N and the 0.3 N compressive tip force.
TEST_P(DisplacementInputLoaded, SoftRobotPastItsBucklingLoad) {
  expect_round_trip(paper::robot(20, 0.25), {1.0, 0.0, 0.0, 0.0}, Vec3(0.0, 0.0, -0.3));
}

// Mixed input on a soft robot (E x 0.1, 15 disks per segment, tip force (0.3, -0.3, 0.1) N): T1,
// T2 and T4 by tension, T3 by displacement.
TEST_P(DisplacementInputLoaded, MixedInputOnASoftRobot) {
  expect_round_trip(paper::robot(15, 0.1), {1.0, 0.3, 0.5, 0.0}, Vec3(0.3, -0.3, 0.1),
                    {K::Tensions, K::Tensions, K::Displacements, K::Tensions});
}

// Pulls past the geometric limit: 0.1 m on T1 and T3 (the robot is 0.1 m long), the others let
// out. Named infeasible, the tendon given.
TEST_P(DisplacementInputLoaded, PullsLongerThanThePathAreInfeasible) {
  const auto m = make_model(GetParam(), paper::robot(10), Effects{});
  const auto ws = m->make_workspace();
  ModelInput in;
  in.actuation.kind = K::Displacements;
  in.actuation.values = {0.1, -0.1, 0.1, -0.1};
  const Solution s = solve(*m, *ws, in, test::fixed_mesh_settings());
  EXPECT_EQ(s.summary.termination, TerminationType::Infeasible) << s.summary.message;
  EXPECT_NE(s.summary.message.find("tendon T1"), std::string::npos) << s.summary.message;
  ASSERT_FALSE(s.disk_frames.empty());  // the robot at rest, a shape to show
}

// Pulls at the edge of the geometric limit: T1 pulled 49.5, 49.7 and 49.9 mm on segment 1 (50 mm
// long; at curvature x offset 1 a fully constrained path gives 50 mm), T2 let out as much. Each
// model either converges with no tendon past its limit or names T1 infeasible: never a numerical
// failure (PRB, whose 3R links reach T1's limit before these pulls, ended line_search_failed).
TEST_P(DisplacementInputLoaded, PullsAtTheGeometricLimitConvergeOrAreNamed) {
  const auto m = make_model(GetParam(), paper::robot(10), Effects{});
  const auto ws = m->make_workspace();
  for (double pull : {0.0495, 0.0497, 0.0499}) {
    ModelInput in;
    in.actuation.kind = K::Displacements;
    in.actuation.values = {pull, -pull, 0.0, 0.0};
    const Solution s = solve(*m, *ws, in, test::fixed_mesh_settings());
    if (s.converged()) {
      EXPECT_TRUE(s.geometry_warnings.empty() || s.geometry_warnings.front().what.find("limit") != std::string::npos)
          << pull << ": " << s.geometry_warnings.front().what;
      EXPECT_NEAR(s.tendon_displacements[0], pull, 1e-12);
    } else {
      EXPECT_EQ(s.summary.termination, TerminationType::Infeasible) << pull << ": " << s.summary.message;
      EXPECT_NE(s.summary.message.find("tendon T1"), std::string::npos) << s.summary.message;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(StaticModels, DisplacementInputLoaded,
                         ::testing::Values(ModelKind::CCsub, ModelKind::PRB, ModelKind::VC, ModelKind::VCref),
                         [](const auto& info) { return to_string(info.param); });

std::string field_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.field();
  }
  return "";
}

// CC stays kinematic: it refuses mixed input and elastic tendons under displacement input.
TEST(DisplacementInputCc, RefusesMixedInputAndElasticTendons) {
  Robot r = paper::robot(5);
  const auto cc = make_model(ModelKind::CC, r, Effects{});
  const auto ws = cc->make_workspace();
  ModelInput in;
  in.actuation.kind = K::Displacements;
  in.actuation.values = {0.001, 1.0, 0.0, 0.0};
  in.actuation.kinds = {K::Displacements, K::Tensions, K::Displacements, K::Displacements};
  EXPECT_EQ(field_of([&] { solve(*cc, *ws, in, test::fixed_mesh_settings()); }), "actuation");
  r.segments[1].tendons[0].stiffness = 100.0;
  const auto elastic = make_model(ModelKind::CC, r, Effects{});
  const auto ws2 = elastic->make_workspace();
  in.actuation.kinds.clear();
  EXPECT_EQ(field_of([&] { solve(*elastic, *ws2, in, test::fixed_mesh_settings()); }), "robot.segments[1].tendons[0].stiffness");
  in.actuation.kind = K::Tensions;  // tensions: the stiffness plays no role
  EXPECT_TRUE(solve(*elastic, *ws2, in, test::fixed_mesh_settings()).converged());
}

// Scene files: mixed input is both lists with null where the other gives the tendon; it
// round-trips through scene_to_json.
TEST(DisplacementInputScene, MixedListsRoundTrip) {
  Scene s = paper::scene(5, 2, "vc");
  s.actuation.kind = K::Displacements;
  s.actuation.kinds = {K::Displacements, K::Tensions, K::Tensions, K::Displacements};
  s.actuation.values = {0.002, 0.5, 0.0, -0.001};
  s.robot.segments[1].tendons[1].stiffness = 350.0;
  const std::string text = scene_to_json(s);
  EXPECT_NE(text.find("null"), std::string::npos) << text;
  const Scene back = parse_scene(text);
  EXPECT_EQ(back.actuation.kinds, s.actuation.kinds);
  EXPECT_EQ(back.actuation.values, s.actuation.values);
  EXPECT_EQ(back.actuation.kind, K::Displacements);
  ASSERT_TRUE(back.robot.segments[1].tendons[1].stiffness.has_value());
  EXPECT_EQ(*back.robot.segments[1].tendons[1].stiffness, 350.0);
  EXPECT_FALSE(back.robot.segments[0].tendons[0].stiffness.has_value());
}

}  // namespace
