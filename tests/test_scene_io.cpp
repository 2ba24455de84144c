// Scene files: every bad input is an InputError naming the JSON path and the value; a scene
// round-trips through scene_to_json; every example parses; docs/scene-file.md's key reference is
// the parser's field table; the solution JSON contract.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tdcr/core/error.hpp"
#include "tdcr/core/paper_robot.hpp"
#include "tdcr/core/scene_io.hpp"
#include "tdcr/models/static_model.hpp"
#include "bad_scene_inputs.hpp"
#include "fixed_mesh_settings.hpp"

namespace {

using json = nlohmann::json;
using tdcr::InputError;

using namespace bad_scenes;

class SceneBadInput : public ::testing::TestWithParam<BadInput> {};

// What a program does with a scene file (the CLI too): parse it (keys, types, values), then let
// the models layer check the model name and what that model can take.
TEST_P(SceneBadInput, ThrowsInputErrorNamingFieldAndValue) {
  const BadInput& b = GetParam();
  try {
    tdcr::validate_scene(tdcr::parse_scene(b.text, "scene.json"));
    FAIL() << "no InputError for " << b.text;
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), b.field) << e.what();
    EXPECT_NE(std::string(e.what()).find(b.in_what), std::string::npos)
        << "what() = " << e.what() << "\nexpected to contain: " << b.in_what;
  }
}

INSTANTIATE_TEST_SUITE_P(ScenesIo, SceneBadInput, ::testing::ValuesIn(bad_inputs()),
                         [](const ::testing::TestParamInfo<BadInput>& info) { return info.param.name; });

TEST(SceneIo, MalformedJsonNamesSourceAndBytePosition) {
  try {
    tdcr::parse_scene("{\"robot\": [1, 2,, 3]}", "my_scene.json");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "my_scene.json");
    EXPECT_NE(std::string(e.what()).find("byte 17"), std::string::npos) << e.what();
  }
}

TEST(SceneIo, MissingFileIsInputErrorNamingPath) {
  const std::string path = (std::filesystem::temp_directory_path() / "tdcr_no_such_scene.json").string();
  try {
    tdcr::load_scene(path);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), path);
    EXPECT_NE(std::string(e.what()).find("cannot be opened"), std::string::npos) << e.what();
  }
}

TEST(SceneIo, DirectoryIsNotAScene) {
  const std::string dir = std::filesystem::temp_directory_path().string();
  try {
    tdcr::load_scene(dir);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), dir);
    EXPECT_NE(std::string(e.what()).find("directory"), std::string::npos) << e.what();
  }
}

TEST(SceneIo, DeeplyNestedJsonIsRejectedNotACrash) {
  const std::string text = "{\"robot\": " + std::string(100000, '[') + std::string(100000, ']') + "}";
  try {
    tdcr::parse_scene(text);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.field().rfind("robot[0][0]", 0), 0u) << e.field();
    EXPECT_NE(std::string(e.what()).find("nested too deeply"), std::string::npos) << e.what();
  }
}

TEST(SceneIo, LongValuesAreShortenedInMessages) {
  try {
    tdcr::parse_scene(with("/robot/segments/0/length", std::vector<double>(1000, 1.0)));
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "robot.segments[0].length");
    EXPECT_LT(std::string(e.what()).size(), 400u) << e.what();
    EXPECT_NE(e.value().find("..."), std::string::npos) << e.value();
  }
}

// A number that overflows a double is an InputError at its path wherever it stands (nested
// arrays, the solver object), with the number's text; a 400-digit integer (Python writes big
// ints so) is shortened in the message.
TEST(SceneIo, NumberOverflowNamesItsPathAndText) {
  struct Case {
    std::string text, field, value;
  };
  const std::string digits(400, '9');
  const std::vector<Case> cases = {
      {with_raw("/solver", R"({"rk4_max_step": 1e999})"), "solver.rk4_max_step", "1e999"},
      {with_raw("/robot/segments/0/tendons/0/routing", R"({"type": "points", "positions": [[0, 0.008], [0, -1E+999]]})"),
       "robot.segments[0].tendons[0].routing.positions[1][1]", "-1E+999"},
      {with_raw("/loads", R"({"gravity": [0, 0, )" + digits + "]}"), "loads.gravity[2]", digits.substr(0, 20)},
  };
  for (const Case& c : cases) {
    try {
      tdcr::parse_scene(c.text, "scene.json");
      ADD_FAILURE() << "accepted " << c.text;
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), c.field) << e.what();
      EXPECT_EQ(e.value().rfind(c.value, 0), 0u) << e.what();
      EXPECT_LT(e.value().size(), 64u) << e.what();
      EXPECT_NE(std::string(e.what()).find("must be a finite number"), std::string::npos) << e.what();
    }
  }
}

