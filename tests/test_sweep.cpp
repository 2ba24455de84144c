// Sweeps: sweep-file parsing and its bad-input errors, and the CSV output's independence of
// threads, shards and interruptions.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "tdcr/core/error.hpp"
#include "tdcr/sweep/sweep_run.hpp"
#include "fixed_mesh_settings.hpp"

namespace {

namespace fs = std::filesystem;
const std::string kExamples = TDCR_EXAMPLES_DIR;
const std::string kTipForceScene = kExamples + "/paper_robot_tip_force.json";

std::string tmp(const std::string& name) {
  const fs::path dir = fs::path(TDCR_BINARY_DIR) / "test_sweep_tmp";
  fs::create_directories(dir);
  fs::remove(dir / name);
  return (dir / name).string();
}

std::string read(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// 8 x 8 = 64 samples (two blocks), VC and CCsub, on the paper robot with a tip force.
std::string grid_sweep() {
  return R"({"scene": ")" + kTipForceScene + R"(", "models": ["vc", "ccsub"],
    "axes": [{"field": "actuation.tensions[0]", "from": 0, "to": 4, "count": 8},
             {"field": "loads.tip_force[1]", "from": 0, "to": 0.5, "count": 8}]})";
}


/// The rows of a sweep CSV (after the header lines).
std::vector<std::vector<std::string>> rows_of(const std::string& path) {
  std::istringstream in(read(path));
  std::vector<std::vector<std::string>> rows;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line.rfind("sample,", 0) == 0) continue;
    // CSV: a quoted field may hold commas.
    std::vector<std::string> cells(1);
    bool quoted = false;
    for (std::size_t i = 0; i < line.size(); ++i) {
      if (line[i] == '"' && quoted && i + 1 < line.size() && line[i + 1] == '"') cells.back() += line[++i];
      else if (line[i] == '"') quoted = !quoted;
      else if (line[i] == ',' && !quoted) cells.emplace_back();
      else cells.back() += line[i];
    }
    rows.push_back(cells);
  }
  return rows;
}

/// Same samples, inputs, models and statuses; tip positions within `tol` m and tip rotations
/// within `rot_tol` rad (`tol` if not given).
void expect_same_rows(const std::string& a, const std::string& b, double tol = 1e-9, double rot_tol = 0.0) {
  if (rot_tol == 0.0) rot_tol = tol;
  const auto ra = rows_of(a), rb = rows_of(b);
  ASSERT_EQ(ra.size(), rb.size());
  ASSERT_FALSE(ra.empty());
  for (std::size_t r = 0; r < ra.size(); ++r) {
    ASSERT_EQ(ra[r].size(), rb[r].size());
    const std::size_t n = ra[r].size();
    // sample, 2 axes, model, status (columns 0..4) exactly; tip and rotation (n-8 .. n-3) close.
    for (std::size_t c = 0; c < 5; ++c) EXPECT_EQ(ra[r][c], rb[r][c]) << "row " << r << " column " << c;
    for (std::size_t c = n - 8; c < n - 2; ++c)
      EXPECT_NEAR(std::stod(ra[r][c]), std::stod(rb[r][c]), c < n - 5 ? tol : rot_tol) << "row " << r << " column " << c;
  }
}

tdcr::SweepSpec grid() { return tdcr::parse_sweep(grid_sweep(), "grid"); }

TEST(SweepFile, GridSamplesAreTheCartesianProductLastAxisFastest) {
  const tdcr::SweepSpec spec = grid();
  ASSERT_EQ(spec.sample_count(), 64u);
  std::vector<double> v;
  spec.sample_values(9, v);  // row 1 of the first axis, column 1 of the second
  EXPECT_DOUBLE_EQ(v[0], 4.0 / 7.0);
  EXPECT_DOUBLE_EQ(v[1], 0.5 / 7.0);
  EXPECT_EQ(spec.axes[0].target, tdcr::SweepAxis::Target::Tension);
  EXPECT_EQ(spec.axes[1].target, tdcr::SweepAxis::Target::TipForce);
  const tdcr::ModelInput in = spec.input_with(spec.base, v);
  EXPECT_DOUBLE_EQ(in.actuation.values[0], 4.0 / 7.0);
  EXPECT_DOUBLE_EQ(in.loads.tip_force[1], 0.5 / 7.0);
}

