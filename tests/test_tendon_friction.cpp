// Tests of capstan tendon friction (Effects::tendon_friction, docs/models.md "Tendon friction"):
// off costs nothing and changes nothing, the capstan law on a planar bend, hysteresis between
// pulling and releasing, the models that refuse it, and its scene-file and JSON forms.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "tdcr/core/error.hpp"
#include "tdcr/core/paper_robot.hpp"
#include "tdcr/core/scene_io.hpp"
#include "tdcr/models/ccsub.hpp"
#include "tdcr/models/model_registry.hpp"
#include "tdcr/models/static_model.hpp"

using namespace tdcr;

namespace {

const ModelKind kDiscrete[] = {ModelKind::CCsub, ModelKind::PRB, ModelKind::VCref};

Solution solve_with(ModelKind kind, const Robot& robot, const Effects& effects, const std::vector<double>& T) {
  const auto model = make_model(kind, robot, effects);
  auto ws = model->make_workspace();
  ModelInput in;
  in.actuation.values = T;
  return tdcr::solve(*model, *ws, in, SolverOptions{}, nullptr);
}

// One segment of the paper robot (50 mm, 8 mm pitch radius) with a single tendon at +y.
Robot one_tendon_robot(int disks) {
  Robot r = paper::robot(disks);
  r.segments.resize(1);
  r.segments[0].tendons.resize(1);
  return r;
}

Effects friction(double mu, TendonFriction::Motion motion) {
  Effects e = paper::effects("vcref");  // paper::scene(..., "vcref")'s, whose answers these compare with
  e.tendon_friction.coefficient = mu;
  e.tendon_friction.motion = motion;
  return e;
}

// Angle between the base axis and the tip disk's axis (rad).
double bend(const Solution& s) { return std::acos(std::min(1.0, s.disk_frames.back().R(2, 2))); }

// Angle between the base axis z and the tendon's last chord: for a planar bend (all turns the
// same way) the tendon's total turning angle.
double wrap_angle(const Solution& s, const Vec3& r) {
  const std::size_t n = s.disk_frames.size();
  const Frame& a = s.disk_frames[n - 2];
  const Frame& b = s.disk_frames[n - 1];
  const Vec3 chord = (b.p + b.R * r - a.p - a.R * r).normalized();
  return std::atan2(Vec3::UnitZ().cross(chord).norm(), chord.z());
}

}  // namespace

// Friction off (absent, zero coefficient, zero per-tendon coefficients, either motion) is
// today's code path: the same answer to the last bit, for every model.
TEST(TendonFriction, ZeroCoefficientIsTodaysAnswer) {
  const Scene base = paper::scene(5, 6, "vcref");
  for (const ModelInfo& info : model_registry()) {
    const Solution ref = solve_with(info.kind, base.robot, base.effects, base.actuation.values);
    ASSERT_TRUE(ref.summary.converged()) << info.name;
    Effects zero = friction(0.0, TendonFriction::Motion::Releasing);
    zero.tendon_friction.coefficients.assign(base.robot.tendon_count(), 0.0);
    const Solution off = solve_with(info.kind, base.robot, zero, base.actuation.values);
    ASSERT_TRUE(off.summary.converged()) << info.name;
    EXPECT_EQ((off.disk_frames.back().p - ref.disk_frames.back().p).norm(), 0.0) << info.name;
    EXPECT_TRUE(off.tendon_end_tensions.empty()) << info.name;
  }
}

// A vanishing coefficient through the friction code path converges to the frictionless answer:
// the chord-tension disk forces reduce to Eq. 30-33.
TEST(TendonFriction, TinyCoefficientApproachesFrictionless) {
  const Scene base = paper::scene(5, 6, "vcref");
  for (ModelKind kind : kDiscrete) {
    const Solution ref = solve_with(kind, base.robot, base.effects, base.actuation.values);
    const Solution tiny = solve_with(kind, base.robot, friction(1e-9, TendonFriction::Motion::Pulling),
                                     base.actuation.values);
    ASSERT_TRUE(tiny.summary.converged()) << to_string(kind);
    EXPECT_LT((tiny.disk_frames.back().p - ref.disk_frames.back().p).norm(), 1e-9) << to_string(kind);
    ASSERT_EQ(tiny.tendon_end_tensions.size(), 4u);
    for (int k = 0; k < 4; ++k)
      EXPECT_NEAR(tiny.tendon_end_tensions[k], base.actuation.values[k], 1e-8) << to_string(kind) << " tendon " << k;
  }
}

