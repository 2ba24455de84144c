// Calibration (tdcr/models/calibration.hpp), the remaining parameter groups and the fit's
// numerics: tendon stiffness, shear modulus and per-tendon offset scales recovered from data that
// identify them; the implicit-function Jacobian against the structured differences; a covariance
// that the robust loss's down-weighted outliers do not inflate.
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tdcr/core/lie.hpp"
#include "tdcr/core/paper_robot.hpp"
#include "tdcr/models/answer_linearisation.hpp"
#include "tdcr/models/calibration.hpp"
#include "tdcr/models/static_model.hpp"

#include "calibration_scenes.hpp"

namespace {

using tdcr::CalibrationData;
using tdcr::CalibrationOptions;
using tdcr::CalibrationResult;
using tdcr::ModelKind;
using tdcr::Scene;
using tdcr::Vec3;

using tdcr_test::data_solver;
using tdcr_test::paper_scene;

// Random inputs: tensions up to 40 % of T_M, a transverse tip force up to `force` N and a tip
// moment about the base's z axis up to `moment` N m.
std::vector<tdcr::ModelInput> inputs(const Scene& truth, int count, double force, double moment, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double tm = tdcr::paper::max_tension(truth.robot);
  std::vector<tdcr::ModelInput> out;
  for (int i = 0; i < count; ++i) {
    tdcr::ModelInput in = truth.input();
    for (double& t : in.actuation.values) t = 0.4 * tm * u(rng);
    in.loads.tip_force = Vec3(force * (2.0 * u(rng) - 1.0), force * (2.0 * u(rng) - 1.0), 0.0);
    in.loads.tip_moment = Vec3(0.0, 0.0, moment * (2.0 * u(rng) - 1.0));
    out.push_back(in);
  }
  return out;
}

// The measurements (tip pose, plus Gaussian noise of `noise` m on the positions) of `truth`
// solved by `kind` for `in`.
CalibrationData measure(const Scene& truth, ModelKind kind, const std::vector<tdcr::ModelInput>& in,
                        double noise = 0.0, unsigned seed = 1) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  auto model = tdcr::make_model(kind, truth);
  auto ws = model->make_workspace();
  CalibrationData data;
  data.source = "generated";
  for (const tdcr::ModelInput& input : in) {
    tdcr::CalibrationSample m;
    m.input = input;
    const tdcr::Solution s = tdcr::solve(*model, *ws, input, data_solver(truth));
    EXPECT_TRUE(s.converged()) << s.summary.brief_report();
    m.tip = s.tip().p + noise * Vec3(g(rng), g(rng), g(rng));
    m.rotation = tdcr::lie::log_so3(s.tip().R);
    m.line = static_cast<int>(data.samples.size()) + 2;
    data.samples.push_back(m);
  }
  return data;
}

const tdcr::FittedParameter& param(const CalibrationResult& r, const std::string& name) {
  for (const tdcr::FittedParameter& p : r.parameters)
    if (p.name == name) return p;
  throw std::runtime_error("no parameter " + name);
}