// Every numeric solver option has bounds (tdcr::SolverOptions::validate): a value outside is an
// InputError naming solver.<name> and the value, e.g. rk4_steps 1e8, which ran for minutes.
TEST(SceneIo, SolverOptionsOutsideTheirBoundsNameFieldAndValue) {
  struct Case {
    json solver;
    std::string field, value;
  };
  const std::vector<Case> cases = {
      {{{"rk4_steps", 100000000}}, "solver.rk4_steps", "100000000"},
      {{{"rk4_steps", 4097}}, "solver.rk4_steps", "4097"},
      {{{"rk4_steps", 0}}, "solver.rk4_steps", "0"},
      {{{"rk4_max_step", 1e-7}}, "solver.rk4_max_step", "1e-07"},
      {{{"rk4_max_step", 0}}, "solver.rk4_max_step", "0"},
      {{{"tip_tolerance", 1e-19}}, "solver.tip_tolerance", "1e-19"},
      {{{"tip_tolerance", 0.1}}, "solver.tip_tolerance", "0.1"},
      {{{"tip_tolerance", -1e-8}}, "solver.tip_tolerance", "-1e-08"},
      {{{"function_tolerance", -1e-8}}, "solver.function_tolerance", "-1e-08"},
      {{{"function_tolerance", 1e-16}}, "solver.function_tolerance", "1e-16"},
      {{{"function_tolerance", 0.1}}, "solver.function_tolerance", "0.1"},
      {{{"step_tolerance", 1e-21}}, "solver.step_tolerance", "1e-21"},
      {{{"step_tolerance", 1}}, "solver.step_tolerance", "1"},
      {{{"cvode_rtol", 1e-15}}, "solver.cvode_rtol", "1e-15"},
      {{{"cvode_rtol", 0.5}}, "solver.cvode_rtol", "0.5"},
      {{{"cvode_atol", 1e-21}}, "solver.cvode_atol", "1e-21"},
      {{{"cvode_atol", 0.1}}, "solver.cvode_atol", "0.1"},
      {{{"max_iterations", 0}}, "solver.max_iterations", "0"},
      {{{"max_iterations", 1001}}, "solver.max_iterations", "1001"},
      {{{"max_continuation_steps", 0}}, "solver.max_continuation_steps", "0"},
      {{{"max_continuation_steps", 1001}}, "solver.max_continuation_steps", "1001"},
  };
  for (const Case& c : cases) {
    try {
      tdcr::parse_scene(with("/solver", c.solver), "scene.json");
      ADD_FAILURE() << "accepted " << c.solver.dump();
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), c.field) << c.solver.dump() << ": " << e.what();
      EXPECT_EQ(e.value(), c.value) << c.solver.dump() << ": " << e.what();
      EXPECT_NE(std::string(e.what()).find("must be"), std::string::npos) << e.what();
    }
  }
}

// The bounds themselves are accepted (the ranges are closed), and so is the finest mesh an
// accuracy-driven solve refines to: the solve validates each refined mesh's options again
// (2^kMaxRk4Halvings times the first's steps at most).
TEST(SceneIo, SolverOptionsAtTheirBoundsAreValid) {
  using S = tdcr::SolverOptions;
  const std::vector<json> valid = {
      {{"integrator", "rk4_fixed"}, {"rk4_steps", S::kMaxRk4Steps}, {"rk4_max_step", S::kMinRk4MaxStep}},
      {{"tip_tolerance", S::kMaxTipTolerance}},
      {{"tip_tolerance", S::kMinTipTolerance}},
      {{"tip_tolerance", 0}, {"function_tolerance", 0}},
      {{"function_tolerance", S::kMinFunctionTolerance}, {"step_tolerance", S::kMinStepTolerance},
       {"cvode_rtol", S::kMinCvodeRtol}, {"cvode_atol", S::kMinCvodeAtol}, {"max_iterations", 1},
       {"max_continuation_steps", 1}},
      {{"function_tolerance", S::kMaxFunctionTolerance}, {"step_tolerance", S::kMaxStepTolerance},
       {"cvode_rtol", S::kMaxCvodeRtol}, {"cvode_atol", S::kMaxCvodeAtol}, {"max_iterations", S::kMaxIterations},
       {"max_continuation_steps", S::kMaxContinuationSteps}},
  };
  for (const json& solver : valid) EXPECT_NO_THROW(tdcr::parse_scene(with("/solver", solver))) << solver.dump();

  S finest;  // as the refinement makes it (rk4_refinement.cpp, solve_refined)
  finest.integrator = tdcr::IntegratorKind::FixedStepRK4;
  finest.rk4_steps = S::kFirstMeshRk4Steps << S::kMaxRk4Halvings;
  finest.rk4_max_step = S::kFirstMeshRk4MaxStep / (1 << S::kMaxRk4Halvings);
  EXPECT_NO_THROW(finest.validate());
  // C++ only (JSON has no infinity): exactly rk4_steps steps per interval.
  S exact;
  exact.integrator = tdcr::IntegratorKind::FixedStepRK4;
  exact.rk4_max_step = std::numeric_limits<double>::infinity();
  EXPECT_NO_THROW(exact.validate());
}

