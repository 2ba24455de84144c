// `tdcr simulate`: the CSV it writes, its exit codes and messages on bad input and on a step that
// fails (apps/simulate_command.cpp).
#include <gtest/gtest.h>

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
  EXPECT_EQ(rows[0].rfind("t,tip_x,tip_y,tip_z,rot_x,rot_y,rot_z,status,iterations", 0), 0u) << rows[0];
  EXPECT_EQ(rows[1].rfind("0,0,0,0.1,", 0), 0u) << rows[1];  // at rest, straight
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

}  // namespace
