// The tdcr command-line program, run as a user runs it: exit status, stdout, stderr.
#include <sys/wait.h>

#include <unistd.h>

#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "bad_scene_inputs.hpp"
#include "cli_run.hpp"

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

const std::string kBinary = TDCR_BINARY_DIR "/bin/tdcr";
const std::string kExamples = TDCR_EXAMPLES_DIR;

using tdcr_test::CliRun;
using tdcr_test::quote;
using tdcr_test::read_file;

/// A temporary directory, removed at the end of the test.
class TempDir {
 public:
  TempDir() {
    static int counter = 0;
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = info ? info->name() : "x";
    for (char& c : name)
      if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
    path_ = fs::temp_directory_path() /
            ("tdcr_test_cli_" + name + "_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }
  std::string write(const std::string& name, const std::string& text) const {
    const fs::path p = path_ / name;
    std::ofstream(p) << text;
    return p.string();
  }

 private:
  fs::path path_;
};

/// Runs `tdcr <args>` (arguments already quoted as needed) and captures everything.
CliRun run_tdcr(const std::string& args) {
  TempDir tmp;
  return tdcr_test::run_program(kBinary, args, tmp.path() / "stderr.txt");
}

std::string example(const std::string& name) { return quote(kExamples + "/" + name); }

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// ---------------------------------------------------------------------------------------------
// Usage

TEST(Cli, BinaryExists) { ASSERT_TRUE(fs::exists(kBinary)) << kBinary; }

TEST(Cli, HelpPrintsUsage) {
  const CliRun r = run_tdcr("--help");
  EXPECT_EQ(r.status, 0);
  EXPECT_TRUE(contains(r.out, "usage: tdcr solve")) << r.out;
  EXPECT_TRUE(contains(r.out, "--repeat")) << r.out;
}

TEST(Cli, VersionPrintsVersion) {
  const CliRun r = run_tdcr("--version");
  EXPECT_EQ(r.status, 0);
  EXPECT_TRUE(contains(r.out, "tdcr ")) << r.out;
}

TEST(Cli, NoArgumentsIsUsageError) {
  const CliRun r = run_tdcr("");
  EXPECT_EQ(r.status, 2);
  EXPECT_TRUE(contains(r.err, "missing command")) << r.err;
}

TEST(Cli, UnknownCommand) {
  const CliRun r = run_tdcr("frobnicate");
  EXPECT_EQ(r.status, 2);
  EXPECT_TRUE(contains(r.err, "frobnicate")) << r.err;
}

TEST(Cli, UnknownOption) {
  const CliRun r = run_tdcr("solve " + example("paper_robot_cc.json") + " --fast");
  EXPECT_EQ(r.status, 2);
  EXPECT_TRUE(contains(r.err, "unknown option '--fast'")) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

TEST(Cli, MissingSceneArgument) {
  const CliRun r = run_tdcr("solve --json");
  EXPECT_EQ(r.status, 2);
  EXPECT_TRUE(contains(r.err, "missing scene file")) << r.err;
}

TEST(Cli, TwoSceneFiles) {
  const CliRun r = run_tdcr("solve " + example("paper_robot_cc.json") + " " + example("paper_robot_vc.json"));
  EXPECT_EQ(r.status, 2);
  EXPECT_TRUE(contains(r.err, "unexpected argument")) << r.err;
}

struct BadArgs {
  std::string name;
  std::string args;      ///< After "solve <cc example>".
  std::string in_error;  ///< stderr must contain this.
};
std::ostream& operator<<(std::ostream& os, const BadArgs& b) { return os << b.name; }

class CliBadArgs : public ::testing::TestWithParam<BadArgs> {};

TEST_P(CliBadArgs, ExitTwoWithMessage) {
  const CliRun r = run_tdcr("solve " + example("paper_robot_cc.json") + " " + GetParam().args);
  EXPECT_EQ(r.status, 2) << r.out << r.err;
  EXPECT_TRUE(contains(r.err, GetParam().in_error)) << r.err;
}

INSTANTIATE_TEST_SUITE_P(
    Cli, CliBadArgs,
    ::testing::Values(BadArgs{"RepeatZero", "--repeat 0", "--repeat"},
                      BadArgs{"RepeatNegative", "--repeat -4", "--repeat"},
                      BadArgs{"RepeatText", "--repeat abc", "got 'abc'"},
                      BadArgs{"RepeatFraction", "--repeat 1.5", "got '1.5'"},
                      BadArgs{"RepeatHuge", "--repeat 99999999999999999999", "--repeat"},
                      BadArgs{"RepeatMissing", "--repeat", "--repeat: missing argument"},
                      BadArgs{"RepeatEqualsEmpty", "--repeat=", "--repeat"},
                      BadArgs{"ModelMissing", "--model", "--model: missing argument"},
                      BadArgs{"ModelUnknown", "--model cosserat", "cosserat"},
                      BadArgs{"AccuracyOutOfRange", "--model auto --accuracy 1.5", "--accuracy"},
                      BadArgs{"IntegratorUnknown", "--integrator euler", "euler"},
                      BadArgs{"TipToleranceText", "--tip-tolerance abc", "--tip-tolerance: expected a number"},
                      BadArgs{"TipToleranceTooLoose", "--tip-tolerance 1", "solver.tip_tolerance"},
                      BadArgs{"TipToleranceNegative", "--tip-tolerance -1e-9", "(got -1e-09)"},
                      BadArgs{"JsonWithValue", "--json=yes", "--json takes no argument"}),
    [](const ::testing::TestParamInfo<BadArgs>& info) { return info.param.name; });

// ---------------------------------------------------------------------------------------------
// Bad scene files

TEST(Cli, MissingFile) {
  const CliRun r = run_tdcr("solve /nonexistent/tdcr_scene.json");
  EXPECT_EQ(r.status, 2);
  EXPECT_TRUE(contains(r.err, "/nonexistent/tdcr_scene.json")) << r.err;
  EXPECT_TRUE(contains(r.err, "cannot be opened")) << r.err;
  EXPECT_TRUE(contains(r.err, "error: ")) << r.err;
}

json paper_scene() { return json::parse(read_file(kExamples + "/paper_robot_cc.json")); }

struct BadScene {
  std::string name;
  std::string text;
  std::string field;  ///< stderr must name this field.
};
std::ostream& operator<<(std::ostream& os, const BadScene& b) { return os << b.name; }

std::string scene_with(const std::string& ptr, const json& v) {
  json j = paper_scene();
  j[json::json_pointer(ptr)] = v;
  return j.dump();
}

/// Every bad scene of the shared table (bad_scene_inputs.hpp, the same table test_scene_io.cpp runs
/// through the C++ API) through the command line: exit 2, nothing on stdout, and a message on
/// stderr that names the field and contains the value.
class CliBadSceneTable : public ::testing::TestWithParam<bad_scenes::BadInput> {};

TEST_P(CliBadSceneTable, ExitTwoNamingFieldAndValue) {
  const bad_scenes::BadInput& b = GetParam();
  TempDir tmp;
  const std::string path = tmp.write("scene.json", b.text);
  const CliRun r = run_tdcr("solve " + quote(path));
  EXPECT_EQ(r.status, 2) << r.out << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
  // Errors about the file as a whole name the file: the API test calls it scene.json.
  const std::string field = b.field == "scene.json" ? path : b.field;
  EXPECT_TRUE(contains(r.err, "error: " + field + ": ")) << r.err;
  EXPECT_TRUE(contains(r.err, b.in_what)) << r.err;
}

INSTANTIATE_TEST_SUITE_P(SharedTable, CliBadSceneTable, ::testing::ValuesIn(bad_scenes::bad_inputs()),
                         [](const ::testing::TestParamInfo<bad_scenes::BadInput>& info) { return info.param.name; });

class CliBadScene : public ::testing::TestWithParam<BadScene> {};

TEST_P(CliBadScene, ExitTwoNamingTheField) {
  TempDir tmp;
  const std::string path = tmp.write("scene.json", GetParam().text);
  const CliRun r = run_tdcr("solve " + quote(path) + " --json");
  EXPECT_EQ(r.status, 2) << r.out << r.err;
  EXPECT_TRUE(contains(r.err, "error: ")) << r.err;
  EXPECT_TRUE(contains(r.err, GetParam().field + ": ")) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

INSTANTIATE_TEST_SUITE_P(
    Cli, CliBadScene,
    ::testing::Values(
        BadScene{"Malformed", "{\"robot\": ", "scene.json"},
        BadScene{"NegativeLength", scene_with("/robot/segments/1/length", -0.05), "robot.segments[1].length"},
        BadScene{"FloatDisks", scene_with("/robot/segments/0/disks", 2.5), "robot.segments[0].disks"},
        BadScene{"UnknownKey", scene_with("/robot/segments/0/lenght", 0.05), "robot.segments[0].lenght"},
        BadScene{"DisplacementString", scene_with("/actuation/displacements/1", "x"),
                 "actuation.displacements[1]"},
        BadScene{"TendonOnAxis", scene_with("/robot/segments/1/tendons/0", {{"x", 0}, {"y", 0}}),
                 "robot.segments[1].tendons[0]"},
        BadScene{"BadEffect", scene_with("/effects", {{"disk_normal_force", "maybe"}}),
                 "effects.disk_normal_force"},
        BadScene{"WrongTipForce", scene_with("/loads", {{"tip_force", {1, 2}}}), "loads.tip_force"},
        BadScene{"Overflow", "{\"robot\": {\"segments\": [{\"length\": 1e999}]}}", "robot.segments[0].length"}),
    [](const ::testing::TestParamInfo<BadScene>& info) { return info.param.name; });

TEST(Cli, SceneFromStdin) {
  const CliRun r = run_tdcr("solve - < " + quote(kExamples + "/paper_robot_cc.json") + " --json");
  EXPECT_TRUE(r.status == 0 || r.status == 1 || r.status == 2) << r.status;
  EXPECT_FALSE(contains(r.err, "cannot be opened")) << r.err;
}

// ---------------------------------------------------------------------------------------------
// Solving

/// Checks the JSON contract of `tdcr solve --json` (see tdcr::solution_to_json).
void expect_contract(const json& j) {
  for (const char* k : {"model", "status", "reason", "iterations", "residual_norm", "tip", "disks",
                        "tendon_displacements", "timing", "summary"})
    EXPECT_TRUE(j.contains(k)) << "missing key " << k;
  ASSERT_TRUE(j["tip"].is_object());
  EXPECT_TRUE(j["tip"].contains("position"));
  EXPECT_TRUE(j["tip"].contains("rotation"));
  for (const char* k : {"repeat", "median_us", "min_us"}) EXPECT_TRUE(j["timing"].contains(k)) << k;
  for (const char* k : {"termination", "message", "solver_flag", "iterations", "residual_evaluations",
                        "jacobian_evaluations", "residual_norm", "physical_residual", "unknowns",
                        "continuation_steps", "linear_solver", "integrator", "solve_time_s"})
    EXPECT_TRUE(j["summary"].contains(k)) << "missing summary key " << k;
  EXPECT_TRUE(j["status"] == "converged" || j["status"] == "failed") << j["status"];
}

TEST(Cli, SolveCcExampleJsonContract) {
  const CliRun r = run_tdcr("solve " + example("paper_robot_cc.json") + " --json --repeat 3");
  ASSERT_EQ(r.status, 0) << r.err;
  json j;
  ASSERT_NO_THROW(j = json::parse(r.out)) << r.out;
  expect_contract(j);
  EXPECT_EQ(j["model"], "cc");
  EXPECT_EQ(j["status"], "converged");
  EXPECT_EQ(j["timing"]["repeat"], 3);
  EXPECT_LE(j["timing"]["min_us"].get<double>(), j["timing"]["median_us"].get<double>());
  // Base disk, 2 x 10 disks.
  EXPECT_EQ(j["disks"].size(), 21u);
  EXPECT_EQ(j["tendon_displacements"].size(), 4u);
  ASSERT_EQ(j["tip"]["position"].size(), 3u);
  ASSERT_EQ(j["tip"]["rotation"].size(), 3u);
  // Tendon 1 (at +y) pulled: the robot bends towards +y, 0.25 rad in segment 1.
  EXPECT_GT(j["tip"]["position"][1].get<double>(), 0.0);
  EXPECT_NEAR(j["tip"]["rotation"][2][2].get<double>(), std::cos(0.25), 1e-9);
}

TEST(Cli, SolveCcExampleHumanSummary) {
  const CliRun r = run_tdcr("solve " + example("paper_robot_cc.json"));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(contains(r.out, "model:  cc")) << r.out;
  EXPECT_TRUE(contains(r.out, "status: converged")) << r.out;
  EXPECT_TRUE(contains(r.out, "tip position (mm)")) << r.out;
  EXPECT_TRUE(contains(r.out, "tip angle from base z axis (deg):    14.32")) << r.out;
  EXPECT_TRUE(contains(r.out, "solve time (us)")) << r.out;
}

TEST(Cli, ModelOverrideIsCaseInsensitive) {
  const CliRun r = run_tdcr("solve " + example("paper_robot_cc.json") + " --model CC --json");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(json::parse(r.out)["model"], "cc");
}

TEST(Cli, ModelAutoPicksAndSaysWhy) {
  // No external load, 10 disks per segment: CC is within 0.15 % of VCref (docs/models.md).
  const CliRun r = run_tdcr("solve " + example("paper_robot_vc.json") + " --model auto --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["model"], "cc");
  EXPECT_NE(j["model_selection"].get<std::string>().find("requested 1 %"), std::string::npos);
  // A tip force rules CC out.
  const CliRun f = run_tdcr("solve " + example("paper_robot_tip_force.json") + " --model auto --json");
  ASSERT_EQ(f.status, 0) << f.err;
  EXPECT_EQ(json::parse(f.out)["model"], "vc");
}

/// Every example solves and converges (exit 0) with the JSON contract on stdout.
TEST(Cli, EveryExampleConverges) {
  int count = 0;
  for (const auto& entry : fs::directory_iterator(kExamples)) {
    if (entry.path().extension() != ".json") continue;
    SCOPED_TRACE(entry.path().string());
    const CliRun r = run_tdcr("solve " + quote(entry.path().string()) + " --json");
    ASSERT_EQ(r.status, 0) << r.err;
    json j;
    ASSERT_NO_THROW(j = json::parse(r.out)) << r.out;
    expect_contract(j);
    EXPECT_EQ(j["status"], "converged");
    ++count;
  }
  EXPECT_GE(count, 8);
}

/// --integrator overrides the scene's integrator (VC integrates the Cosserat rod ODEs).
TEST(Cli, IntegratorOverride) {
  const CliRun r = run_tdcr("solve " + example("paper_robot_vc.json") + " --integrator cvode --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const json j = json::parse(r.out);
  expect_contract(j);
  EXPECT_EQ(j["summary"]["integrator"], "cvode");
}

/// A solve that cannot converge (one Newton iteration for a bend under a tip force, where the
/// unloaded initial guess is not the answer) exits 1 and still prints the result, "failed".
TEST(Cli, NonConvergedSolveExitsOne) {
  json j = json::parse(read_file(kExamples + "/paper_robot_tip_force.json"));
  j["solver"] = {{"max_iterations", 1}, {"continuation", false}};  // a direct failure
  TempDir tmp;
  const std::string path = tmp.write("vc_one_iteration.json", j.dump());
  const CliRun r = run_tdcr("solve " + quote(path) + " --json");
  ASSERT_EQ(r.status, 1) << r.out << r.err;
  json out;
  ASSERT_NO_THROW(out = json::parse(r.out)) << r.out;
  expect_contract(out);
  EXPECT_EQ(out["status"], "failed");
  EXPECT_NE(out["reason"], "converged");
}

// ---------------------------------------------------------------------------------------------
// tdcr inverse

/// The paper robot example with all tensions zero (the inverse starts from the scene's tensions).
std::string slack_paper_robot(const TempDir& tmp) {
  json j = json::parse(read_file(kExamples + "/paper_robot_vc.json"));
  j["actuation"]["tensions"] = {0, 0, 0, 0};
  return tmp.write("slack.json", j.dump());
}

/// The example's tip (tendon 1 at T_M) is reached from zero tensions, by T_M on tendon 1 alone:
/// the least-norm tensions that make this bend.
TEST(CliInverse, ReachesTheExampleTipWithItsTensions) {
  const CliRun f = run_tdcr("solve " + example("paper_robot_vc.json") + " --json");
  ASSERT_EQ(f.status, 0) << f.err;
  const json tip = json::parse(f.out)["tip"]["position"];
  char target[128];
  std::snprintf(target, sizeof target, "%.17g,%.17g,%.17g", tip[0].get<double>(), tip[1].get<double>(),
                tip[2].get<double>());
  TempDir tmp;
  const CliRun r = run_tdcr("inverse " + quote(slack_paper_robot(tmp)) + " --target " + target + " --json");
  ASSERT_EQ(r.status, 0) << r.out << r.err;
  const json j = json::parse(r.out);
  expect_contract(j);
  const json& inv = j["inverse"];
  EXPECT_EQ(inv["status"], "converged");
  EXPECT_LT(inv["position_error"].get<double>(), 1e-6);
  EXPECT_TRUE(inv["target"]["rotation"].is_null());
  ASSERT_EQ(inv["tensions"].size(), 4u);
  // The target is the example's tip at the default tip tolerance (1e-8 m); the inverse solves on
  // the fixed mesh, so the tensions come back to the tension that 1e-8 m moves (1.9e-6 N here).
  EXPECT_NEAR(inv["tensions"][0].get<double>(), 5.5532974, 1e-5);
  for (int k = 1; k < 4; ++k) EXPECT_LE(inv["tensions"][k].get<double>(), 1e-5);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(j["tip"]["position"][i].get<double>(), tip[i].get<double>(), 1e-6);

  const CliRun text = run_tdcr("inverse " + quote(slack_paper_robot(tmp)) + " --target " + target);
  ASSERT_EQ(text.status, 0) << text.err;
  EXPECT_TRUE(contains(text.out, "inverse:  converged")) << text.out;
  EXPECT_TRUE(contains(text.out, "tensions (N):")) << text.out;
}

/// A target above the straight robot cannot be reached (tendons only shorten it): exit 1, the
/// closest pose printed with its distance.
TEST(CliInverse, UnreachableTargetExitsOne) {
  TempDir tmp;
  const CliRun r = run_tdcr("inverse " + quote(slack_paper_robot(tmp)) + " --target 0,0,0.3 --json");
  ASSERT_EQ(r.status, 1) << r.out << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["inverse"]["status"], "failed");
  EXPECT_NEAR(j["inverse"]["position_error"].get<double>(), 0.2, 1e-9);
  const CliRun text = run_tdcr("inverse " + quote(slack_paper_robot(tmp)) + " --target 0,0,0.3");
  EXPECT_EQ(text.status, 1);
  EXPECT_TRUE(contains(text.out, "unreachable")) << text.out;
}

TEST(CliInverse, BadTargetExitsTwoNamingIt) {
  const std::string scene = example("paper_robot_vc.json");
  for (const std::string bad : {"0,1", "0,0.1,x", "1,2,3,4", "0,0,0.1,"}) {
    const CliRun r = run_tdcr("inverse " + scene + " --target " + quote(bad));
    EXPECT_EQ(r.status, 2) << bad;
    EXPECT_TRUE(contains(r.err, "--target") && contains(r.err, bad)) << r.err;
  }
  const CliRun nan = run_tdcr("inverse " + scene + " --target 0,nan,0.1");
  EXPECT_EQ(nan.status, 2);
  EXPECT_TRUE(contains(nan.err, "target.position[1]") && contains(nan.err, "nan")) << nan.err;
  const CliRun missing = run_tdcr("inverse " + scene);
  EXPECT_EQ(missing.status, 2);
  EXPECT_TRUE(contains(missing.err, "--target")) << missing.err;
}

}  // namespace