// Tendon stiffness shows in the shape only where the motor sets a displacement (a tension input
// shapes the robot the same for any stretch): CCsub data under displacement input (the tendon
// displacements of tension solves of the elastic-tendon robot), every tendon's stiffness back to
// 1e-6 relative from 30 % off.
TEST(CalibrationFit, RecoversTendonStiffnessFromDisplacementInput) {
  Scene truth = paper_scene(5);
  for (tdcr::Segment& seg : truth.robot.segments)
    for (tdcr::TendonSpec& t : seg.tendons) t.stiffness = 300.0;
  auto model = tdcr::make_model(ModelKind::CCsub, truth);
  auto ws = model->make_workspace();
  std::vector<tdcr::ModelInput> by_displacement;
  for (const tdcr::ModelInput& in : inputs(truth, 12, 0.0, 0.0, 3)) {
    const tdcr::Solution s = tdcr::solve(*model, *ws, in, data_solver(truth));
    ASSERT_TRUE(s.converged());
    tdcr::ModelInput d = in;
    d.actuation.kind = tdcr::Actuation::Kind::Displacements;
    d.actuation.values = s.tendon_displacements;
    by_displacement.push_back(d);
  }
  const CalibrationData data = measure(truth, ModelKind::CCsub, by_displacement);
  Scene start = truth;
  int k = 0;
  for (tdcr::Segment& seg : start.robot.segments)
    for (tdcr::TendonSpec& t : seg.tendons) t.stiffness = 300.0 * (k++ % 2 ? 1.3 : 0.7);
  CalibrationOptions o;
  o.model = ModelKind::CCsub;
  o.parameters = tdcr::parse_calibration_parameters("tendon_stiffness");
  const CalibrationResult r = tdcr::calibrate(start, data, o);
  EXPECT_TRUE(r.converged()) << r.summary.brief_report() << " " << r.summary.message;
  ASSERT_EQ(static_cast<int>(r.parameters.size()), k);
  for (const tdcr::FittedParameter& p : r.parameters) EXPECT_NEAR(p.value / 300.0, 1.0, 1e-6) << p.name;
  EXPECT_TRUE(r.non_identifiable.empty()) << r.warning;
  EXPECT_GT(r.summary.before.max_position, 1e-4);
}

// The shear modulus sets VC's torsional stiffness: tip moments about the axis and transverse tip
// forces twist the robot, and the measured tip rotation tells G. Back to 1e-6 relative from 30 %
// high, with E fitted too.
TEST(CalibrationFit, RecoversShearModulusFromLoads) {
  const Scene truth = paper_scene(5);
  const CalibrationData data = measure(truth, ModelKind::VC, inputs(truth, 10, 0.1, 0.01, 5));
  const double g = truth.robot.backbone.youngs_modulus / (2.0 * (1.0 + truth.robot.backbone.poisson_ratio));
  Scene start = truth;
  start.robot.backbone.shear_modulus = 1.3 * g;
  start.robot.backbone.youngs_modulus *= 0.7;
  CalibrationOptions o;
  o.model = ModelKind::VC;
  o.parameters = tdcr::parse_calibration_parameters("youngs_modulus,shear_modulus");
  const CalibrationResult r = tdcr::calibrate(start, data, o);
  EXPECT_TRUE(r.converged()) << r.summary.brief_report() << " " << r.summary.message;
  EXPECT_NEAR(param(r, "shear_modulus").value / g, 1.0, 1e-6);
  EXPECT_NEAR(param(r, "youngs_modulus").value / truth.robot.backbone.youngs_modulus, 1.0, 1e-6);
  EXPECT_TRUE(r.non_identifiable.empty()) << r.warning;
}

// Per-tendon offset scales with E, from PRB data under tip forces (without loads only their ratio
// to E would matter): each tendon's scale back to 1e-6 relative from offsets 30 % low, E 30 %
// high.
TEST(CalibrationFit, RecoversPerTendonOffsetScales) {
  const Scene truth = paper_scene(5);
  const CalibrationData data = measure(truth, ModelKind::PRB, inputs(truth, 16, 0.1, 0.0, 7));
  Scene start = truth;
  start.robot.backbone.youngs_modulus *= 1.3;
  for (tdcr::Segment& seg : start.robot.segments)
    for (tdcr::TendonSpec& t : seg.tendons) t.x *= 0.7, t.y *= 0.7;
  CalibrationOptions o;
  o.model = ModelKind::PRB;
  o.parameters = tdcr::parse_calibration_parameters("youngs_modulus,tendon_offset_scale");
  const CalibrationResult r = tdcr::calibrate(start, data, o);
  EXPECT_TRUE(r.converged()) << r.summary.brief_report() << " " << r.summary.message;
  EXPECT_NEAR(param(r, "youngs_modulus").value / truth.robot.backbone.youngs_modulus, 1.0, 1e-6);
  int tendons = 0;
  for (const tdcr::FittedParameter& p : r.parameters)
    if (p.name.rfind("tendon_offset_scale", 0) == 0) {
      EXPECT_NEAR(p.value * 0.7, 1.0, 1e-6) << p.name;
      ++tendons;
    }
  EXPECT_GE(tendons, 4);
  EXPECT_TRUE(r.non_identifiable.empty()) << r.warning;
}

