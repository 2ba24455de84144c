// Calibration (tdcr/models/calibration.hpp): parameters recovered from data the same model made,
// standard errors that cover the truth, non-identifiable parameters reported, bad data named by
// line and column.
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tdcr/core/error.hpp"
#include "tdcr/core/lie.hpp"
#include "tdcr/core/paper_robot.hpp"
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

// `count` measurements of `truth` solved by `kind`: random tensions up to 40 % of T_M on each
// tendon and, with `force`, a random transverse tip force up to `force` N; tip position and
// orientation measured in a base frame moved by `base`, plus Gaussian noise of `noise` m on the
// positions.
CalibrationData make_data(const Scene& truth, ModelKind kind, int count, double force, const tdcr::Frame& base,
                          double noise = 0.0, unsigned seed = 1) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> g(0.0, 1.0);
  const double tm = tdcr::paper::max_tension(truth.robot);
  auto model = tdcr::make_model(kind, truth);
  auto ws = model->make_workspace();
  CalibrationData data;
  data.source = "generated";
  for (int i = 0; i < count; ++i) {
    tdcr::CalibrationSample m;
    m.input = truth.input();
    for (double& t : m.input.actuation.values) t = 0.4 * tm * u(rng);
    m.input.loads.tip_force = Vec3(force * (2.0 * u(rng) - 1.0), force * (2.0 * u(rng) - 1.0), 0.0);
    const tdcr::Solution s = tdcr::solve(*model, *ws, m.input, data_solver(truth));
    EXPECT_TRUE(s.converged()) << s.summary.brief_report();
    const tdcr::Frame tip = base * s.tip();
    m.tip = tip.p + noise * Vec3(g(rng), g(rng), g(rng));
    m.rotation = tdcr::lie::log_so3(tip.R);
    m.line = i + 2;
    data.samples.push_back(m);
  }
  return data;
}

// The scene with E and every tendon offset off by the given factors.
Scene perturbed(const Scene& truth, double e_factor, double offset_factor) {
  Scene s = truth;
  s.robot.backbone.youngs_modulus *= e_factor;
  for (tdcr::Segment& seg : s.robot.segments)
    for (tdcr::TendonSpec& t : seg.tendons) t.x *= offset_factor, t.y *= offset_factor;
  return s;
}

const tdcr::FittedParameter& param(const CalibrationResult& r, const std::string& name) {
  for (const tdcr::FittedParameter& p : r.parameters)
    if (p.name == name) return p;
  throw std::runtime_error("no parameter " + name);
}

class SameModelRecovery : public ::testing::TestWithParam<ModelKind> {};

// Noise-free data of a model, fitted by the same model from E 30 % high, offsets 30 % low and no
// base offset: every parameter back to 1e-6 relative (the base offset to 1e-9 m).
TEST_P(SameModelRecovery, RecoversYoungsModulusOffsetsAndBaseOffset) {
  const Scene truth = paper_scene(5);
  const tdcr::Frame base{tdcr::lie::exp_so3(Vec3(0.01, -0.02, 0.005)), Vec3(1e-3, -2e-3, 0.5e-3)};
  const CalibrationData data = make_data(truth, GetParam(), 12, 0.1, base);
  const Scene start = perturbed(truth, 1.3, 0.7);
  CalibrationOptions o;
  o.model = GetParam();
  o.parameters = tdcr::parse_calibration_parameters("youngs_modulus,segment_offset_scale,base_offset,base_rotation");
  const CalibrationResult r = tdcr::calibrate(start, data, o);
  EXPECT_TRUE(r.converged()) << r.summary.brief_report() << " " << r.summary.message;
  EXPECT_NEAR(param(r, "youngs_modulus").value / truth.robot.backbone.youngs_modulus, 1.0, 1e-6);
  EXPECT_NEAR(param(r, "segment_offset_scale[0]").value * 0.7, 1.0, 1e-6);
  EXPECT_NEAR(param(r, "segment_offset_scale[1]").value * 0.7, 1.0, 1e-6);
  EXPECT_NEAR((r.base.p - base.p).norm(), 0.0, 1e-9);
  EXPECT_NEAR(tdcr::lie::rotation_angle(r.base.R, base.R), 0.0, 1e-7);
  EXPECT_NEAR(r.scene.robot.segments[1].tendons[0].y / truth.robot.segments[1].tendons[0].y, 1.0, 1e-6);
  EXPECT_LT(r.summary.after.max_position, 1e-9);
  EXPECT_GT(r.summary.before.max_position, 1e-3);
  EXPECT_TRUE(r.non_identifiable.empty()) << r.warning;
  EXPECT_EQ(r.scene.model, tdcr::to_string(GetParam()));
}