TEST(SweepFile, RandomSamplesAreSeededAndInRange) {
  const std::string text = R"({"scene": ")" + kTipForceScene + R"(", "models": ["vc"], "sampling": "random",
    "samples": 1000, "seed": 7, "axes": [{"field": "actuation.tensions[1]", "from": 1, "to": 2},
    {"field": "robot.backbone.youngs_modulus", "values": [1e11, 2e11]}]})";
  const tdcr::SweepSpec a = tdcr::parse_sweep(text), b = tdcr::parse_sweep(text);
  EXPECT_EQ(a.sample_count(), 1000u);
  EXPECT_EQ(a.hash, b.hash);
  std::vector<double> va, vb;
  double sum = 0.0;
  int stiff = 0;
  for (std::uint64_t i = 0; i < 1000; ++i) {
    a.sample_values(i, va);
    b.sample_values(i, vb);
    ASSERT_EQ(va, vb);
    ASSERT_GE(va[0], 1.0);
    ASSERT_LT(va[0], 2.0);
    sum += va[0];
    stiff += va[1] == 2e11;
  }
  EXPECT_NEAR(sum / 1000, 1.5, 0.03);  // uniform: mean 1.5, standard error 0.009
  EXPECT_NEAR(stiff, 500, 60);
  // A robot axis rebuilds the scene with the value set.
  a.sample_values(3, va);
  EXPECT_EQ(a.scene_with(va).robot.backbone.youngs_modulus, va[1]);
  // Another seed is another sweep.
  std::string other = text;
  other.replace(other.find("\"seed\": 7"), 9, "\"seed\": 8");
  EXPECT_NE(tdcr::parse_sweep(other).hash, a.hash);
}

/// Mean distance between consecutive samples of `order`, each axis normalised to [0, 1].
double mean_step(const tdcr::SweepSpec& spec, const std::vector<std::uint64_t>& order) {
  std::vector<double> a, b;
  double sum = 0.0;
  for (std::size_t k = 1; k < order.size(); ++k) {
    spec.sample_values(order[k - 1], a);
    spec.sample_values(order[k], b);
    double d2 = 0.0;
    for (std::size_t x = 0; x < a.size(); ++x) {
      const double span = spec.axes[x].values.empty() ? spec.axes[x].to - spec.axes[x].from : 1.0;
      d2 += std::pow((b[x] - a[x]) / span, 2);
    }
    sum += std::sqrt(d2);
  }
  return sum / double(order.size() - 1);
}