// Capstan law: a single tendon bends one segment in a plane; its end tension is the base
// tension times exp(-/+ mu theta), theta the total turning angle of the tendon on the converged
// shape (from the base axis to its last chord). Pulling bends less than frictionless, releasing
// more.
TEST(TendonFriction, CapstanLawOnAPlanarBend) {
  const Robot robot = one_tendon_robot(8);
  const double T0 = 5.0, mu = 0.3;
  const Vec3 r(robot.segments[0].tendons[0].x, robot.segments[0].tendons[0].y, 0.0);
  for (ModelKind kind : kDiscrete) {
    const Solution free = solve_with(kind, robot, Effects(), {T0});
    const Solution pull = solve_with(kind, robot, friction(mu, TendonFriction::Motion::Pulling), {T0});
    const Solution rel = solve_with(kind, robot, friction(mu, TendonFriction::Motion::Releasing), {T0});
    ASSERT_TRUE(free.summary.converged() && pull.summary.converged() && rel.summary.converged()) << to_string(kind);
    const double th_pull = wrap_angle(pull, r), th_rel = wrap_angle(rel, r);
    EXPECT_GT(th_pull, 0.3) << to_string(kind);  // a real bend
    ASSERT_EQ(pull.tendon_end_tensions.size(), 1u);
    EXPECT_NEAR(pull.tendon_end_tensions[0], T0 * std::exp(-mu * th_pull), 1e-9 * T0) << to_string(kind);
    EXPECT_NEAR(rel.tendon_end_tensions[0], T0 * std::exp(mu * th_rel), 1e-9 * T0) << to_string(kind);
    EXPECT_LT(bend(pull), 0.95 * bend(free)) << to_string(kind);
    EXPECT_GT(bend(rel), 1.05 * bend(free)) << to_string(kind);
  }
}

// Hysteresis: pull the tendon up to 4 N and release it from 6 N back through the same tensions,
// warm starting each step from the previous one of the same direction. At 4 N both directions
// converge to different shapes, the released robot bent more.
TEST(TendonFriction, LoadingAndUnloadingDiffer) {
  const Robot robot = one_tendon_robot(6);
  for (ModelKind kind : kDiscrete) {
    const auto pulling = make_model(kind, robot, friction(0.2, TendonFriction::Motion::Pulling));
    const auto releasing = make_model(kind, robot, friction(0.2, TendonFriction::Motion::Releasing));
    auto walk = [](const StaticModel& m, const std::vector<double>& path) {
      auto ws = m.make_workspace();
      Solution s;
      for (double T : path) {
        ModelInput in;
        in.actuation.values = {T};
        s = tdcr::solve(m, *ws, in, SolverOptions{}, s.summary.converged() ? &s : nullptr);
        EXPECT_TRUE(s.summary.converged()) << m.name() << " at T = " << T;
      }
      return s;
    };
    const Solution up = walk(*pulling, {1.0, 2.0, 3.0, 4.0});
    const Solution down = walk(*releasing, {6.0, 5.0, 4.0});
    EXPECT_GT((up.disk_frames.back().p - down.disk_frames.back().p).norm(), 1e-3) << to_string(kind);
    EXPECT_GT(bend(down), 1.1 * bend(up)) << to_string(kind);
  }
}

// A tendon through two segments: friction acts at every hole on its way (both segments), and
// the models that place the tendon forces at the disks agree on the end tension.
TEST(TendonFriction, TwoSegmentsModelsAgree) {
  const Scene s = paper::scene(10, 5, "vcref");  // T3 = T_M: through both segments
  const Effects e = friction(0.1, TendonFriction::Motion::Pulling);
  const Solution ref = solve_with(ModelKind::VCref, s.robot, e, s.actuation.values);
  const Solution sub = solve_with(ModelKind::CCsub, s.robot, e, s.actuation.values);
  ASSERT_TRUE(ref.summary.converged() && sub.summary.converged());
  const double T0 = s.actuation.values[2];
  ASSERT_GT(T0, 0.0);
  EXPECT_LT(ref.tendon_end_tensions[2], 0.95 * T0);
  EXPECT_NEAR(sub.tendon_end_tensions[2], ref.tendon_end_tensions[2], 0.02 * T0);
  EXPECT_LT((sub.disk_frames.back().p - ref.disk_frames.back().p).norm(), 0.02 * s.robot.total_length());
}