// The other parameter groups, from noise-free CCsub data with transverse gravity and capstan
// friction: a segment length, a disk mass and the friction coefficient back from 30 % off.
TEST(Calibration, RecoversLengthDiskMassAndFriction) {
  Scene truth = paper_scene(5);
  truth.robot.segments[1].disk_mass = 0.004;
  truth.robot.segments[0].disk_mass = 0.004;
  truth.effects.tendon_friction.coefficient = 0.1;
  const tdcr::Frame identity;
  CalibrationData data = make_data(truth, ModelKind::CCsub, 12, 0.05, identity);
  // Gravity across the robot for every measurement (re-solved: make_data solved without it).
  {
    auto model = tdcr::make_model(ModelKind::CCsub, truth);
    auto ws = model->make_workspace();
    for (tdcr::CalibrationSample& m : data.samples) {
      m.input.loads.gravity = Vec3(-9.81, 0.0, 0.0);
      const tdcr::Solution s = tdcr::solve(*model, *ws, m.input, data_solver(truth));
      ASSERT_TRUE(s.converged());
      m.tip = s.tip().p;
      m.rotation = tdcr::lie::log_so3(s.tip().R);
    }
  }
  Scene start = truth;
  start.robot.segments[1].length *= 1.3;
  start.robot.segments[1].disk_mass *= 0.7;
  start.effects.tendon_friction.coefficient = 0.07;
  CalibrationOptions o;
  o.model = ModelKind::CCsub;
  o.parameters = tdcr::parse_calibration_parameters("segment_length[1],disk_mass[1],friction_coefficient");
  const CalibrationResult r = tdcr::calibrate(start, data, o);
  EXPECT_TRUE(r.converged()) << r.summary.brief_report();
  EXPECT_NEAR(param(r, "segment_length[1]").value / 0.05, 1.0, 1e-6);
  EXPECT_NEAR(param(r, "disk_mass[1]").value / 0.004, 1.0, 1e-6);
  EXPECT_NEAR(param(r, "friction_coefficient").value / 0.1, 1.0, 1e-6);
  EXPECT_TRUE(r.non_identifiable.empty()) << r.warning;
}

// Backbone points instead of the tip: E back from the positions of the disks at s = 0.03 m and
// s = 0.05 m (disks 3 and 5 of segment 1, n = 5) of noise-free CCsub shapes, and a point between
// two disks compared on the screw motion between them.
TEST(Calibration, RecoversFromBackbonePoints) {
  const Scene truth = paper_scene(5);
  CalibrationData data = make_data(truth, ModelKind::CCsub, 8, 0.1, tdcr::Frame{});
  auto model = tdcr::make_model(ModelKind::CCsub, truth);
  auto ws = model->make_workspace();
  for (tdcr::CalibrationSample& m : data.samples) {
    const tdcr::Solution s = tdcr::solve(*model, *ws, m.input, data_solver(truth));
    m.tip.reset();
    m.rotation.reset();
    for (int disk : {3, 5}) {
      tdcr::MeasuredPoint p;
      p.s = 0.01 * disk;
      p.position = s.disk_frames[static_cast<std::size_t>(disk)].p;
      m.points.push_back(p);
    }
  }
  CalibrationOptions o;
  o.model = ModelKind::CCsub;
  o.parameters = tdcr::parse_calibration_parameters("youngs_modulus");
  const CalibrationResult r = tdcr::calibrate(perturbed(truth, 1.3, 1.0), data, o);
  EXPECT_TRUE(r.converged()) << r.summary.brief_report();
  EXPECT_NEAR(r.parameters[0].value / truth.robot.backbone.youngs_modulus, 1.0, 1e-6);
  EXPECT_LT(r.summary.after.max_position, 1e-9);
  EXPECT_GT(r.residuals_before[0].point_error, 1e-4);
  // A point half-way between disks 3 and 4 is on the arc between them: off the chord's midpoint
  // by the arc's sagitta (c / 2) tan(theta / 4), chord c, bending angle theta.
  data.samples.resize(1);
  const tdcr::Solution s = tdcr::solve(*model, *ws, data.samples[0].input, data_solver(truth));
  tdcr::MeasuredPoint mid;
  mid.s = 0.035;
  mid.position = 0.5 * (s.disk_frames[3].p + s.disk_frames[4].p);
  data.samples[0].points = {mid};
  const CalibrationResult m = tdcr::calibrate(truth, data, o);
  const double c = (s.disk_frames[4].p - s.disk_frames[3].p).norm();
  const double theta = tdcr::lie::rotation_angle(s.disk_frames[3].R, s.disk_frames[4].R);
  const double sagitta = 0.5 * c * std::tan(0.25 * theta);
  EXPECT_GT(sagitta, 1e-5);
  EXPECT_NEAR(m.residuals_before[0].point_error, sagitta, 0.02 * sagitta);
}