TEST(SweepFile, RandomSamplesAreSolvedInNeighbourOrder) {
  const std::string head = R"({"scene": ")" + kTipForceScene + R"(", "models": ["vc"], "sampling": "random",
    "samples": 3000, "seed": 3, )";
  const std::string axes2 = R"("axes": [{"field": "actuation.tensions[0]", "from": 0, "to": 5},
    {"field": "loads.tip_force[1]", "from": 0, "to": 0.5}]})";
  const tdcr::SweepSpec spec = tdcr::parse_sweep(head + axes2);
  const std::uint64_t block = tdcr::sweep_block_size(spec);
  EXPECT_GT(block, tdcr::kSweepBlock);
  // The last block is partial; its order is a permutation of its samples.
  const std::uint64_t first = 3000 / block * block;
  std::vector<std::uint64_t> order, natural;
  tdcr::sweep_solve_order(spec, first, 3000, order);
  tdcr::sweep_solve_order(tdcr::parse_sweep(head + R"("order": "sample", )" + axes2), first, 3000, natural);
  ASSERT_EQ(order.size(), 3000 - first);
  std::vector<std::uint64_t> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_EQ(sorted, natural);  // "order": "sample" keeps sample order
  // Along the Hilbert curve through n uniform points of the unit square a step is about
  // 1/sqrt(n) (here about 0.04); between unsorted samples about 0.52.
  EXPECT_GT(mean_step(spec, natural), 0.4);
  EXPECT_LT(mean_step(spec, order), 2.0 / std::sqrt(double(order.size())));
  // One input axis: sorted by value. A grid keeps grid order.
  const tdcr::SweepSpec one = tdcr::parse_sweep(head + R"("axes": [{"field": "loads.tip_force[2]", "from": 0.5, "to": -0.5}]})");
  tdcr::sweep_solve_order(one, 0, tdcr::sweep_block_size(one), order);
  std::vector<double> a, b;
  for (std::size_t k = 1; k < order.size(); ++k) {
    one.sample_values(order[k - 1], a);
    one.sample_values(order[k], b);
    ASSERT_LE(a[0], b[0]);
  }
  tdcr::sweep_solve_order(grid(), 0, 32, order);
  for (std::size_t k = 0; k < order.size(); ++k) EXPECT_EQ(order[k], k);
  // Scene axes first: a model serves a run of equal scenes (two moduli, two runs).
  const tdcr::SweepSpec mixed = tdcr::parse_sweep(head + R"("axes": [{"field": "actuation.tensions[1]", "from": 1, "to": 2},
    {"field": "robot.backbone.youngs_modulus", "values": [1e11, 2e11]}]})");
  tdcr::sweep_solve_order(mixed, 0, tdcr::sweep_block_size(mixed), order);
  int changes = 0;
  for (std::size_t k = 1; k < order.size(); ++k) {
    mixed.sample_values(order[k - 1], a);
    mixed.sample_values(order[k], b);
    changes += a[1] != b[1];
  }
  EXPECT_EQ(changes, 1);
}

TEST(SweepFile, RelativeScenePathIsTakenFromTheSweepFile) {
  const tdcr::SweepSpec spec = tdcr::load_sweep(kExamples + "/sweeps/tension_force_grid.json");
  EXPECT_EQ(spec.sample_count(), 45u);
  EXPECT_EQ(spec.models.size(), 2u);
  EXPECT_EQ(tdcr::load_sweep(kExamples + "/sweeps/stiffness_design.json").sample_count(), 15u);
}

// Mixed input (examples/paper_robot_displacements.json: tendons 0-2 by displacement, 3 by
// tension): an axis sweeps the list that gives its tendon, and only that one.
TEST(SweepFile, MixedInputAxesFollowEachTendonsKind) {
  const std::string scene = R"({"scene": ")" + kExamples + "/paper_robot_displacements.json" + R"(", "models": ["vc"], )";
  const tdcr::SweepSpec ok = tdcr::parse_sweep(
      scene + R"("axes": [{"field": "actuation.displacements[1]", "values": [-0.003, -0.002]},
                          {"field": "actuation.tensions[3]", "values": [0.1, 0.2, 0.3]}]})",
      "mixed.json", "/nonexistent");
  EXPECT_EQ(ok.sample_count(), 6u);
  EXPECT_THROW(tdcr::parse_sweep(scene + R"("axes": [{"field": "actuation.tensions[0]", "values": [1]}]})", "mixed.json",
                                 "/nonexistent"),
               tdcr::InputError);
}

struct BadSweep {
  const char* what;
  std::string text;
  std::string field;  // InputError::field()
  std::string value;  // a part of InputError::value()
};