// A scene file's robot has at most 250000 disks in all segments together (scene_schema.cpp,
// kMaxDisks: VCref's scaling benchmark goes to 2 x 100000): the segment that crosses the bound is
// named, with its disks.
TEST(SceneIo, DiskCountOfTheRobotIsBounded) {
  EXPECT_NO_THROW(tdcr::parse_scene(edited([](json& j) {
    j["robot"]["segments"][0]["disks"] = 100000;
    j["robot"]["segments"][1]["disks"] = 150000;
  })));
  for (const int disks : {249991, 100000000}) {
    try {
      tdcr::parse_scene(with("/robot/segments/1/disks", disks));  // segment 0 has 10
      ADD_FAILURE() << "accepted " << disks;
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), "robot.segments[1].disks") << e.what();
      EXPECT_EQ(e.value(), std::to_string(disks)) << e.what();
      EXPECT_NE(std::string(e.what()).find("at most 250000 disks"), std::string::npos) << e.what();
    }
  }
}

TEST(SceneIo, MinimalSceneTakesDefaults) {
  const tdcr::Scene s = tdcr::parse_scene(base_scene().dump());
  const tdcr::Scene d;
  EXPECT_EQ(s.robot.segments.size(), 2u);
  EXPECT_EQ(s.robot.tendon_count(), 4);
  EXPECT_EQ(s.actuation.kind, tdcr::Actuation::Kind::Tensions);
  EXPECT_EQ(s.loads.tip_force, tdcr::Vec3::Zero());
  EXPECT_EQ(s.effects.shear_extension, d.effects.shear_extension);
  EXPECT_EQ(s.effects.disk_normal_force, d.effects.disk_normal_force);
  EXPECT_TRUE(s.effects.kink_forces);
  EXPECT_EQ(s.solver.max_iterations, d.solver.max_iterations);
  EXPECT_EQ(s.solver.rk4_steps, d.solver.rk4_steps);
  EXPECT_EQ(s.robot.segments[0].disk_mass, 0.0);
  EXPECT_FALSE(s.robot.backbone.shear_modulus.has_value());
}

// solver.stability is "auto" (the default), true (every answer) or false (none), and is written
// back the same way.
TEST(SceneIo, StabilityIsAutoTrueOrFalse) {
  EXPECT_EQ(tdcr::parse_scene(base_scene().dump()).solver.stability, tdcr::StabilityCheck::Automatic);
  const std::pair<json, tdcr::StabilityCheck> cases[] = {{"auto", tdcr::StabilityCheck::Automatic},
                                                         {true, tdcr::StabilityCheck::Always},
                                                         {false, tdcr::StabilityCheck::Never}};
  for (const auto& [value, check] : cases) {
    const tdcr::Scene s = tdcr::parse_scene(with("/solver", {{"stability", value}}));
    EXPECT_EQ(s.solver.stability, check) << value.dump();
    const json back = json::parse(tdcr::scene_to_json(s));
    EXPECT_EQ(back.at("solver").at("stability"), value);
    EXPECT_EQ(tdcr::parse_scene(tdcr::scene_to_json(s)).solver.stability, check);
  }
}