INSTANTIATE_TEST_SUITE_P(Models, SameModelRecovery, ::testing::Values(ModelKind::CCsub, ModelKind::PRB, ModelKind::VC),
                         [](const auto& info) { return tdcr::to_string(info.param); });

// With 0.1 mm noise the truth lies within 3 standard errors (residual-scaled covariance) in at
// least 95 % of the seeded trials' parameters.
TEST(Calibration, StandardErrorsCoverTheTruth) {
  const Scene truth = paper_scene(5);
  int inside = 0, total = 0;
  for (ModelKind kind : {ModelKind::CCsub, ModelKind::PRB}) {
    for (unsigned seed = 1; seed <= 6; ++seed) {
      const CalibrationData data = make_data(truth, kind, 15, 0.1, tdcr::Frame{}, 1e-4, seed);
      CalibrationOptions o;
      o.model = kind;
      o.parameters = tdcr::parse_calibration_parameters("youngs_modulus,segment_offset_scale");
      const CalibrationResult r = tdcr::calibrate(perturbed(truth, 1.3, 0.7), data, o);
      ASSERT_TRUE(r.converged()) << r.summary.brief_report();
      const double want[3] = {truth.robot.backbone.youngs_modulus, 1.0 / 0.7, 1.0 / 0.7};
      for (int q = 0; q < 3; ++q) {
        const tdcr::FittedParameter& p = r.parameters[static_cast<std::size_t>(q)];
        ASSERT_TRUE(std::isfinite(p.std_error) && p.std_error > 0.0) << p.name;
        inside += std::abs(p.value - want[q]) <= 3.0 * p.std_error;
        ++total;
      }
      EXPECT_NEAR(r.summary.after.rms_position, 1e-4 * std::sqrt(3.0), 0.6e-4);
    }
  }
  EXPECT_GE(inside, static_cast<int>(std::ceil(0.95 * total))) << inside << " of " << total;
}

// Tension-only data without loads: only the ratio of E and the tendon offsets matters (CCsub is
// inextensible; the tendons' moments scale with their offsets, and only the chords' directions
// between disks tell them apart, by 3e-6 of the largest singular value: a 100 % change of that
// combination moves the fit by 4e-3 standard deviations). All three are reported as not
// identifiable, with infinite standard errors and a warning naming them.
TEST(Calibration, ReportsNonIdentifiableParameters) {
  const Scene truth = paper_scene(5);
  const CalibrationData data = make_data(truth, ModelKind::CCsub, 10, 0.0, tdcr::Frame{});
  CalibrationOptions o;
  o.model = ModelKind::CCsub;
  o.parameters = tdcr::parse_calibration_parameters("youngs_modulus,segment_offset_scale");
  const CalibrationResult r = tdcr::calibrate(perturbed(truth, 1.3, 1.0), data, o);
  ASSERT_EQ(r.non_identifiable.size(), 3u) << r.warning;
  EXPECT_NE(r.warning.find("not identifiable from these data: youngs_modulus, segment_offset_scale[0], "
                           "segment_offset_scale[1]"),
            std::string::npos)
      << r.warning;
  EXPECT_FALSE(param(r, "youngs_modulus").identifiable);
  EXPECT_TRUE(std::isinf(param(r, "youngs_modulus").std_error));
  EXPECT_TRUE(std::isinf(param(r, "segment_offset_scale[1]").std_error));
  // E alone is identifiable from the same data.
  o.parameters = tdcr::parse_calibration_parameters("youngs_modulus");
  const CalibrationResult e = tdcr::calibrate(perturbed(truth, 1.3, 1.0), data, o);
  EXPECT_TRUE(e.non_identifiable.empty()) << e.warning;
  EXPECT_NEAR(e.parameters[0].value / truth.robot.backbone.youngs_modulus, 1.0, 1e-6);
}