class JacobianAgreement : public ::testing::TestWithParam<ModelKind> {};

// The implicit-function Jacobian and the structured differences give the same fit and the same
// standard errors (both are first-order differences of step 1e-6 relative), and the implicit one
// solves only the residual points.
TEST_P(JacobianAgreement, SameFitAndStandardErrors) {
  const Scene truth = paper_scene(5);
  const CalibrationData data = measure(truth, GetParam(), inputs(truth, 12, 0.1, 0.0, 11), 1e-4, 2);
  Scene start = truth;
  start.robot.backbone.youngs_modulus *= 1.3;
  CalibrationOptions o;
  o.model = GetParam();
  o.position_std = 1e-4;
  o.parameters = tdcr::parse_calibration_parameters("youngs_modulus,segment_offset_scale,base_offset");
  const CalibrationResult a = tdcr::calibrate(start, data, o);
  o.jacobian = tdcr::CalibrationJacobian::Differences;
  const CalibrationResult b = tdcr::calibrate(start, data, o);
  ASSERT_TRUE(a.converged() && b.converged()) << a.summary.brief_report() << " / " << b.summary.brief_report();
  EXPECT_GT(a.summary.linearised_answers, 0);
  EXPECT_EQ(b.summary.linearised_answers, 0);
  EXPECT_LT(a.summary.forward_solves, b.summary.forward_solves);
  EXPECT_LE(a.summary.iterations, b.summary.iterations + 1);
  for (std::size_t q = 0; q < a.parameters.size(); ++q) {
    const tdcr::FittedParameter &p = a.parameters[q], &s = b.parameters[q];
    EXPECT_NEAR(p.value, s.value, 1e-3 * p.std_error) << p.name;
    EXPECT_NEAR(p.std_error / s.std_error, 1.0, 1e-4) << p.name;
  }
}

INSTANTIATE_TEST_SUITE_P(Models, JacobianAgreement, ::testing::Values(ModelKind::CCsub, ModelKind::PRB, ModelKind::VC),
                         [](const auto& info) { return tdcr::to_string(info.param); });

// An answer linearised for a model at a nearby Young's modulus agrees with that model's own solve
// to second order in the change.
TEST(CalibrationFit, LinearisedAnswerMatchesTheSolve) {
  const Scene truth = paper_scene(5);
  const tdcr::ModelInput in = inputs(truth, 1, 0.1, 0.0, 13)[0];
  for (ModelKind kind : {ModelKind::CCsub, ModelKind::PRB, ModelKind::VC}) {
    auto model = tdcr::make_model(kind, truth);
    auto ws = model->make_workspace();
    const tdcr::Solution s = tdcr::solve(*model, *ws, in, data_solver(truth));
    ASSERT_TRUE(s.converged());
    tdcr::AnswerLinearisation lin;
    ASSERT_TRUE(lin.linearise(*model, *ws, in, data_solver(truth), s)) << tdcr::to_string(kind);
    Scene near = truth;
    near.robot.backbone.youngs_modulus *= 1.0 + 1e-5;
    auto other = tdcr::make_model(kind, near);
    auto ows = other->make_workspace();
    tdcr::Solution p;
    ASSERT_TRUE(lin.predict(*other, *ows, in, data_solver(truth), p)) << tdcr::to_string(kind);
    const tdcr::Solution t = tdcr::solve(*other, *ows, in, data_solver(truth));
    ASSERT_TRUE(t.converged());
    const double moved = (t.tip().p - s.tip().p).norm();
    EXPECT_GT(moved, 1e-9) << tdcr::to_string(kind);
    EXPECT_LT((p.tip().p - t.tip().p).norm(), 1e-4 * moved) << tdcr::to_string(kind);
  }
}