TEST(SceneIo, ParsesFullKeySet) {
  const char* text = R"({
    "description": "every key",
    "robot": {
      "backbone": {"youngs_modulus": 6e10, "shear_modulus": 2.3e10, "outer_radius": 0.0005,
                   "inner_radius": 0.0002, "mass_per_length": 0.004},
      "segments": [
        {"length": 0.06, "disks": 3, "tendons": [{"x": 0.01, "y": 0}, {"x": -0.005, "y": 0.0087},
                                                 {"x": -0.005, "y": -0.0087}], "disk_mass": 0.002},
        {"length": 0.04, "disks": 1, "tendons": [], "disk_mass": 0.001}
      ]
    },
    "actuation": {"displacements": [0.001, -0.0005, -0.0005], "displacement_convention": "per_segment"},
    "loads": {"tip_force": [0.1, -0.2, 0.3], "tip_moment": [0.01, 0.02, -0.03], "gravity": [0, 0, -9.81]},
    "effects": {"shear_extension": false, "disk_normal_force": "kept", "tendon_path": "partially_constrained",
                "kink_forces": false,
                "prb": {"gamma": [0.1, 0.3, 0.4, 0.2], "k_theta": [3, 2.5, 2.75]}},
    "model": "ccsub",
    "solver": {"integrator": "rk4_fixed", "rk4_steps": 16, "tip_tolerance": 1e-9, "cvode_rtol": 1e-6, "cvode_atol": 1e-9,
               "function_tolerance": 1e-8, "step_tolerance": 1e-12, "max_iterations": 50,
               "linear_solver": "klu", "continuation": true, "max_continuation_steps": 20,
               "coarse_loading_path": false}
  })";
  const tdcr::Scene s = tdcr::parse_scene(text);
  const auto& b = s.robot.backbone;
  EXPECT_EQ(b.youngs_modulus, 6e10);
  ASSERT_TRUE(b.shear_modulus.has_value());
  EXPECT_EQ(*b.shear_modulus, 2.3e10);
  EXPECT_EQ(b.outer_radius, 0.0005);
  EXPECT_EQ(b.inner_radius, 0.0002);
  ASSERT_TRUE(b.mass_per_length.has_value());
  EXPECT_EQ(*b.mass_per_length, 0.004);
  ASSERT_EQ(s.robot.segments.size(), 2u);
  EXPECT_EQ(s.robot.segments[0].length, 0.06);
  EXPECT_EQ(s.robot.segments[0].disks, 3);
  ASSERT_EQ(s.robot.segments[0].tendons.size(), 3u);
  EXPECT_EQ(s.robot.segments[0].tendons[1].x, -0.005);
  EXPECT_EQ(s.robot.segments[0].tendons[1].y, 0.0087);
  EXPECT_EQ(s.robot.segments[0].disk_mass, 0.002);
  EXPECT_TRUE(s.robot.segments[1].tendons.empty());
  EXPECT_EQ(s.actuation.kind, tdcr::Actuation::Kind::Displacements);
  EXPECT_EQ(s.actuation.convention, tdcr::Actuation::DisplacementConvention::PerSegment);
  EXPECT_EQ(s.actuation.values, (std::vector<double>{0.001, -0.0005, -0.0005}));
  EXPECT_EQ(s.loads.tip_force, tdcr::Vec3(0.1, -0.2, 0.3));
  EXPECT_EQ(s.loads.tip_moment, tdcr::Vec3(0.01, 0.02, -0.03));
  EXPECT_EQ(s.loads.gravity, tdcr::Vec3(0, 0, -9.81));
  EXPECT_FALSE(s.effects.shear_extension);
  EXPECT_EQ(s.effects.disk_normal_force, tdcr::DiskNormalForce::Kept);
  EXPECT_EQ(s.effects.tendon_path, tdcr::TendonPath::PartiallyConstrained);
  EXPECT_FALSE(s.effects.kink_forces);
  EXPECT_EQ(s.effects.prb.gamma[3], 0.2);
  EXPECT_EQ(s.effects.prb.k_theta[2], 2.75);
  EXPECT_EQ(s.model, "ccsub");
  EXPECT_EQ(s.solver.integrator, tdcr::IntegratorKind::FixedStepRK4);
  EXPECT_EQ(s.solver.rk4_steps, 16);
  EXPECT_EQ(s.solver.tip_tolerance, 1e-9);
  EXPECT_EQ(s.solver.cvode_rtol, 1e-6);
  EXPECT_EQ(s.solver.cvode_atol, 1e-9);
  EXPECT_EQ(s.solver.function_tolerance, 1e-8);
  EXPECT_EQ(s.solver.step_tolerance, 1e-12);
  EXPECT_EQ(s.solver.max_iterations, 50);
  EXPECT_EQ(s.solver.linear_solver, tdcr::LinearSolverKind::SparseKLU);
  EXPECT_TRUE(s.solver.continuation);
  EXPECT_EQ(s.solver.max_continuation_steps, 20);
  EXPECT_FALSE(s.solver.coarse_loading_path);
  EXPECT_TRUE(tdcr::SolverOptions().coarse_loading_path);
}

TEST(SceneIo, ParsesDirectStiffness) {
  const tdcr::Scene s = tdcr::parse_scene(
      with("/robot/backbone", {{"stiffness", {{"EI", 4e-3}, {"GJ", 3e-3}, {"EA", 1e5}, {"GA", 4e4}}},
                               {"mass_per_length", 0.001}}));
  ASSERT_TRUE(s.robot.backbone.stiffness.has_value());
  EXPECT_EQ(s.robot.backbone.effective_stiffness().EI, 4e-3);
  EXPECT_EQ(s.robot.backbone.effective_stiffness().GA, 4e4);
}

