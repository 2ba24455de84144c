// Inverse solve (inverse_solve.hpp): targets produced by forward solves are reached from zero
// tensions by every model, the tensions are of minimum norm (antagonistic pulls released), a
// pose target is met where the tendons allow it, an unreachable target fails with its distance,
// bad input names the field.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tdcr/core/error.hpp"
#include "tdcr/core/lie.hpp"
#include "tdcr/core/scene_io.hpp"
#include "tdcr/models/inverse_solve.hpp"
#include "tdcr/models/static_model.hpp"

using namespace tdcr;

namespace {

Scene example(const std::string& name) { return load_scene(std::string(TDCR_EXAMPLES_DIR) + "/" + name); }

// The forward solve of `s` with tensions T.
Solution forward(const StaticModel& model, const Scene& s, const std::vector<double>& T) {
  auto ws = model.make_workspace();
  ModelInput in = s.input();
  in.actuation.values = T;
  return solve(model, *ws, in, s.solver);
}

std::vector<double> random_tensions(std::mt19937& rng, std::size_t m, double max) {
  std::uniform_real_distribution<double> u(0.0, max);
  std::vector<double> T(m);
  for (double& t : T) t = u(rng);
  return T;
}

double norm(const std::vector<double>& T) {
  double s = 0;
  for (double t : T) s += t * t;
  return std::sqrt(s);
}

// Solves for the target from zero tensions and checks the answer: converged, the returned
// Solution's tip at the target (1e-6 m), tensions >= 0 and no larger than the generating ones
// (which reach the target too).
InverseResult reach(const StaticModel& model, const Scene& s, const InverseTarget& target,
                    const std::vector<double>& generating) {
  auto ws = model.make_workspace();
  ModelInput start = s.input();
  start.actuation.values.assign(generating.size(), 0.0);
  const InverseResult r = inverse_solve(model, *ws, start, target, s.solver);
  std::printf("%s: %s\n", model.name().c_str(), r.brief_report().c_str());
  EXPECT_TRUE(r.converged()) << r.brief_report();
  EXPECT_TRUE(r.minimum_norm) << r.brief_report();
  EXPECT_TRUE(r.solution.converged());
  EXPECT_LT((r.solution.tip().p - target.position).norm(), 1e-6);
  EXPECT_LT(r.position_error, 1e-6);
  EXPECT_EQ(r.solution.tensions, r.tensions);
  for (double t : r.tensions) EXPECT_GE(t, 0.0);
  EXPECT_LE(norm(r.tensions), norm(generating) * (1 + 1e-9));
  return r;
}

struct Case {
  ModelKind kind;
  bool loaded;
};

class InverseReachesForwardTargets : public testing::TestWithParam<Case> {};

// The paper robot (examples/paper_robot_vc.json; loaded: paper_robot_tip_force.json, 0.5 N
// along +y at the tip) under seeded random tensions up to 2.5 N (45% of T_M).
TEST_P(InverseReachesForwardTargets, FromZeroTensions) {
  const Case c = GetParam();
  Scene s = example(c.loaded ? "paper_robot_tip_force.json" : "paper_robot_vc.json");
  s.model = to_string(c.kind);
  const auto model = make_model(c.kind, s);
  std::mt19937 rng(14 + static_cast<unsigned>(c.kind));
  for (int trial = 0; trial < 2; ++trial) {
    const std::vector<double> T = random_tensions(rng, 4, 2.5);
    const Solution f = forward(*model, s, T);
    ASSERT_TRUE(f.converged());
    InverseTarget target;
    target.position = f.tip().p;
    reach(*model, s, target, T);
  }
}

INSTANTIATE_TEST_SUITE_P(Models, InverseReachesForwardTargets,
                         testing::Values(Case{ModelKind::CC, false}, Case{ModelKind::CCsub, false},
                                         Case{ModelKind::PRB, false}, Case{ModelKind::VC, false},
                                         Case{ModelKind::VCref, false}, Case{ModelKind::CCsub, true},
                                         Case{ModelKind::PRB, true}, Case{ModelKind::VC, true},
                                         Case{ModelKind::VCref, true}),
                         [](const testing::TestParamInfo<Case>& i) {
                           return to_string(i.param.kind) + (i.param.loaded ? "_Loaded" : "_Unloaded");
                         });

// `segments` segments of 50 mm, 10 disks, 4 tendons each at 90 degrees (8 mm pitch radius),
// inextensible backbone: pulling both tendons of an opposing pair only compresses it.
Scene cross_robot(int segments, ModelKind kind) {
  Scene s = example("paper_robot_vc.json");
  s.robot.segments.resize(static_cast<std::size_t>(segments));
  for (Segment& seg : s.robot.segments)
    seg.tendons = {{0.008, 0.0}, {0.0, 0.008}, {-0.008, 0.0}, {0.0, -0.008}};
  s.effects.shear_extension = false;
  s.model = to_string(kind);
  s.actuation.values.assign(4 * static_cast<std::size_t>(segments), 0.0);
  return s;
}

class InverseMinimumNorm : public testing::TestWithParam<ModelKind> {};

// Generating tensions pull every tendon; the answer pulls at most one tendon of each opposing
// pair, and its norm is smaller. In CC, CCsub and VC the shape depends on the tendon moments
// alone, so the released tendon is exactly slack. In PRB (joint-lumped tendon chords) and VCref
// (discrete disk forces) pulling a pair bends the robot slightly (the tip of this robot at
// T = (1, 0.2, 0, 0) N moves 1.2e-6 m when pair 0 pulls 0.5 N more): the exact target may need a
// trace of the antagonist, bounded here by 1e-3 of its partner.
TEST_P(InverseMinimumNorm, ReleasesAntagonisticPairs) {
  const bool moments_only = GetParam() == ModelKind::CC || GetParam() == ModelKind::CCsub || GetParam() == ModelKind::VC;
  const Scene s = cross_robot(1, GetParam());
  const auto model = make_model(GetParam(), s);
  std::mt19937 rng(90);
  for (int trial = 0; trial < 2; ++trial) {
    std::vector<double> T = random_tensions(rng, 4, 2.0);
    for (double& t : T) t += 0.5;  // every tendon pulls
    const Solution f = forward(*model, s, T);
    ASSERT_TRUE(f.converged());
    InverseTarget target;
    target.position = f.tip().p;
    const InverseResult r = reach(*model, s, target, T);
    ASSERT_EQ(r.tensions.size(), 4u);
    for (std::size_t pair = 0; pair < 2; ++pair) {
      const double low = std::min(r.tensions[pair], r.tensions[pair + 2]);
      const double high = std::max(r.tensions[pair], r.tensions[pair + 2]);
      EXPECT_LE(low, moments_only ? 1e-9 : 1e-3 * high)
          << "pair " << pair << ": " << r.tensions[pair] << ", " << r.tensions[pair + 2];
    }
    EXPECT_LT(norm(r.tensions), norm(T));
  }
}

INSTANTIATE_TEST_SUITE_P(Models, InverseMinimumNorm,
                         testing::Values(ModelKind::CC, ModelKind::CCsub, ModelKind::PRB, ModelKind::VC,
                                         ModelKind::VCref),
                         [](const testing::TestParamInfo<ModelKind>& i) { return to_string(i.param); });

class InversePose : public testing::TestWithParam<ModelKind> {};

// Two segments with 4 tendons each: a tip pose (position and orientation) from a forward solve
// is reached; the position alone is met by other tensions with another orientation.
TEST_P(InversePose, PositionAndOrientation) {
  const Scene s = cross_robot(2, GetParam());
  const auto model = make_model(GetParam(), s);
  std::mt19937 rng(7);
  std::vector<double> T = random_tensions(rng, 8, 2.0);
  for (std::size_t k = 0; k < 2; ++k) T[k] = 0.0;  // segment 1 bends one way, segment 2 another
  T[4 + 2] = T[4 + 3] = 0.0;
  const Solution f = forward(*model, s, T);
  ASSERT_TRUE(f.converged());
  InverseTarget target;
  target.position = f.tip().p;
  target.rotation = lie::log_so3(f.tip().R);
  const InverseResult r = reach(*model, s, target, T);
  EXPECT_LT(r.rotation_error, 1e-6);
  EXPECT_LT(lie::rotation_angle(r.solution.tip().R, f.tip().R), 1e-6);

  InverseTarget position_only = target;
  position_only.rotation.reset();
  const InverseResult p = reach(*model, s, position_only, T);
  EXPECT_EQ(p.rotation_error, 0.0);
  EXPECT_GT(lie::rotation_angle(p.solution.tip().R, f.tip().R), 1e-3);
  EXPECT_LT(norm(p.tensions), norm(r.tensions));
}

INSTANTIATE_TEST_SUITE_P(Models, InversePose, testing::Values(ModelKind::CC, ModelKind::VC),
                         [](const testing::TestParamInfo<ModelKind>& i) { return to_string(i.param); });

// Above the straight robot (tendons can only shorten it) and far to its side: failed, with the
// closest pose found and its distance.
TEST(InverseSolve, UnreachableTargetFailsWithDistance) {
  Scene s = example("paper_robot_vc.json");
  const auto model = make_model(ModelKind::VC, s);
  auto ws = model->make_workspace();
  ModelInput start = s.input();
  start.actuation.values.assign(4, 0.0);
  for (const Vec3& p : {Vec3(0.0, 0.0, 0.3), Vec3(0.0, 0.5, 0.0)}) {
    InverseTarget target;
    target.position = p;
    InverseOptions o;
    o.max_iterations = 40;
    const InverseResult r = inverse_solve(*model, *ws, start, target, s.solver, o);
    std::printf("target (%g, %g, %g): %s\n", p.x(), p.y(), p.z(), r.brief_report().c_str());
    EXPECT_FALSE(r.converged());
    EXPECT_NE(r.status, InverseStatus::ForwardFailed);
    ASSERT_TRUE(r.solution.converged());
    EXPECT_NEAR(r.position_error, (r.solution.tip().p - p).norm(), 1e-15);
    EXPECT_GT(r.position_error, 0.1);  // at least the distance to the robot's reach (0.1 m)
    EXPECT_LE(r.iterations, o.max_iterations);
    EXPECT_NE(r.brief_report().find(to_string(r.status)), std::string::npos);
  }
  // Straight up: zero tensions are the closest, and the distance is exactly 0.3 - 0.1 m.
  InverseTarget up;
  up.position = Vec3(0, 0, 0.3);
  const InverseResult r = inverse_solve(*model, *ws, start, up, s.solver);
  EXPECT_EQ(r.status, InverseStatus::Unreachable);
  EXPECT_NEAR(r.position_error, 0.2, 1e-12);
}

TEST(InverseSolve, BadInputNamesTheField) {
  Scene s = example("paper_robot_vc.json");
  const auto model = make_model(ModelKind::CC, s);
  auto ws = model->make_workspace();
  const ModelInput start = s.input();
  InverseTarget t;
  t.position = Vec3(0, std::nan(""), 0.1);
  try {
    inverse_solve(*model, *ws, start, t, s.solver);
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "target.position[1]");
    EXPECT_EQ(e.value(), "nan");
  }
  t.position = Vec3(0, 0, 0.1);
  t.rotation = Vec3(0, INFINITY, 0);
  EXPECT_THROW(inverse_solve(*model, *ws, start, t, s.solver), InputError);
  t.rotation.reset();
  InverseOptions o;
  o.position_tolerance = 0;
  try {
    inverse_solve(*model, *ws, start, t, s.solver, o);
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "inverse.position_tolerance");
  }
  ModelInput displaced = start;
  displaced.actuation.kind = Actuation::Kind::Displacements;
  try {
    inverse_solve(*model, *ws, displaced, t, s.solver);
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "actuation");
  }
}

}  // namespace
