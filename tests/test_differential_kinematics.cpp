// Differential kinematics (SolverOptions::differential_kinematics): the tip Jacobian and
// compliance of every static model against central finite differences of full solves, CC's
// against its closed-form derivative, and the JSON output.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tdcr/core/lie.hpp"
#include "tdcr/core/paper_robot.hpp"
#include "tdcr/core/scene_io.hpp"
#include "tdcr/models/static_model.hpp"
#include "tdcr/models/vc.hpp"
#include "fixed_mesh_settings.hpp"

using namespace tdcr;

namespace {

using Mat6X = Eigen::MatrixXd;

// Input parameter j: actuation value j < m, then tip force x, y, z, tip moment x, y, z.
ModelInput perturbed(const ModelInput& input, int j, double dv) {
  ModelInput out = input;
  const int m = static_cast<int>(input.actuation.values.size());
  if (j < m)
    out.actuation.values[static_cast<std::size_t>(j)] += dv;
  else if (j < m + 3)
    out.loads.tip_force[j - m] += dv;
  else
    out.loads.tip_moment[j - m - 3] += dv;
  return out;
}

// Central differences of full solves (warm-started from `base`): d tip pose / d parameter j
// for j in [first, first + count), the rotation rows as the base-frame rotation vector.
Mat6X full_solve_differences(const StaticModel& model, const ModelInput& input, const SolverOptions& options,
                             const Solution& base, int first, int count, const std::vector<double>& steps) {
  auto ws = model.make_workspace();
  Mat6X D(6, count);
  auto pose = [](const Solution& a, const Solution& b) {
    Eigen::Matrix<double, 6, 1> d;
    d << a.tip().p - b.tip().p, lie::log_so3(a.tip().R * b.tip().R.transpose());
    return d;
  };
  const int m = static_cast<int>(input.actuation.values.size());
  for (int c = 0; c < count; ++c) {
    const int j = first + c;
    const double h = steps[static_cast<std::size_t>(c)];
    // A zero tension cannot decrease: one-sided (4 g(h) - g(2h) - 3 g(0)) / 2h.
    const bool one_sided = j < m && input.actuation.values[static_cast<std::size_t>(j)] == 0.0;
    const Solution plus = solve(model, *ws, perturbed(input, j, h), options, &base);
    const Solution other = solve(model, *ws, perturbed(input, j, one_sided ? 2 * h : -h), options, &base);
    EXPECT_TRUE(plus.converged() && other.converged()) << "parameter " << j;
    D.col(c) = one_sided ? Eigen::Matrix<double, 6, 1>((4 * pose(plus, base) - pose(other, base)) / (2 * h))
                         : Eigen::Matrix<double, 6, 1>(pose(plus, other) / (2 * h));
  }
  return D;
}

// A solve of `s` by `model` with differential kinematics.
Solution solve_with_dk(const StaticModel& model, const Scene& s) {
  auto ws = model.make_workspace();
  SolverOptions with_dk = s.solver;
  with_dk.differential_kinematics = true;
  return solve(model, *ws, s.input(), with_dk);
}

// Largest error of A against reference B, position rows and rotation rows each relative to
// the largest entry of B's block (they have different units).
double relative_error(const Mat6X& A, const Mat6X& B) {
  double worst = 0;
  for (int block = 0; block < 2; ++block) {
    const double scale = B.middleRows(3 * block, 3).cwiseAbs().maxCoeff();
    worst = std::max(worst, (A - B).middleRows(3 * block, 3).cwiseAbs().maxCoeff() / scale);
  }
  return worst;
}

struct Case {
  ModelKind kind;
  bool loaded;
};

std::string case_name(const testing::TestParamInfo<Case>& info) {
  return to_string(info.param.kind) + (info.param.loaded ? "_Loaded" : "_Unloaded");
}

// The paper robot (n = 5) under unequal tensions on all four tendons, with a tip wrench out of
// the bending plane if `loaded`.
Scene test_scene(ModelKind kind, bool loaded) {
  Scene s = paper::scene(5, 1, to_string(kind));
  s.actuation.values = {2.0, 0.5, 1.0, 0.3};
  if (loaded) {
    s.loads.tip_force = Vec3(0.1, -0.05, -0.1);
    s.loads.tip_moment = Vec3(0.002, 0.001, -0.003);
  }
  // Full-solve differences need one mesh for every solve (an accuracy-driven mesh may change
  // between the perturbed solves).
  s.solver.integrator = IntegratorKind::FixedStepRK4;
  s.solver.function_tolerance = 1e-13;
  return s;
}

// The Jacobian and compliance of `model` on `s` against central differences of full solves.
void expect_matches_full_solves(const StaticModel& model, const Scene& s, const std::string& name) {
  auto ws = model.make_workspace();
  SolverOptions with_dk = s.solver;
  with_dk.differential_kinematics = true;
  const ModelInput input = s.input();
  const Solution base = solve(model, *ws, input, with_dk);
  ASSERT_TRUE(base.converged()) << base.summary.message;
  ASSERT_EQ(base.tip_jacobian.rows(), 6);
  ASSERT_EQ(base.tip_jacobian.cols(), 4);
  ASSERT_EQ(base.tip_compliance.rows(), 6);
  ASSERT_EQ(base.tip_compliance.cols(), 6);
  // Without the option nothing is computed.
  EXPECT_EQ(solve(model, *ws, input, s.solver).tip_jacobian.size(), 0);

  // Steps of the full-solve differences: 1e-4 N, 1e-4 N * 0.1 m (PRB's differences agreed to
  // the printed digits for steps of 1e-6 to 1e-3 N: their error is far below the tolerance).
  const std::vector<double> tension_steps(4, 1e-4), wrench_steps = {1e-4, 1e-4, 1e-4, 1e-5, 1e-5, 1e-5};
  const Mat6X J_fd = full_solve_differences(model, input, s.solver, base, 0, 4, tension_steps);
  const Mat6X C_fd = full_solve_differences(model, input, s.solver, base, 4, 6, wrench_steps);
  const double eJ = relative_error(base.tip_jacobian, J_fd);
  const double eC = relative_error(base.tip_compliance, C_fd);
  std::printf("%s: Jacobian %.2e, compliance %.2e relative to full-solve differences\n", name.c_str(), eJ, eC);
  EXPECT_LT(eJ, 1e-6);
  EXPECT_LT(eC, 1e-6);
  // Physics: a tip force along +x moves the tip along +x, a tension on tendon 1 (at +y) bends
  // the robot towards +y.
  EXPECT_GT(base.tip_compliance(0, 0), 0);
  EXPECT_GT(base.tip_jacobian(1, 0), 0);
}

class DifferentialKinematics : public testing::TestWithParam<Case> {};

TEST_P(DifferentialKinematics, MatchesFiniteDifferencesOfFullSolves) {
  const Case c = GetParam();
  const Scene s = test_scene(c.kind, c.loaded);
  expect_matches_full_solves(*make_model(c.kind, s), s, case_name({c, 0}));
}

// VC's multiple shooting (the formulation of large loads; 90 unknowns at n = 5): the same.
TEST(DifferentialKinematicsVc, MultipleShootingMatchesFiniteDifferencesOfFullSolves) {
  const Scene s = test_scene(ModelKind::VC, true);
  VcOptions options;
  options.formulation = VcFormulation::MultipleShooting;
  expect_matches_full_solves(VcModel(s.robot, s.effects, options), s, "vc multiple shooting");
}

INSTANTIATE_TEST_SUITE_P(StaticModels, DifferentialKinematics,
                         testing::Values(Case{ModelKind::CCsub, false}, Case{ModelKind::CCsub, true},
                                         Case{ModelKind::PRB, false}, Case{ModelKind::PRB, true},
                                         Case{ModelKind::VC, false}, Case{ModelKind::VC, true},
                                         Case{ModelKind::VCref, false}, Case{ModelKind::VCref, true}),
                         case_name);

// CCsub and PRB leave unloaded distal subsegments out of their unknowns: with only segment 1's
// tendons pulled, a tip wrench adds unknowns and is linearised in the larger system. CCsub: against
// full-solve differences (one-sided at the zero tensions). PRB: a straight
// subsegment's bending plane is a polar angle without derivative, so nothing is reported (the
// linearisation there gave a compliance 40 % off).
TEST(DifferentialKinematicsLumped, UnloadedDistalSegmentIsLinearisedInTheLargerSystem) {
  for (ModelKind kind : {ModelKind::CCsub, ModelKind::PRB}) {
    Scene s = test_scene(kind, false);
    s.actuation.values = {2.0, 0.5, 0.0, 0.0};
    const auto model = make_model(kind, s);
    const Solution base = solve_with_dk(*model, s);
    ASSERT_TRUE(base.converged()) << base.summary.message;
    if (kind == ModelKind::PRB) {
      EXPECT_EQ(base.tip_jacobian.size(), 0);
      EXPECT_EQ(base.tip_compliance.size(), 0);
      continue;
    }
    ASSERT_EQ(base.tip_compliance.cols(), 6) << to_string(kind);
    const Mat6X J_fd = full_solve_differences(*model, s.input(), s.solver, base, 0, 4, {1e-4, 1e-4, 1e-4, 1e-4});
    const Mat6X C_fd =
        full_solve_differences(*model, s.input(), s.solver, base, 4, 6, {1e-4, 1e-4, 1e-4, 1e-5, 1e-5, 1e-5});
    EXPECT_LT(relative_error(base.tip_jacobian, J_fd), 1e-6) << to_string(kind);
    EXPECT_LT(relative_error(base.tip_compliance, C_fd), 1e-6) << to_string(kind);
  }
}

// A tendon at 0 N is differentiated one-sided (it cannot push; VC drops it): VC under a tip
// wrench with segment 2's tendons slack, against one-sided full-solve differences.
TEST(DifferentialKinematicsVc, ZeroTensionIsOneSided) {
  Scene s = test_scene(ModelKind::VC, true);
  s.actuation.values = {2.0, 0.5, 0.0, 0.0};
  const auto model = make_model(ModelKind::VC, s);
  const Solution base = solve_with_dk(*model, s);
  ASSERT_TRUE(base.converged()) << base.summary.message;
  ASSERT_EQ(base.tip_jacobian.cols(), 4);
  const Mat6X J_fd = full_solve_differences(*model, s.input(), s.solver, base, 0, 4, std::vector<double>(4, 1e-4));
  const double e = relative_error(base.tip_jacobian, J_fd);
  std::printf("vc with slack tendons: Jacobian %.2e\n", e);
  EXPECT_LT(e, 1e-6);
}

// CC from tensions on a one-segment robot (Kirchhoff rod) is an arc of curvature
// kappa = -sum_k T_k y_k / EI about the base x axis: tip (0, (cos kL - 1) / k, sin kL / k), tip
// rotation rot_x(kappa L). Its Jacobian is d tip / d kappa times d kappa / d T_k = -y_k / EI.
TEST(DifferentialKinematicsCc, MatchesClosedFormDerivative) {
  Scene s = paper::scene(10, 1, "cc");
  s.robot.segments.resize(1);
  s.effects.shear_extension = false;
  s.actuation.values = {2.0, 0.5};
  s.solver.differential_kinematics = true;
  const Solution sol = solve(s);
  ASSERT_TRUE(sol.converged()) << sol.summary.message;
  ASSERT_EQ(sol.tip_jacobian.rows(), 6);
  ASSERT_EQ(sol.tip_jacobian.cols(), 2);
  EXPECT_EQ(sol.tip_compliance.size(), 0);  // CC has no statics of external loads

  const double EI = s.robot.backbone.effective_stiffness().EI, L = s.robot.segments[0].length;
  const auto& tendons = s.robot.segments[0].tendons;
  const double kappa = -(2.0 * tendons[0].y + 0.5 * tendons[1].y) / EI;
  const double S = std::sin(kappa * L), C = std::cos(kappa * L);
  EXPECT_LT((sol.tip().p - Vec3(0, (C - 1) / kappa, S / kappa)).norm(), 1e-12);  // the arc itself
  Eigen::Matrix<double, 6, 1> d_dkappa;
  d_dkappa << 0, (-L * S * kappa - (C - 1)) / (kappa * kappa), (L * C * kappa - S) / (kappa * kappa), L, 0, 0;
  Mat6X expected(6, 2);
  for (int k = 0; k < 2; ++k) expected.col(k) = d_dkappa * (-tendons[static_cast<std::size_t>(k)].y / EI);
  const double e = relative_error(sol.tip_jacobian, expected);
  std::printf("CC closed form: relative error %.2e\n", e);
  EXPECT_LT(e, 1e-8);
}

// CC from displacements: the Jacobian is with respect to the displacements (m per m).
TEST(DifferentialKinematicsCc, DisplacementInputMatchesFiniteDifferences) {
  Scene s = paper::scene(10, 1, "cc");
  s.actuation.kind = Actuation::Kind::Displacements;
  s.actuation.values = {0.002, -0.002, 0.001, -0.0005};
  const auto model = make_model(ModelKind::CC, s);
  const Solution base = solve_with_dk(*model, s);
  ASSERT_TRUE(base.converged()) << base.summary.message;
  ASSERT_EQ(base.tip_jacobian.cols(), 4);
  const Mat6X fd = full_solve_differences(*model, s.input(), s.solver, base, 0, 4, std::vector<double>(4, 1e-6));
  EXPECT_LT(relative_error(base.tip_jacobian, fd), 1e-6);
}

// The JSON output carries both matrices as lists of rows when computed, neither otherwise.
TEST(DifferentialKinematicsJson, WritesMatricesWhenPresent) {
  Scene s = paper::scene(5, 2, "prb");
  s.loads.tip_force = Vec3(0, 0.1, 0);
  s.solver.differential_kinematics = true;
  const Solution sol = solve(s);
  ASSERT_TRUE(sol.converged());
  const auto j = nlohmann::json::parse(solution_to_json(sol));
  ASSERT_TRUE(j.contains("tip_jacobian") && j.contains("tip_compliance"));
  ASSERT_EQ(j["tip_jacobian"].size(), 6u);
  ASSERT_EQ(j["tip_jacobian"][0].size(), 4u);
  ASSERT_EQ(j["tip_compliance"][5].size(), 6u);
  EXPECT_EQ(j["tip_compliance"][1][1].get<double>(), sol.tip_compliance(1, 1));
  s.solver.differential_kinematics = false;
  const auto k = nlohmann::json::parse(solution_to_json(solve(s)));
  EXPECT_FALSE(k.contains("tip_jacobian") || k.contains("tip_compliance"));
}

}  // namespace