void expect_same_scene(const tdcr::Scene& a, const tdcr::Scene& b) {
  // The serialised form lists every field; equal text means equal scenes.
  EXPECT_EQ(tdcr::scene_to_json(a), tdcr::scene_to_json(b));
  ASSERT_EQ(a.robot.segments.size(), b.robot.segments.size());
  EXPECT_EQ(a.actuation.values, b.actuation.values);
  EXPECT_EQ(a.robot.backbone.effective_stiffness().EI, b.robot.backbone.effective_stiffness().EI);
}

TEST(SceneIo, RoundTripsPaperScene) {
  tdcr::Scene s = tdcr::paper::scene(10, 6, "vcref");
  s.loads.tip_force = tdcr::Vec3(0.1, 0.2, -0.3);
  s.loads.gravity = tdcr::Vec3(0, 0, -9.81);
  s.robot.backbone.density = 6450.0;
  s.robot.segments[1].disk_mass = 1e-3 / 3.0;  // not a short decimal: checks exact round trip
  s.effects.shear_extension = false;
  s.effects.disk_normal_force = tdcr::DiskNormalForce::Kept;
  s.effects.kink_forces = false;
  s.effects.prb.k_theta[1] = 2.5;
  s.effects.tendon_friction.coefficient = 0.1;
  s.effects.tendon_friction.coefficients.assign(s.robot.tendon_count(), 0.05);
  s.effects.tendon_friction.coefficients[1] = 0.3 / 7.0;
  s.effects.tendon_friction.motion = tdcr::TendonFriction::Motion::Releasing;
  s.solver.integrator = tdcr::IntegratorKind::Cvode;
  s.solver.linear_solver = tdcr::LinearSolverKind::Dense;
  s.solver.continuation = true;
  s.solver.max_iterations = 77;
  const tdcr::Scene back = tdcr::parse_scene(tdcr::scene_to_json(s));
  expect_same_scene(s, back);
  EXPECT_EQ(back.robot.segments[1].disk_mass, 1e-3 / 3.0);
  EXPECT_EQ(back.effects.prb.gamma[0], s.effects.prb.gamma[0]);
  EXPECT_FALSE(back.effects.kink_forces);
  EXPECT_EQ(back.effects.tendon_friction.coefficient, 0.1);
  EXPECT_EQ(back.effects.tendon_friction.coefficients, s.effects.tendon_friction.coefficients);
  EXPECT_EQ(back.effects.tendon_friction.motion, tdcr::TendonFriction::Motion::Releasing);
  EXPECT_EQ(back.solver.max_iterations, 77);
}

TEST(SceneIo, RoundTripsDisplacementsShearModulusAndStiffness) {
  tdcr::Scene s = tdcr::paper::scene(3, 1, "cc");
  s.actuation.kind = tdcr::Actuation::Kind::Displacements;
  s.actuation.values = {0.002, -0.002, 0.0, 0.0};
  s.actuation.convention = tdcr::Actuation::DisplacementConvention::PerSegment;
  s.robot.backbone.shear_modulus = 7.5e10;
  s.robot.backbone.mass_per_length = 0.0031;
  expect_same_scene(s, tdcr::parse_scene(tdcr::scene_to_json(s)));

  s.robot.backbone.stiffness = tdcr::BackboneStiffness{1e-3, 8e-4, 1e5, 4e4};
  const tdcr::Scene back = tdcr::parse_scene(tdcr::scene_to_json(s));
  expect_same_scene(s, back);
  ASSERT_TRUE(back.robot.backbone.stiffness.has_value());
  EXPECT_EQ(back.robot.backbone.stiffness->GJ, 8e-4);
}

TEST(SceneIo, EveryExampleParsesAndValidates) {
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(TDCR_EXAMPLES_DIR)) {
    if (entry.path().extension() != ".json") continue;
    SCOPED_TRACE(entry.path().string());
    tdcr::Scene s;
    ASSERT_NO_THROW(s = tdcr::load_scene(entry.path().string()));
    EXPECT_NO_THROW(s.validate());
    const std::string stem = entry.path().stem().string();
    if (stem.rfind("paper_robot_", 0) != 0) {  // other robots: parse, validate, round-trip
      expect_same_scene(s, tdcr::parse_scene(tdcr::scene_to_json(s)));
      ++count;
      continue;
    }
    // The paper robot examples: 2 x 50 mm segments, 10 disks each, 4 tendons.
    EXPECT_EQ(s.robot.segments.size(), 2u);
    EXPECT_EQ(s.robot.tendon_count(), 4);
    EXPECT_DOUBLE_EQ(s.robot.total_length(), 0.1);
    EXPECT_EQ(s.model, stem == "paper_robot_tip_force" || stem == "paper_robot_displacements" ? "vc"
                       : stem == "paper_robot_dynamics"                                    ? "ccsub"
                           : entry.path().stem().string().substr(std::string("paper_robot_").size()));
    expect_same_scene(s, tdcr::parse_scene(tdcr::scene_to_json(s)));
    ++count;
  }
  EXPECT_GE(count, 6);
}

