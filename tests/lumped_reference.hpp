// Reader of tests/data/reference_ccsub_prb.csv (outputs of the paper's own code for CCsub and
// PRB), shared by test_model_ccsub.cpp and test_model_prb.cpp.
#pragma once

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tdcr/core/types.hpp"

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

}  // namespace lumped_reference