// The residual points' solves (Newton to 1e-13, calibration_detail.hpp's kPolishTolerance) give
// the same answer warm-started from a far iterate's answer as cold, to 1e-12 relative: the cost
// is one function of the parameters.
TEST(CalibrationFit, PolishedAnswersDoNotDependOnTheStart) {
  const Scene truth = paper_scene(5);
  Scene far = truth;
  far.robot.backbone.youngs_modulus *= 1.3;
  tdcr::SolverOptions tight = data_solver(truth);
  tight.function_tolerance = 1e-13;
  tight.reuse_jacobian = false;
  tight.extrapolate_warm_starts = false;
  for (ModelKind kind : {ModelKind::CCsub, ModelKind::PRB, ModelKind::VC})
    for (const tdcr::ModelInput& in : inputs(truth, 4, 0.1, 0.0, 19)) {
      auto model = tdcr::make_model(kind, truth);
      auto ws = model->make_workspace();
      auto far_model = tdcr::make_model(kind, far);
      auto far_ws = far_model->make_workspace();
      const tdcr::Solution start = tdcr::solve(*far_model, *far_ws, in, tight);
      ASSERT_TRUE(start.converged());
      const tdcr::Solution cold = tdcr::solve(*model, *ws, in, tight);
      const tdcr::Solution from = tdcr::warm_start_from_other_robot(*model, start);
      const tdcr::Solution warm = tdcr::solve(*model, *ws, in, tight, &from);
      ASSERT_TRUE(cold.converged() && warm.converged());
      EXPECT_GT((start.tip().p - cold.tip().p).norm(), 1e-4);
      EXPECT_LT((warm.tip().p - cold.tip().p).norm(), 1e-12 * cold.tip().p.norm()) << tdcr::to_string(kind);
    }
}

// The covariance with the robust loss's weights: without outliers Huber's covariance is the plain
// least-squares one; one measurement 50 standard deviations off, down-weighted by Huber or
// Cauchy (default scale), leaves the standard errors within 30 % of the same loss's on the clean
// data, where plain least squares inflates them by more than 2x.
TEST(CalibrationFit, DownWeightedOutlierDoesNotInflateStandardErrors) {
  const Scene truth = paper_scene(5);
  const CalibrationData clean = measure(truth, ModelKind::CCsub, inputs(truth, 20, 0.1, 0.0, 17), 1e-4, 4);
  CalibrationOptions o;
  o.model = ModelKind::CCsub;
  o.parameters = tdcr::parse_calibration_parameters("youngs_modulus,segment_offset_scale");
  o.position_std = 1e-4;
  o.loss_scale = 5.0;  // every clean measurement in Huber's quadratic range
  o.loss = tdcr::CalibrationLoss::None;
  const CalibrationResult plain = tdcr::calibrate(truth, clean, o);
  o.loss = tdcr::CalibrationLoss::Huber;
  const CalibrationResult huber = tdcr::calibrate(truth, clean, o);
  ASSERT_TRUE(plain.converged() && huber.converged());
  for (Eigen::Index a = 0; a < plain.covariance.rows(); ++a)
    for (Eigen::Index b = 0; b < plain.covariance.cols(); ++b)
      EXPECT_NEAR(huber.covariance(a, b), plain.covariance(a, b),
                  1e-6 * std::sqrt(plain.covariance(a, a) * plain.covariance(b, b)));

  // The outlier adds at most Huber's loss_scale^2 to the weighted residuals: the default scale, 3.
  CalibrationData dirty = clean;
  *dirty.samples[5].tip += Vec3(5e-3, -2e-3, 1e-3);
  o.loss_scale = 3.0;
  for (tdcr::CalibrationLoss loss : {tdcr::CalibrationLoss::Huber, tdcr::CalibrationLoss::Cauchy}) {
    o.loss = loss;
    const CalibrationResult reference = tdcr::calibrate(truth, clean, o);
    const CalibrationResult r = tdcr::calibrate(truth, dirty, o);
    ASSERT_TRUE(r.converged()) << r.summary.brief_report();
    for (std::size_t q = 0; q < r.parameters.size(); ++q)
      EXPECT_LT(r.parameters[q].std_error, 1.3 * reference.parameters[q].std_error)
          << tdcr::to_string(loss) << " " << r.parameters[q].name;
  }
  o.loss = tdcr::CalibrationLoss::None;
  const CalibrationResult inflated = tdcr::calibrate(truth, dirty, o);
  EXPECT_GT(inflated.parameters[0].std_error, 2.0 * plain.parameters[0].std_error);
}

}  // namespace