TEST(SceneIo, SceneDataFilesParse) {
  const std::filesystem::path dir = std::filesystem::path(TDCR_TEST_DATA_DIR) / "scenes";
  ASSERT_TRUE(std::filesystem::exists(dir)) << dir;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() != ".json") continue;
    SCOPED_TRACE(entry.path().string());
    EXPECT_NO_THROW(tdcr::load_scene(entry.path().string()));
  }
}

TEST(SceneIo, ModelNameIsTheModelsLayersToCheck) {
  // Core knows no model names: the parser only checks that `model` is a string.
  const tdcr::Scene s = tdcr::parse_scene(with("/model", "cosserat"));
  EXPECT_EQ(s.model, "cosserat");
  EXPECT_THROW(tdcr::validate_scene(s), InputError);
  EXPECT_NO_THROW(tdcr::validate_scene(tdcr::parse_scene(with("/model", "auto"))));
}

// `effects.kink_forces: false` in a scene file gives the paper code's VC formulation: the
// reference rows with a tip force (paper code, tests/data/reference_vc.csv; the rows where kink
// forces act, n >= 5) are reproduced through the scene path (text -> parse -> tdcr::solve) to
// 1e-6 m (measured: 2.8e-8 m worst of 45 rows), while the default (kink forces on) moves some of
// these tips by more than 1e-4 m (measured: 1.6e-4 m).
TEST(SceneIo, KinkForcesFalseReproducesPaperCodeVc) {
  std::ifstream in(std::string(TDCR_TEST_DATA_DIR) + "/reference_vc.csv");
  ASSERT_TRUE(in.good());
  std::string line;
  std::getline(in, line);  // provenance comment
  std::getline(in, line);  // header
  int rows = 0;
  double worst_paper = 0, worst_default = 0;
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    std::string source, cell;
    std::getline(ss, source, ',');
    std::vector<double> v;
    while (std::getline(ss, cell, ',')) v.push_back(std::stod(cell));
    ASSERT_EQ(v.size(), 22u);
    const tdcr::Vec3 force(v[6], v[7], v[8]);
    const int n = static_cast<int>(v[1]);
    if (force.norm() == 0 || n < 5) continue;
    tdcr::Scene s = tdcr::paper::scene(n, 1, "vc");
    s.actuation.values = {v[2], v[3], v[4], v[5]};
    s.loads.tip_force = force;
    s.solver.integrator = tdcr::IntegratorKind::FixedStepRK4;
    s.solver.rk4_steps = std::max(4, 160 / n);
    nlohmann::json j = nlohmann::json::parse(tdcr::scene_to_json(s));
    j["effects"]["kink_forces"] = false;
    const tdcr::Scene paper = tdcr::parse_scene(j.dump());
    ASSERT_FALSE(paper.effects.kink_forces);
    const tdcr::Vec3 p_ref(v[10], v[11], v[12]);
    const tdcr::Solution a = tdcr::solve(paper);
    const tdcr::Solution b = tdcr::solve(s);
    ASSERT_TRUE(a.converged() && b.converged()) << line;
    const double ea = (a.tip().p - p_ref).norm();
    EXPECT_LT(ea, 1e-6) << source << " case " << v[0] << " n " << n;
    worst_paper = std::max(worst_paper, ea);
    worst_default = std::max(worst_default, (b.tip().p - p_ref).norm());
    ++rows;
  }
  EXPECT_GE(rows, 20);
  EXPECT_GT(worst_default, 1e-4);
  std::printf("rows %d: worst tip error %.3g m (kink_forces false), %.3g m (default)\n", rows, worst_paper,
              worst_default);
}