// A parameter without effect on the data (a disk mass without gravity) is not identifiable.
TEST(Calibration, ParameterWithoutEffectIsNotIdentifiable) {
  const Scene truth = paper_scene(5);
  const CalibrationData data = make_data(truth, ModelKind::PRB, 6, 0.1, tdcr::Frame{});
  CalibrationOptions o;
  o.model = ModelKind::PRB;
  o.parameters = tdcr::parse_calibration_parameters("youngs_modulus,disk_mass[0]");
  const CalibrationResult r = tdcr::calibrate(truth, data, o);
  ASSERT_EQ(r.non_identifiable, std::vector<std::string>{"disk_mass[0]"}) << r.warning;
  EXPECT_TRUE(param(r, "youngs_modulus").identifiable);
}

// --- Data files ---

std::string error_of(const std::string& csv, const Scene& scene) {
  try {
    tdcr::parse_calibration_data(csv, scene, "d.csv");
  } catch (const tdcr::InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(CalibrationData, ReadsSweepOutput) {
  const Scene s = paper_scene(5);
  const std::string csv =
      "# tdcr sweep 0123456789abcdef samples=2 models=vc\n"
      "sample,actuation.tensions[0],loads.tip_force[1],model,status,reason,tip_x,tip_y,tip_z,rot_x,rot_y,rot_z,"
      "iterations,solve_time_s\n"
      "0,1.5,0.25,vc,converged,\"\",0.001,0.002,0.09,0.1,0,0,5,1e-4\n"
      "1,2,0,vc,converged,\"a, \"\"quoted\"\" reason\",0.003,0.004,0.08,0.2,0,0,4,1e-4\n";
  const CalibrationData d = tdcr::parse_calibration_data(csv, s, "sweep.csv");
  ASSERT_EQ(d.samples.size(), 2u);
  EXPECT_EQ(d.samples[0].line, 3);
  EXPECT_DOUBLE_EQ(d.samples[0].input.actuation.values[0], 1.5);
  EXPECT_DOUBLE_EQ(d.samples[0].input.loads.tip_force[1], 0.25);
  EXPECT_DOUBLE_EQ(d.samples[1].tip->y(), 0.004);
  EXPECT_DOUBLE_EQ(d.samples[1].rotation->x(), 0.2);
  EXPECT_FALSE(d.has_std);
}

TEST(CalibrationData, ReadsPointsAndStandardDeviations) {
  const Scene s = paper_scene(5);
  const std::string csv =
      "actuation.tensions[2],tip_x,tip_y,tip_z,tip_x_std,tip_y_std,tip_z_std,point_x@0.05,point_y@0.05,point_z@0.05\n"
      "1,0.01,0.02,0.09,1e-4,2e-4,,0.001,0.002,0.049\n"
      "1,0.01,0.02,0.09,,,,,,\n";
  const CalibrationData d = tdcr::parse_calibration_data(csv, s, "p.csv");
  ASSERT_EQ(d.samples.size(), 2u);
  ASSERT_EQ(d.samples[0].points.size(), 1u);
  EXPECT_DOUBLE_EQ(d.samples[0].points[0].s, 0.05);
  EXPECT_DOUBLE_EQ(d.samples[0].tip_std.y(), 2e-4);
  EXPECT_TRUE(std::isnan(d.samples[0].tip_std.z()));
  EXPECT_TRUE(d.samples[1].points.empty());
  EXPECT_TRUE(d.has_std);
}

struct BadData {
  const char* name;
  const char* csv;
  const char* expected;  // part of the message
};

class BadDataFile : public ::testing::TestWithParam<BadData> {};

TEST_P(BadDataFile, NamesLineAndColumn) {
  const std::string what = error_of(GetParam().csv, paper_scene(5));
  EXPECT_NE(what.find(GetParam().expected), std::string::npos) << what;
}

INSTANTIATE_TEST_SUITE_P(
    Rows, BadDataFile,
    ::testing::Values(
        BadData{"not_a_number", "actuation.tensions[0],tip_x,tip_y,tip_z\n1,0,0,0.1\n1,abc,0,0.1\n",
                "d.csv line 3, column tip_x: not a number (got abc)"},
        BadData{"nan", "actuation.tensions[0],tip_x,tip_y,tip_z\n1,0,nan,0.1\n", "d.csv line 2, column tip_y: must be a finite number (got nan)"},
        BadData{"negative_tension", "actuation.tensions[1],tip_x,tip_y,tip_z\n-1,0,0,0.1\n",
                "d.csv line 2, column actuation.tensions[1]: a tension must not be negative"},
        BadData{"field_count", "actuation.tensions[0],tip_x,tip_y,tip_z\n1,0,0\n", "d.csv line 2: expected 4 fields"},
        BadData{"partial_group", "actuation.tensions[0],tip_x,tip_y,tip_z\n1,0,,0.1\n", "d.csv line 2, column tip_y"},
        BadData{"failed_status", "status,tip_x,tip_y,tip_z\nconverged,0,0,0.1\nmax_iterations,,,\n",
                "d.csv line 3, column status: a measurement must come from a converged solve"},
        BadData{"unknown_column", "actuation.tension[0],tip_x,tip_y,tip_z\n", "d.csv line 1, column actuation.tension[0]: unknown column"},
        BadData{"robot_column", "robot.backbone.youngs_modulus,tip_x,tip_y,tip_z\n", "calibration data are measurements of one robot"},
        BadData{"missing_tendon", "actuation.tensions[4],tip_x,tip_y,tip_z\n", "does not exist: the scene's robot has 4 tendons"},
        BadData{"incomplete_header", "actuation.tensions[0],tip_x,tip_y\n", "d.csv line 1, column tip: needs all three columns"},
        BadData{"no_measurement", "actuation.tensions[0]\n1\n", "no measurement column"},
        BadData{"negative_std", "tip_x,tip_y,tip_z,tip_x_std,tip_y_std,tip_z_std\n0,0,0.1,-1,1,1\n", "d.csv line 2, column tip_x_std: a standard deviation must be positive"},
        BadData{"point_beyond_tip", "point_x@0.2,point_y@0.2,point_z@0.2\n", "arc length"},
        BadData{"two_models", "model,tip_x,tip_y,tip_z\nvc,0,0,0.1\nvcref,0,0,0.1\n",
                "d.csv line 3, column model: the data mix models (line 2 is vc)"},
        BadData{"empty", "# only a comment\n", "no header line"},
        BadData{"no_rows", "tip_x,tip_y,tip_z\n", "no data rows"}),
    [](const auto& info) { return std::string(info.param.name); });

TEST(CalibrationData, MissingFileNamesThePath) {
  try {
    tdcr::read_calibration_data("/nonexistent/data.csv", paper_scene(5));
    FAIL();
  } catch (const tdcr::InputError& e) {
    EXPECT_EQ(e.field(), "/nonexistent/data.csv");
  }
}

// --- Parameter lists and options ---

TEST(CalibrationParameters, ParsesNamesIndicesAndBounds) {
  const auto p = tdcr::parse_calibration_parameters("youngs_modulus:1e10:1e12, segment_length[1],base_offset::0.01");
  ASSERT_EQ(p.size(), 3u);
  EXPECT_EQ(p[0].kind, tdcr::CalibrationParameterKind::YoungsModulus);
  EXPECT_DOUBLE_EQ(*p[0].lower, 1e10);
  EXPECT_EQ(p[1].index, 1);
  EXPECT_FALSE(p[2].lower.has_value());
  EXPECT_DOUBLE_EQ(*p[2].upper, 0.01);
}

TEST(CalibrationParameters, RefusesBadEntries) {
  for (const char* bad : {"young", "youngs_modulus:-1:", "youngs_modulus:2:1", "youngs_modulus,youngs_modulus",
                          "segment_length[x]", "youngs_modulus[0]", "base_offset[3]", "", "youngs_modulus:abc:"}) {
    try {
      tdcr::parse_calibration_parameters(bad);
      ADD_FAILURE() << bad;
    } catch (const tdcr::InputError& e) {
      EXPECT_EQ(e.field(), "--fit") << bad;
    }
  }
}

TEST(CalibrationParameters, RefusesWhatTheSceneCannotTake) {
  const Scene s = paper_scene(5);
  const CalibrationData data = make_data(s, ModelKind::CCsub, 2, 0.0, tdcr::Frame{});
  CalibrationOptions o;
  o.model = ModelKind::CCsub;
  o.parameters = tdcr::parse_calibration_parameters("tendon_stiffness[0]");
  EXPECT_THROW(tdcr::calibrate(s, data, o), tdcr::InputError);  // inextensible tendon
  o.parameters = tdcr::parse_calibration_parameters("segment_length[2]");
  EXPECT_THROW(tdcr::calibrate(s, data, o), tdcr::InputError);  // two segments
  o.parameters = tdcr::parse_calibration_parameters("youngs_modulus:3e11:4e11");
  EXPECT_THROW(tdcr::calibrate(s, data, o), tdcr::InputError);  // start outside the bounds
  o.parameters = tdcr::parse_calibration_parameters("youngs_modulus");
  o.position_std = -1.0;
  try {
    tdcr::calibrate(s, data, o);
    FAIL();
  } catch (const tdcr::InputError& e) {
    EXPECT_EQ(e.field(), "calibration.position_std");
  }
}

}  // namespace