TEST(SweepFile, BadInputNamesTheFieldAndTheValue) {
  const std::string scene = R"("scene": ")" + kTipForceScene + R"(", )";
  const std::string ok_axis = R"({"field": "actuation.tensions[0]", "values": [0, 1]})";
  const std::vector<BadSweep> cases = {
      {"unknown top-level key", "{" + scene + R"("models": ["vc"], "axis": [], "axes": [)" + ok_axis + "]}", "axis", ""},
      {"unknown axis key", "{" + scene + R"("models": ["vc"], "axes": [{"field": "actuation.tensions[0]", "values": [1], "step": 1}]})",
       "axes[0].step", ""},
      {"tendon that does not exist", "{" + scene + R"("models": ["vc"], "axes": [{"field": "actuation.tensions[4]", "values": [1]}]})",
       "actuation.tensions[4]", ""},
      {"robot key that does not exist", "{" + scene + R"("models": ["vc"], "axes": [{"field": "robot.backbone.young", "values": [1e11]}]})",
       "robot.backbone.young", "1e+11"},
      {"segment that does not exist", "{" + scene + R"("models": ["vc"], "axes": [{"field": "robot.segments[2].length", "values": [0.05]}]})",
       "robot.segments[2].length", "0.05"},
      {"negative tension", "{" + scene + R"("models": ["vc"], "axes": [{"field": "actuation.tensions[1]", "from": -1, "to": 1, "count": 3}]})",
       "actuation.tensions[1]", "-1"},
      {"Poisson ratio above 0.5", "{" + scene + R"("models": ["vc"], "axes": [{"field": "robot.backbone.poisson_ratio", "values": [0.3, 0.6]}]})",
       "robot.backbone.poisson_ratio", "0.6"},
      {"load component that does not exist", "{" + scene + R"("models": ["vc"], "axes": [{"field": "loads.tip_force[3]", "values": [1]}]})",
       "loads.tip_force[3]", ""},
      {"model that refuses the loads", "{" + scene + R"("models": ["cc"], "axes": [)" + ok_axis + "]}", "actuation.tensions[0]", "0"},
      {"unknown model", "{" + scene + R"("models": ["vcc"], "axes": [)" + ok_axis + "]}", "models[0]", "vcc"},
      {"scene file that does not exist", R"({"scene": "no_such_scene.json", "models": ["vc"], "axes": [)" + ok_axis + "]}", "scene",
       "no_such_scene.json"},
      {"random without a seed", "{" + scene + R"("models": ["vc"], "sampling": "random", "samples": 5, "axes": [)" + ok_axis + "]}",
       "seed", ""},
      {"grid range without count", "{" + scene + R"("models": ["vc"], "axes": [{"field": "actuation.tensions[0]", "from": 0, "to": 1}]})",
       "axes[0].count", ""},
      {"displacement of a tendon given by tension",
       "{" + scene + R"("models": ["vc"], "axes": [{"field": "actuation.displacements[0]", "values": [0.001]}]})",
       "actuation.displacements[0]", ""},
      {"not a sweepable field", "{" + scene + R"("models": ["vc"], "axes": [{"field": "model", "values": [1]}]})", "axes[0].field",
       "model"},
      // Numbers that overflow a double, named by their path in the sweep file (not an internal error).
      {"range end that overflows a double",
       "{" + scene + R"("models": ["vc"], "axes": [{"field": "actuation.tensions[0]", "from": 0, "to": 1e999, "count": 3}]})",
       "axes[0].to", "1e999"},
      {"value that overflows a double",
       "{" + scene + R"("models": ["vc"], "axes": [{"field": "actuation.tensions[0]", "values": [1, -1e999]}]})",
       "axes[0].values[1]", "-1e999"},
      {"inline scene number that overflows a double",
       R"({"scene": {"robot": {"segments": [{"length": 0.05, "disks": 2, "tendons": [{"x": 0, "y": 0.008}]}]},
                     "actuation": {"tensions": [1e999]}},
           "models": ["vc"], "axes": [)" + ok_axis + "]}",
       "scene.actuation.tensions[0]", "1e999"},
      {"range wider than a double", "{" + scene + R"("models": ["vc"], "axes": [{"field": "loads.tip_force[0]", "from": -1e308, "to": 1e308, "count": 3}]})",
       "axes[0].to", "1e+308"},
      // Indices too large for any integer type: fields that do not exist (was std::stoul's out_of_range).
      {"tendon index of 23 digits",
       "{" + scene + R"("models": ["vc"], "axes": [{"field": "actuation.tensions[99999999999999999999999]", "values": [1]}]})",
       "actuation.tensions[99999999999999999999999]", ""},
      {"segment index of 23 digits",
       "{" + scene + R"("models": ["vc"], "axes": [{"field": "robot.segments[99999999999999999999999].length", "values": [0.05]}]})",
       "robot.segments[99999999999999999999999].length", "0.05"},
      {"duplicate key", "{" + scene + R"("models": ["vc"], "models": ["cc"], "axes": [)" + ok_axis + "]}", "models", "models"},
  };
  for (const BadSweep& c : cases) {
    try {
      tdcr::parse_sweep(c.text, "bad.json", "/nonexistent");
      ADD_FAILURE() << c.what << ": accepted";
    } catch (const tdcr::InputError& e) {
      EXPECT_EQ(e.field(), c.field) << c.what << ": " << e.what();
      EXPECT_NE(e.value().find(c.value), std::string::npos) << c.what << ": " << e.what();
    }
  }
}