/// docs/scene-file.md with every generated block (between `<!-- scene-keys: OBJECT -->` and
/// `<!-- /scene-keys -->`) replaced by the table of scene_key_reference(); names the blocks the
/// page lacks or has in excess in `problems`.
std::string with_generated_tables(std::string page, std::string& problems) {
  const std::string end_marker = "<!-- /scene-keys -->";
  std::vector<std::string> names;
  for (const tdcr::SceneKeyTable& t : tdcr::scene_key_reference()) {
    const std::string name = t.object.empty() ? "top" : t.object;
    names.push_back(name);
    const std::string begin_marker = "<!-- scene-keys: " + name + " -->\n";
    const auto begin = page.find(begin_marker);
    const auto end = begin == std::string::npos ? begin : page.find(end_marker, begin);
    if (end == std::string::npos) {
      problems += "no block '" + begin_marker + "...' for the keys of '" + name + "'\n";
      continue;
    }
    const auto from = begin + begin_marker.size();
    page.replace(from, end - from, t.markdown);
  }
  for (auto at = page.find("<!-- scene-keys: "); at != std::string::npos; at = page.find("<!-- scene-keys: ", at + 1)) {
    const auto close = page.find(" -->", at);
    const std::string name = page.substr(at + 17, close - at - 17);
    if (std::find(names.begin(), names.end(), name) == names.end())
      problems += "block '" + name + "' names no object of the scene\n";
  }
  return page;
}

// The key reference of docs/scene-file.md is generated from the parser's field table: a key added,
// removed or changed in the table and not in the page fails here. TDCR_UPDATE_DOCS=1 rewrites the
// page's tables (then review the diff).
TEST(SceneIo, KeyReferenceOfTheDocsIsTheFieldTable) {
  const std::filesystem::path path = std::filesystem::path(TDCR_SOURCE_DIR) / "docs" / "scene-file.md";
  std::ifstream in(path);
  ASSERT_TRUE(in) << path;
  std::stringstream text;
  text << in.rdbuf();
  const std::string page = text.str();
  std::string problems;
  const std::string generated = with_generated_tables(page, problems);
  EXPECT_TRUE(problems.empty()) << problems;
  if (generated != page && std::getenv("TDCR_UPDATE_DOCS")) {
    std::ofstream(path) << generated;
    GTEST_SKIP() << "rewrote the key tables of " << path;
  }
  EXPECT_TRUE(generated == page) << path << " disagrees with the scene field table; rerun this test with "
                                 << "TDCR_UPDATE_DOCS=1 to regenerate its tables, then review the diff. Generated:\n"
                                 << generated;
}

TEST(SceneIo, KeyReferenceListsEveryKeyOnce) {
  std::string all;
  for (const auto& t : tdcr::scene_key_reference()) all += t.markdown;
  for (const char* path : {"`description`", "`robot.backbone.stiffness.GA`", "`robot.segments[i].tendons[k].y`",
                           "`actuation.displacement_convention`", "`effects.prb.k_theta`",
                           "`solver.max_continuation_steps`"}) {
    const auto first = all.find(std::string("| ") + path + " |");
    EXPECT_NE(first, std::string::npos) << path;
    EXPECT_EQ(all.find(std::string("| ") + path + " |", first + 1), std::string::npos) << path;
  }
  // Defaults are those of the structs, as scene_to_json writes them.
  EXPECT_NE(all.find("| `solver.rk4_steps` | integer |  | `8` |"), std::string::npos) << all;
  EXPECT_NE(all.find("| `robot.backbone.youngs_modulus` | number | Pa | `2.11e11` |"), std::string::npos) << all;
}

tdcr::Solution sample_solution() {
  tdcr::Solution s;
  s.model = "vc";
  s.model_fingerprint = 0x0123456789abcdefull;
  s.summary.termination = tdcr::TerminationType::Converged;
  s.summary.message = "KINSOL_SUCCESS";
  s.summary.iterations = 5;
  s.summary.residual_norm = 1e-12;
  s.summary.linear_solver = "dense";
  s.summary.integrator = "rk4";
  for (int i = 0; i < 3; ++i) {
    tdcr::Frame f;
    f.p = tdcr::Vec3(0.0, 0.001 * i, 0.01 * i);
    f.R = Eigen::AngleAxisd(0.1 * i, tdcr::Vec3::UnitX()).toRotationMatrix();
    s.disk_frames.push_back(f);
  }
  s.tendon_displacements = {0.001, -0.001};
  s.tensions = {1.0, 0.0};
  return s;
}

