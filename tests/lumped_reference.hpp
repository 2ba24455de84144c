// Reader of tests/data/reference_ccsub_prb.csv (outputs of the paper's own code for CCsub and
// PRB), shared by test_model_ccsub.cpp and test_model_prb.cpp.
#pragma once

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tdcr/core/scene.hpp"
#include "tdcr/core/types.hpp"
#include "tdcr/models/lumped_model.hpp"
#include "tdcr/models/static_model.hpp"

namespace lumped_reference {

using tdcr::Frame;
using tdcr::Vec3;

// One row of tests/data/reference_ccsub_prb.csv (outputs of the paper's code).
struct RefRow {
  std::string source, model;
  int id = 0, n = 0;
  double T[4] = {}, F[3] = {}, residual = 0.0;
  Frame tip;
};

inline std::vector<RefRow> load_reference() {
  std::ifstream in(std::string(TDCR_TEST_DATA_DIR) + "/reference_ccsub_prb.csv");
  std::vector<RefRow> rows;
  std::string line;
  std::getline(in, line);  // provenance comment
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    std::vector<std::string> c;
    std::string cell;
    while (std::getline(ss, cell, ',')) c.push_back(cell);
    if (c.size() < 24) continue;
    RefRow r;
    r.source = c[0];
    r.id = std::stoi(c[1]);
    r.model = c[2];
    r.n = std::stoi(c[3]);
    for (int k = 0; k < 4; ++k) r.T[k] = std::stod(c[4 + k]);
    for (int k = 0; k < 3; ++k) r.F[k] = std::stod(c[8 + k]);
    r.residual = std::stod(c[11]);
    r.tip.p = Vec3(std::stod(c[12]), std::stod(c[13]), std::stod(c[14]));
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) r.tip.R(i, j) = std::stod(c[15 + 3 * i + j]);
    rows.push_back(r);
  }
  return rows;
}

// The banded formulation (disk poses and wrenches as unknowns) solves the same equations as the
// recursive one: the same tip (1e-9 m: both converge to 1e-10 scaled residuals), and one
// Solution layout, so each formulation's answer warm-starts the other in at most one iteration.
template <class Model>
void expect_banded_matches_recursive(const tdcr::Scene& s) {
  using tdcr::LumpedFormulation;
  using tdcr::Solution;
  const Model rec(s.robot, s.effects, LumpedFormulation::Recursive);
  const Model band(s.robot, s.effects, LumpedFormulation::Banded);
  auto wr = rec.make_workspace();
  auto wb = band.make_workspace();
  const Solution a = tdcr::solve(rec, *wr, s.input(), s.solver);
  const Solution b = tdcr::solve(band, *wb, s.input(), s.solver);
  ASSERT_TRUE(a.converged()) << a.summary.message;
  ASSERT_TRUE(b.converged()) << b.summary.message;
  EXPECT_EQ(b.summary.linear_solver, "klu");
  EXPECT_EQ(b.unknowns.size(), a.unknowns.size());
  EXPECT_LT((a.tip().p - b.tip().p).norm(), 1e-9);
  EXPECT_LT((a.unknowns - b.unknowns).cwiseAbs().maxCoeff(), 1e-6);
  const Solution b2 = tdcr::solve(band, *wb, s.input(), s.solver, &a);
  ASSERT_TRUE(b2.converged());
  EXPECT_LE(b2.summary.iterations, 1);
  EXPECT_LT((b2.tip().p - a.tip().p).norm(), 1e-9);
}

// Automatic with at least 100 loaded subsegments (reduced Newton steps on the banded system)
// matches the recursive formulation with dense LU, in its number of iterations.
template <class Model>
void expect_reduced_matches_recursive(const tdcr::Scene& s) {
  using tdcr::LumpedFormulation;
  const Model rec(s.robot, s.effects, LumpedFormulation::Recursive);
  const Model aut(s.robot, s.effects, LumpedFormulation::Automatic);
  auto wr = rec.make_workspace();
  auto wa = aut.make_workspace();
  const tdcr::Solution a = tdcr::solve(rec, *wr, s.input(), s.solver);
  const tdcr::Solution b = tdcr::solve(aut, *wa, s.input(), s.solver);
  ASSERT_TRUE(a.converged()) << a.summary.message;
  ASSERT_TRUE(b.converged()) << b.summary.message;
  EXPECT_EQ(a.summary.linear_solver, "dense");
  EXPECT_EQ(b.summary.linear_solver, "system");
  EXPECT_EQ(b.summary.unknowns, a.summary.unknowns);
  EXPECT_LE(b.summary.iterations, a.summary.iterations + 1);
  EXPECT_LT((a.tip().p - b.tip().p).norm(), 1e-9);
}

}  // namespace lumped_reference