TEST(SweepRun, ThreadsDoNotChangeTheRows) {
  const tdcr::SweepSpec spec = grid();
  const std::string one = tmp("t1.csv"), two = tmp("t2.csv");
  tdcr::SweepRunOptions o;
  o.threads = 1;
  EXPECT_EQ(tdcr::run_sweep(spec, one, o).samples_solved, 64u);
  o.threads = 2;
  tdcr::run_sweep(spec, two, o);
  // Two threads split the samples, so warm starts differ: each answer within the default tip
  // tolerance (1e-8 m here), so within twice it of the other.
  expect_same_rows(one, two, 2e-8);
  const auto rows = rows_of(one);
  ASSERT_EQ(rows.size(), 128u);  // 64 samples x 2 models, in sample order
  for (std::size_t r = 0; r < rows.size(); ++r) {
    EXPECT_EQ(std::stoul(rows[r][0]), r / 2);
    EXPECT_EQ(rows[r][3], r % 2 ? "ccsub" : "vc");
    EXPECT_EQ(rows[r][4], "converged");
  }
  // Sample 0 has no tension and no force: the straight robot, tip at (0, 0, 0.1).
  EXPECT_NEAR(std::stod(rows[0][8]), 0.1, 1e-9);
  EXPECT_NEAR(std::stod(rows[0][7]), 0.0, 1e-12);
  // A tip force along +y at zero tension bends the tip towards +y (sample 7: 0.5 N), less than
  // the linear cantilever's F L^3 / (3 EI) = 39 mm (a large deflection: F L^2 / EI = 1.2).
  const double linear = 0.5 * 1e-3 / (3 * 2.11e11 * M_PI * std::pow(0.0004, 4) / 4);
  EXPECT_LT(std::stod(rows[14][7]), linear);
  EXPECT_GT(std::stod(rows[14][7]), 0.8 * linear);
}

TEST(SweepRun, NeighbourOrderWritesTheRowsOfSampleOrder) {
  // Random samples solved along the Hilbert curve give the rows of a run in sample order: same
  // samples, inputs, models and statuses, in sample order. The tips agree to twice the default tip
  // tolerance (1e-7 of the length: 1e-8 m here): other warm starts stop on another mesh or at
  // another point within the tolerances, up to 1.1e-8 m apart here, so 3e-8 m. The tip tolerance
  // bounds positions, not rotations: warm steps that keep a predicted estimate stop on the
  // coarsest mesh within it, and the rotations of the two orders' answers then differ by up to
  // 5.2e-8 rad here (8.3e-9 m in position), so 1e-7 rad.
  const std::string head = R"({"scene": ")" + kTipForceScene + R"(", "models": ["vc", "ccsub"], "sampling": "random",
    "samples": 80, "seed": 5, )";
  const std::string axes = R"("axes": [{"field": "actuation.tensions[0]", "from": 0, "to": 5},
    {"field": "loads.tip_force[1]", "from": 0, "to": 0.5}]})";
  const std::string warm = tmp("warm.csv"), plain = tmp("plain.csv"), warm2 = tmp("warm2.csv");
  const tdcr::SweepSpec spec = tdcr::parse_sweep(head + axes);
  std::vector<std::uint64_t> order;
  tdcr::sweep_solve_order(spec, 0, 80, order);
  ASSERT_FALSE(std::is_sorted(order.begin(), order.end()));  // really solved out of order
  tdcr::SweepRunOptions o;
  o.threads = 1;
  tdcr::run_sweep(spec, warm, o);
  tdcr::run_sweep(tdcr::parse_sweep(head + R"("order": "sample", )" + axes), plain, o);
  expect_same_rows(warm, plain, 3e-8, 1e-7);
  const auto rows = rows_of(warm);
  ASSERT_EQ(rows.size(), 160u);
  for (std::size_t r = 0; r < rows.size(); ++r) {
    EXPECT_EQ(std::stoul(rows[r][0]), r / 2);
    EXPECT_EQ(rows[r][4], "converged");
  }
  // Threads and shards do not change the rows (the order is computed per block).
  o.threads = 2;
  tdcr::run_sweep(spec, warm2, o);
  expect_same_rows(warm, warm2, 3e-8, 1e-7);
}