TEST(SolutionJson, HasEveryContractKey) {
  tdcr::SolutionJsonOptions o;
  o.extra.push_back({"timing", R"({"repeat": 7, "median_us": 12.5, "min_us": 11.0})"});
  const json j = json::parse(tdcr::solution_to_json(sample_solution(), o));
  for (const char* k : {"model", "status", "reason", "iterations", "residual_norm", "tip", "disks",
                        "tendon_displacements", "timing", "summary"})
    EXPECT_TRUE(j.contains(k)) << k;
  EXPECT_EQ(j["model"], "vc");
  EXPECT_EQ(j["model_fingerprint"], "0123456789abcdef");
  EXPECT_EQ(j["status"], "converged");
  EXPECT_EQ(j["reason"], "converged: KINSOL_SUCCESS");
  EXPECT_EQ(j["iterations"], 5);
  EXPECT_EQ(j["disks"].size(), 3u);
  EXPECT_EQ(j["tip"]["position"], json({0.0, 0.002, 0.02}));
  EXPECT_DOUBLE_EQ(j["tip"]["rotation"][1][2].get<double>(), -std::sin(0.2));  // row-major R(1, 2)
  EXPECT_EQ(j["timing"]["repeat"], 7);
  EXPECT_EQ(j["timing"]["median_us"], 12.5);
  EXPECT_EQ(j["timing"]["min_us"], 11.0);
  for (const char* k : {"termination", "message", "solver_flag", "iterations", "residual_evaluations",
                        "jacobian_evaluations", "residual_norm", "physical_residual", "unknowns",
                        "continuation_steps", "linear_solver", "integrator", "solve_time_s"})
    EXPECT_TRUE(j["summary"].contains(k)) << k;
  EXPECT_EQ(j["summary"]["linear_solver"], "dense");
}

// A caller's own members (SolutionJsonOptions::extra, the CLI's `timing`) follow the geometry and
// actuation in their order, before the diagnostics; core writes none of its own beside the contract.
TEST(SolutionJson, ExtraMembersFollowTheActuationInTheirOrder) {
  const tdcr::Solution s = sample_solution();
  const nlohmann::ordered_json plain = nlohmann::ordered_json::parse(tdcr::solution_to_json(s));
  EXPECT_FALSE(plain.contains("timing"));
  tdcr::SolutionJsonOptions o;
  o.extra = {{"timing", R"({"repeat": 2})"}, {"note", R"("from a test")"}};
  const nlohmann::ordered_json j = nlohmann::ordered_json::parse(tdcr::solution_to_json(s, o));
  std::vector<std::string> keys;
  for (const auto& item : j.items()) keys.push_back(item.key());
  const auto at = [&](const char* k) { return std::find(keys.begin(), keys.end(), k) - keys.begin(); };
  EXPECT_EQ(at("timing"), at("tensions") + 1);
  EXPECT_EQ(at("note"), at("timing") + 1);
  EXPECT_EQ(at("stability"), at("note") + 1);
  EXPECT_EQ(j["timing"]["repeat"], 2);
  EXPECT_EQ(j["note"], "from a test");
  o.extra = {{"summary", "{}"}};
  EXPECT_THROW(tdcr::solution_to_json(s, o), std::invalid_argument);
  o.extra = {{"timing", "{"}};
  EXPECT_THROW(tdcr::solution_to_json(s, o), std::invalid_argument);
  o.extra = {{"timing", "1"}, {"timing", "2"}};
  EXPECT_THROW(tdcr::solution_to_json(s, o), std::invalid_argument);
}

TEST(SolutionJson, FailedSolveWithNonFiniteValuesIsValidJson) {
  tdcr::Solution s = sample_solution();
  s.summary.termination = tdcr::TerminationType::NonFiniteResidual;
  s.summary.message = "residual is NaN";
  s.summary.residual_norm = std::numeric_limits<double>::quiet_NaN();
  s.disk_frames.back().p.x() = std::numeric_limits<double>::infinity();
  s.tendon_displacements[0] = -std::numeric_limits<double>::infinity();
  const std::string text = tdcr::solution_to_json(s);
  json j;
  ASSERT_NO_THROW(j = json::parse(text)) << text;
  EXPECT_EQ(j["status"], "failed");
  EXPECT_EQ(j["reason"], "non_finite_residual: residual is NaN");
  EXPECT_TRUE(j["residual_norm"].is_null());
  EXPECT_TRUE(j["tip"]["position"][0].is_null());
  EXPECT_TRUE(j["tendon_displacements"][0].is_null());
}

TEST(SolutionJson, EmptySolutionHasNullTip) {
  tdcr::Solution s;
  s.model = "vcref";
  const json j = json::parse(tdcr::solution_to_json(s));
  EXPECT_EQ(j["status"], "failed");
  EXPECT_TRUE(j["tip"]["position"].is_null());
  EXPECT_TRUE(j["disks"].empty());
}

TEST(SolutionJson, OptionalDisksAndBackbone) {
  tdcr::Solution s = sample_solution();
  s.backbone.resize(4);
  tdcr::SolutionJsonOptions o;
  o.include_disks = false;
  o.include_backbone = true;
  const json j = json::parse(tdcr::solution_to_json(s, o));
  EXPECT_FALSE(j.contains("disks"));
  ASSERT_TRUE(j.contains("backbone"));
  EXPECT_EQ(j["backbone"].size(), 4u);
  EXPECT_TRUE(j["backbone"][0].contains("n"));
}

}  // namespace