// CC (kinematic) refuses a nonzero coefficient, naming the field; the automatic choice then
// takes a model that simulates friction (VC's tests: test_vc_friction.cpp).
TEST(TendonFriction, ModelsWithoutFrictionRefuseIt) {
  Scene s = paper::scene(5, 2, "cc");
  s.effects.tendon_friction.coefficients = {0.0, 0.0, 0.1, 0.0};
  try {
    make_model(ModelKind::CC, s.robot, s.effects);
    ADD_FAILURE() << "cc accepted tendon friction";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "effects.tendon_friction") << e.what();
  }
  EXPECT_FALSE(model_info(ModelKind::CC).capabilities.tendon_friction);
  s.model = "auto";
  const Solution a = solve(s);
  EXPECT_TRUE(a.summary.converged());
  EXPECT_NE(a.model, "cc");
  for (const ModelInfo& m : model_registry())
    if (m.name == a.model) {
      EXPECT_TRUE(m.capabilities.tendon_friction) << a.model;
    }
}

// The coefficient and motion are part of the model: different fingerprints, no warm start
// across them; the end tensions are in the JSON answer only with friction on.
TEST(TendonFriction, FingerprintAndJson) {
  const Scene s = paper::scene(5, 2, "ccsub");
  const auto a = make_model(ModelKind::CCsub, s.robot, friction(0.1, TendonFriction::Motion::Pulling));
  const auto b = make_model(ModelKind::CCsub, s.robot, friction(0.2, TendonFriction::Motion::Pulling));
  const auto c = make_model(ModelKind::CCsub, s.robot, friction(0.1, TendonFriction::Motion::Releasing));
  const auto off = make_model(ModelKind::CCsub, s.robot, Effects());
  EXPECT_NE(a->fingerprint(), b->fingerprint());
  EXPECT_NE(a->fingerprint(), c->fingerprint());
  EXPECT_NE(a->fingerprint(), off->fingerprint());
  auto ws = a->make_workspace();
  const Solution sol = tdcr::solve(*a, *ws, s.input(), s.solver, nullptr);
  ASSERT_TRUE(sol.summary.converged());
  EXPECT_NE(solution_to_json(sol).find("\"tendon_end_tensions\""), std::string::npos);
  auto ws_off = off->make_workspace();
  EXPECT_THROW(tdcr::solve(*off, *ws_off, s.input(), s.solver, &sol), InputError);
  const Solution plain = tdcr::solve(*off, *ws_off, s.input(), s.solver, nullptr);
  EXPECT_EQ(solution_to_json(plain).find("\"tendon_end_tensions\""), std::string::npos);
}

// The lumped models' banded formulation reads neighbouring disks only: friction refuses it
// (Automatic then stays recursive).
TEST(TendonFriction, BandedFormulationRefused) {
  const Scene s = paper::scene(5, 2, "ccsub");
  const Effects e = friction(0.1, TendonFriction::Motion::Pulling);
  try {
    CcsubModel m(s.robot, e, LumpedFormulation::Banded);
    ADD_FAILURE() << "banded formulation accepted with friction";
  } catch (const InputError& err) {
    EXPECT_EQ(err.field(), "effects.tendon_friction");
  }
  const CcsubModel automatic(s.robot, e, LumpedFormulation::Automatic);
  auto ws = automatic.make_workspace();
  EXPECT_TRUE(tdcr::solve(automatic, *ws, s.input(), s.solver, nullptr).summary.converged());
}

// Bad coefficients are named by Scene::validate.
TEST(TendonFriction, ScenePartsValidate) {
  Scene s = paper::scene(5, 2, "ccsub");
  s.effects.tendon_friction.coefficient = std::nan("");
  EXPECT_THROW(s.validate(), InputError);
  s.effects.tendon_friction.coefficient = 0.1;
  s.effects.tendon_friction.coefficients = {0.1};
  try {
    s.validate();
    ADD_FAILURE() << "one coefficient for four tendons accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "effects.tendon_friction.coefficients");
  }
}