TEST(SweepRun, MergedShardsEqualOneRun) {
  const tdcr::SweepSpec spec = grid();
  const std::string whole = tmp("whole.csv"), s0 = tmp("s0.csv"), s1 = tmp("s1.csv"), merged = tmp("merged.csv");
  tdcr::SweepRunOptions o;
  tdcr::run_sweep(spec, whole, o);
  o.shard = {1, 2};
  tdcr::run_sweep(spec, s1, o);
  // An incomplete shard is refused.
  EXPECT_THROW(tdcr::merge_sweep_shards(merged, {s1}), tdcr::InputError);
  o.shard = {0, 2};
  tdcr::run_sweep(spec, s0, o);
  EXPECT_THROW(tdcr::merge_sweep_shards(merged, {s0, s0}), tdcr::InputError);
  tdcr::merge_sweep_shards(merged, {s1, s0});
  expect_same_rows(whole, merged);
  const std::string a = read(whole), b = read(merged);
  EXPECT_EQ(a.substr(0, a.find('\n', a.find('\n') + 1)), b.substr(0, b.find('\n', b.find('\n') + 1)));
}

TEST(SweepRun, ResumeAfterATruncatedFileEqualsAFullRun) {
  const tdcr::SweepSpec spec = grid();
  const std::string full = tmp("full.csv"), cut = tmp("cut.csv");
  tdcr::run_sweep(spec, full);
  const std::string text = read(full);
  {
    std::ofstream out(cut);
    out << text.substr(0, text.size() * 3 / 5);  // cut inside a line, inside the second block
  }
  const tdcr::SweepRunStats s = tdcr::run_sweep(spec, cut);
  EXPECT_GT(s.first_sample, 32u);
  EXPECT_LT(s.first_sample, 64u);
  expect_same_rows(full, cut);
  // Finished: a rerun solves nothing.
  EXPECT_EQ(tdcr::run_sweep(spec, cut).samples_solved, 0u);
  // Another sweep into the same file is refused, naming the option and the file.
  std::string other = grid_sweep();
  other.replace(other.find("\"count\": 8"), 10, "\"count\": 9");
  try {
    tdcr::run_sweep(tdcr::parse_sweep(other), cut);
    ADD_FAILURE() << "a file of another sweep was resumed";
  } catch (const tdcr::InputError& e) {
    EXPECT_EQ(e.field(), "-o");
    EXPECT_EQ(e.value(), cut);
  }
}

TEST(SweepRun, AFailedSolveIsARowNotACrash) {
  // One Newton iteration cannot reach 200 N from the 30 N equilibrium.
  const std::string text = R"({"scene": {"robot": {"segments": [{"length": 0.1, "disks": 10,
      "tendons": [{"x": 0, "y": 0.008}]}]}, "actuation": {"tensions": [0]},
      "solver": {"max_iterations": 1, "continuation": false}},
    "models": ["vc"], "axes": [{"field": "actuation.tensions[0]", "values": [0, 30, 200]}]})";
  const std::string out = tmp("fail.csv");
  tdcr::run_sweep(tdcr::parse_sweep(text), out);
  const auto rows = rows_of(out);
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0][3], "converged");
  EXPECT_NE(rows[2][3], "converged");
  EXPECT_FALSE(rows[2][4].empty());  // the reason
}

}  // namespace
