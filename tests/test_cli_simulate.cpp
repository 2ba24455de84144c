// `tdcr simulate`: the CSV it writes, its exit codes and messages on bad input and on a step that
// fails (apps/simulate_command.cpp).
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "cli_run.hpp"

namespace {

const std::string kBinary = TDCR_BINARY_DIR "/bin/tdcr";
const std::string kData = TDCR_TEST_DATA_DIR "/dynamics/";

class CliSimulate : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("tdcr_cli_simulate_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  tdcr_test::CliRun run(const std::string& args) {
    return tdcr_test::run_program(kBinary, "simulate " + args, dir_ / "stderr.txt");
  }
  // A scene file in the test's folder.
  std::string scene(const std::string& text) {
    const auto p = dir_ / "scene.json";
    std::ofstream(p) << text;
    return tdcr_test::quote(p.string());
  }
  std::filesystem::path dir_;
};

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> v;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) v.push_back(l);
  return v;
}

TEST_F(CliSimulate, WritesOneRowPerStep) {
  const auto out = dir_ / "out.csv";
  const auto r = run(tdcr_test::quote(kData + "small_step.json") + " --duration 0.1 --dt 0.01 -o " +
                     tdcr_test::quote(out.string()));
  ASSERT_EQ(r.status, 0) << r.err;
  const auto rows = lines(tdcr_test::read_file(out));
  ASSERT_EQ(rows.size(), 12u);  // header, t = 0, 0.01, ..., 0.1
  EXPECT_EQ(rows[0], "t,tip_x,tip_y,tip_z,rot_x,rot_y,rot_z,status,iterations,kinetic_energy,potential_energy,T_1,T_2,"
                     "T_3,T_4");
  EXPECT_EQ(rows[1].rfind("0,0,0,0.1,", 0), 0u) << rows[1];  // at rest, straight
  // The tensions of the timeline (tension input): 0 at rest, tendon 1 ramped to 2 N by 10 ms.
  EXPECT_NE(rows[1].find(",0,0,0,0,0,0"), std::string::npos) << rows[1];  // energies and tensions 0
  EXPECT_EQ(rows[11].substr(rows[11].size() - 8), ",2,0,0,0") << rows[11];
  EXPECT_EQ(rows[11].rfind("0.1,", 0), 0u) << rows[11];
  EXPECT_NE(rows[11].find(",converged,"), std::string::npos) << rows[11];
  // Standard output when no -o is given.
  const auto s = run(tdcr_test::quote(kData + "small_step.json") + " --duration 0.02 --dt=0.01");
  ASSERT_EQ(s.status, 0) << s.err;
  EXPECT_EQ(lines(s.out).size(), 4u) << s.out;
}

TEST_F(CliSimulate, BadInputExitsTwoNamingTheField) {
  const std::string small = tdcr_test::quote(kData + "small_step.json");
  auto r = run(small + " --duration 0.1 --dt 0");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--dt"), std::string::npos) << r.err;
  r = run(small + " --dt 0.01");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--duration"), std::string::npos) << r.err;
  r = run(small + " --duration 0.1 --model cc");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("has no dynamics"), std::string::npos) << r.err;
  const std::string robot =
      R"("robot": {"backbone": {"density": 6450}, "segments": [{"length": 0.05, "disks": 3, "tendons": [{"x": 0, "y": 0.008}]}]},
         "actuation": {"tensions": [0]}, "model": "ccsub")";
  r = run(scene("{" + robot + R"(, "dynamics": {"bending_damping": 0.01}})") + " --duration 0.1");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("dynamics.bending_damping"), std::string::npos) << r.err;
  r = run(scene("{" + robot + R"(, "dynamics": {"bending_damping_time": -1}})") + " --duration 0.1");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("dynamics.bending_damping_time"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("-1"), std::string::npos) << r.err;
  r = run(scene("{" + robot + R"(, "dynamics": {}, "timeline": [{"t": 0.1}, {"t": 0.05}]})") + " --duration 0.1");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("timeline[1].t"), std::string::npos) << r.err;
  r = run(scene("{" + robot + R"(})") + " --duration 0.1");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("dynamics"), std::string::npos) << r.err;
}

