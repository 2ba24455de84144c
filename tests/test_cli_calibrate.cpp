// `tdcr calibrate`, run as a user runs it: a sweep's output is its data, the fit and its report,
// the calibrated scene file, and bad input (exit 2, the message naming line and column).
#include <sys/wait.h>

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_run.hpp"

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

const std::string kBinary = TDCR_BINARY_DIR "/bin/tdcr";
const std::string kExamples = TDCR_EXAMPLES_DIR;

using tdcr_test::CliRun;
using tdcr_test::quote;
using tdcr_test::read_file;

// A temporary directory for one test, with the paper robot's scene (E 30 % high: the start) and
// data made by `tdcr sweep` of the true robot with CCsub.
class CalibrateCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("tdcr_test_cli_calibrate_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    json scene = json::parse(read_file(kExamples + "/paper_robot_vc.json"));
    scene["model"] = "ccsub";
    std::ofstream(dir_ / "truth.json") << scene.dump(2);
    scene["robot"]["backbone"]["youngs_modulus"] = 1.3 * 2.11e11;
    std::ofstream(dir_ / "start.json") << scene.dump(2);
    const json sweep = {{"scene", (dir_ / "truth.json").string()},
                        {"models", {"ccsub"}},
                        {"axes",
                         {{{"field", "actuation.tensions[0]"}, {"values", {0.5, 1.5, 2.5}}},
                          {{"field", "actuation.tensions[3]"}, {"values", {0.0, 1.0}}},
                          {{"field", "loads.tip_force[0]"}, {"values", {-0.05, 0.05}}}}}};
    std::ofstream(dir_ / "sweep.json") << sweep.dump(2);
    const CliRun r = run("sweep " + path("sweep.json") + " -o " + path("data.csv") + " --threads 1 --quiet");
    ASSERT_EQ(r.status, 0) << r.err;
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string path(const std::string& name) const { return quote((dir_ / name).string()); }
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(dir_ / name) << text;
    return path(name);
  }
  CliRun run(const std::string& args) const {
    return tdcr_test::run_program(kBinary, args, dir_ / "stderr.txt");
  }
  fs::path dir_;
};

// The sweep's CSV is the data: E comes back from 30 % high to the sweep's own accuracy (its
// solves' Newton tolerance, 1e-9 scaled residual), and the calibrated scene file solves.
TEST_F(CalibrateCli, FitsSweepOutputAndWritesTheScene) {
  const CliRun r = run("calibrate " + path("start.json") + " " + path("data.csv") +
                       " --model ccsub --fit youngs_modulus --json -o " + path("calibrated.json"));
  ASSERT_EQ(r.status, 0) << r.err << r.out;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["status"], "converged");
  EXPECT_EQ(j["model"], "ccsub");
  ASSERT_EQ(j["parameters"].size(), 1u);
  EXPECT_EQ(j["parameters"][0]["name"], "youngs_modulus");
  EXPECT_NEAR(j["parameters"][0]["value"].get<double>() / 2.11e11, 1.0, 1e-6);
  EXPECT_NEAR(j["parameters"][0]["initial"].get<double>() / 2.11e11, 1.3, 1e-12);
  EXPECT_GT(j["before"]["rms_position"].get<double>(), 1e-3);
  EXPECT_LT(j["after"]["rms_position"].get<double>(), 1e-8);
  EXPECT_EQ(j["samples"].size(), 12u);
  EXPECT_EQ(j["samples"][0]["line"], 3);  // after the sweep's hash line and header
  const json scene = json::parse(read_file(dir_ / "calibrated.json"));
  EXPECT_NEAR(scene["robot"]["backbone"]["youngs_modulus"].get<double>() / 2.11e11, 1.0, 1e-6);
  EXPECT_EQ(run("solve " + path("calibrated.json")).status, 0);
  EXPECT_GT(j["linearised_answers"].get<int>(), 0);
  // The Jacobian by re-solving instead (--differences): the same fit, nothing linearised.
  const CliRun d = run("calibrate " + path("start.json") + " " + path("data.csv") +
                       " --model ccsub --fit youngs_modulus --json --differences");
  ASSERT_EQ(d.status, 0) << d.err << d.out;
  const json k = json::parse(d.out);
  EXPECT_EQ(k["linearised_answers"], 0);
  EXPECT_NEAR(k["parameters"][0]["value"].get<double>() / j["parameters"][0]["value"].get<double>(), 1.0, 1e-9);
}

TEST_F(CalibrateCli, TextReportNamesParametersAndErrors) {
  const CliRun r = run("calibrate " + path("start.json") + " " + path("data.csv") + " --fit youngs_modulus,disk_mass[1]");
  ASSERT_EQ(r.status, 0) << r.err << r.out;
  EXPECT_NE(r.out.find("youngs_modulus"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("position error (m):"), std::string::npos) << r.out;
  // No gravity: a disk mass does nothing, and the report says so.
  EXPECT_NE(r.out.find("warning: not identifiable from these data: disk_mass[1]"), std::string::npos) << r.out;
}

TEST_F(CalibrateCli, BadRowIsExit2NamingLineAndColumn) {
  std::string text = read_file(dir_ / "data.csv");
  const auto third = text.find('\n', text.find('\n', text.find('\n') + 1) + 1);  // end of line 3
  text.insert(third + 1, "99,1,0,0.05,ccsub,converged,\"\",0.01,oops,0.09,0,0,0,3,1e-5\n");
  const std::string data = write("bad.csv", text);
  const CliRun r = run("calibrate " + path("start.json") + " " + data + " --fit youngs_modulus");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("bad.csv line 4, column tip_y: not a number (got oops)"), std::string::npos) << r.err;
}

TEST_F(CalibrateCli, BadArgumentsAreExit2) {
  const std::string scene = path("start.json"), data = path("data.csv");
  struct Case {
    std::string args, message;
  };
  for (const Case& c : {Case{"--fit young", "--fit: unknown parameter; known: youngs_modulus"},
                        Case{"--fit youngs_modulus:-5:", "its bounds must not be negative"},
                        Case{"", "--fit: missing"},
                        Case{"--fit youngs_modulus --loss square", "--loss: must be huber, cauchy or none (got square)"},
                        Case{"--fit youngs_modulus --position-std -1", "calibration.position_std: must be a positive finite number"},
                        Case{"--fit youngs_modulus --model nope", "model"}}) {
    const CliRun r = run("calibrate " + scene + " " + data + " " + c.args);
    EXPECT_EQ(r.status, 2) << c.args;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << c.args << ": " << r.err;
  }
  const CliRun missing = run("calibrate " + scene + " /nonexistent/d.csv --fit youngs_modulus");
  EXPECT_EQ(missing.status, 2);
  EXPECT_NE(missing.err.find("/nonexistent/d.csv: cannot read the data file"), std::string::npos) << missing.err;
}

}  // namespace