// A single subsegment pulled past 90 deg: CCsub's twist law degenerates there and the step
// fails; the rows up to it are written, the message names the time, residual and iterations.
TEST_F(CliSimulate, FailedStepExitsOneWithTimeResidualIterations) {
  const auto out = dir_ / "out.csv";
  const auto r = run(tdcr_test::quote(kData + "curl_past_90deg.json") + " --duration 0.1 --dt 0.01 -o " +
                     tdcr_test::quote(out.string()));
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.err.find("failed at t = "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("residual"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("iterations"), std::string::npos) << r.err;
  const std::string csv = tdcr_test::read_file(out);
  EXPECT_NE(csv.find("integration_failed"), std::string::npos) << csv;
}

// Displacement input: CCsub's dynamics take motors on elastic tendons (their tension is then a
// function of the shape) and refuse an inextensible driven tendon, naming its stiffness field;
// VC's take both (the same inextensible timeline runs there).
TEST_F(CliSimulate, DisplacementInputOnlyWhereTheModelTakesIt) {
  const std::string text =
      R"({"model": "ccsub", "robot": {"backbone": {"density": 6450}, "segments": [{"length": 0.05, "disks": 3,
         "tendons": [{"x": 0, "y": 0.008}, {"x": 0, "y": -0.008}]}]},
         "actuation": {"displacements": [0, -0.001]}, "dynamics": {"bending_damping_time": 0.01, "shear_damping_time": 0.01},
         "timeline": [{"t": 0}, {"t": 0.02, "actuation": {"displacements": [0.0005, -0.001]}}]})";
  const std::string path = scene(text);
  auto r = run(path + " --duration 0.04 --dt 0.01");
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_NE(r.err.find("robot.segments[0].tendons[0].stiffness"), std::string::npos) << r.err;
  // The tendons' solved tensions: tendon 1 pulled taut; tendon 2, its antagonist, let out by
  // 1 mm, more than the bend lengthens its path (about 0.5 mm): slack, exactly 0.
  const auto check_tensions = [](const std::string& out) {
    const auto rows = lines(out);
    ASSERT_EQ(rows.size(), 6u);
    EXPECT_EQ(rows[5].substr(rows[5].size() - 2), ",0") << rows[5];
    const double T1 = std::stod(rows[5].substr(rows[5].rfind(',', rows[5].size() - 3) + 1));
    EXPECT_GT(T1, 0.1) << rows[5];
  };
  r = run(path + " --duration 0.04 --dt 0.01 --model vc");
  ASSERT_EQ(r.status, 0) << r.err;
  check_tensions(r.out);
  // Elastic tendons (EA = 400 N): CCsub's dynamics run the same timeline.
  std::string elastic = text;
  for (const std::string hole : {"{\"x\": 0, \"y\": 0.008}", "{\"x\": 0, \"y\": -0.008}"}) {
    const std::size_t at = elastic.find(hole);
    ASSERT_NE(at, std::string::npos);
    elastic.replace(at, hole.size(), hole.substr(0, hole.size() - 1) + ", \"stiffness\": 400}");
  }
  r = run(scene(elastic) + " --duration 0.04 --dt 0.01");
  ASSERT_EQ(r.status, 0) << r.err;
  check_tensions(r.out);
}

// The progress bar: on a terminal (a pseudo-terminal by `script`), the time, the steps and the
// real-time ratio on standard error; nothing with --quiet, and nothing when standard error is no
// terminal (the other tests: their standard error is a file).
TEST_F(CliSimulate, ProgressBarOnATerminalOnly) {
  if (std::system("script -qec true /dev/null >/dev/null 2>&1") != 0) GTEST_SKIP() << "no `script` (util-linux)";
  const std::string small = tdcr_test::quote(kData + "small_step.json");
  const std::string out = tdcr_test::quote((dir_ / "out.csv").string());
  const auto tty = [&](const std::string& extra) {
    return tdcr_test::run_program("script", "-qec " + tdcr_test::quote(tdcr_test::quote(kBinary) + " simulate " + small +
                                                                    " --duration 0.1 --dt 0.01 -o " + out + extra) +
                                                " /dev/null",
                                  dir_ / "stderr.txt");
  };
  auto r = tty("");
  ASSERT_EQ(r.status, 0) << r.out;
  EXPECT_NE(r.out.find("t = 0.1 / 0.1 s, 11 steps"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("real time"), std::string::npos) << r.out;
  r = tty(" --quiet");
  ASSERT_EQ(r.status, 0) << r.out;
  EXPECT_EQ(r.out.find("steps"), std::string::npos) << r.out;
  r = run(small + " --duration 0.1 --dt 0.01 -o " + out);
  ASSERT_EQ(r.status, 0);
  EXPECT_EQ(r.err, "");
}

}  // namespace
