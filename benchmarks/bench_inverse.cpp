// Wall time of the inverse solve (tdcr/models/inverse_solve.hpp) on round trips: tension solve ->
// tip -> inverse solve from zero tensions, default options. The draws are those of
// tests/test_inverse_solve.cpp (InverseRoundTrip): the paper robot (examples/paper_robot_vc.json)
// as CCsub, PRB, VC and VCref at n = 5, 10, 20 disks per segment, stiff (Table 3) and soft (E / 10),
// four tip loads (none; 0.3 N along +y, along +x across the bending plane, and oblique, times the
// stiffness factor), without and with tendon friction 0.1; tensions uniform in [0, 0.7 T_M].
// Then examples/helical_tendon.json (three draws per model), and the reported cases of
// tests/test_inverse_solve.cpp (InverseReports: targets the solve before its rework missed). Each
// row: the median wall time of
// --reps inverse solves (each on a fresh workspace), the iterations and forward solves, the tip
// error, the tensions' resolution on the target, whether the minimum norm was verified. A summary
// per model: median and largest time, the rows above 1 s, and the rows whose answer has a larger
// norm than the generating tensions (another local minimum of |T|).
// Usage: bench_inverse [--quick] [--reps N] [--csv FILE]
//   --quick: n = 10 only, stiff, unloaded and one tip force, no friction (the ctest smoke run).
// Exit status 1 if a round trip missed the target (1e-9 m) or its minimum norm was not verified.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "bench_common.hpp"
#include "tdcr/core/paper_robot.hpp"
#include "tdcr/core/scene_io.hpp"
#include "tdcr/models/inverse_solve.hpp"

using namespace tdcr;

namespace {

struct Row {
  std::string model, scene;
  double ms = 0.0;
  int iterations = 0, forward_solves = 0;
  double position_error = 0.0, norm = 0.0, generating_norm = 0.0, resolution = 0.0;
  bool converged = false, minimum_norm = false;
};

double norm(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x * x;
  return std::sqrt(s);
}

Row round_trip(const Scene& s, const std::vector<double>& T, const std::string& label, int reps) {
  Row row;
  row.model = s.model;
  row.scene = label;
  row.generating_norm = norm(T);
  const auto model = make_model(parse_model_kind(s.model), s);
  auto ws = model->make_workspace();
  ModelInput in = s.input();
  in.actuation.values = T;
  const Solution f = solve(*model, *ws, in, s.solver);
  if (!f.converged()) return row;
  InverseTarget target;
  target.position = f.tip().p;
  ModelInput start = s.input();
  start.actuation.values.assign(T.size(), 0.0);
  std::vector<double> ms;
  InverseResult r;
  for (int k = 0; k < reps; ++k) {
    auto w = model->make_workspace();
    const auto t0 = std::chrono::steady_clock::now();
    r = inverse_solve(*model, *w, start, target, s.solver);
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(ms.begin(), ms.end());
  row.ms = ms[ms.size() / 2];
  row.iterations = r.iterations;
  row.forward_solves = r.forward_solves;
  row.position_error = r.position_error;
  row.norm = norm(r.tensions);
  row.resolution = r.tension_resolution;
  row.converged = r.converged();
  row.minimum_norm = r.minimum_norm;
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false;
  int reps = 3;
  std::string csv_path;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--quick")) quick = true;
    else if (!std::strcmp(argv[i], "--reps") && i + 1 < argc) reps = std::max(1, std::atoi(argv[++i]));
    else if (!std::strcmp(argv[i], "--csv") && i + 1 < argc) csv_path = argv[++i];
    else {
      std::fprintf(stderr, "usage: bench_inverse [--quick] [--reps N] [--csv FILE]\n");
      return 2;
    }
  }
  const std::string examples = std::string(TDCR_SOURCE_DIR) + "/examples/";
  const Vec3 forces[] = {Vec3::Zero(), Vec3(0.0, 0.3, 0.0), Vec3(0.3, 0.0, 0.0), Vec3(-0.15, 0.09, -0.24)};
  const char* load_names[] = {"unloaded", "force_y", "force_x", "force_oblique"};
  std::vector<Row> rows;
  std::printf("%-6s %-36s %9s %6s %7s %10s %9s %9s %9s %s\n", "model", "scene", "time_ms", "iters", "solves",
              "tip_err_m", "|T|_N", "|T0|_N", "resol_N", "min_norm");
  auto print = [&](const Row& r) {
    std::printf("%-6s %-36s %9.1f %6d %7d %10.2e %9.4g %9.4g %9.2g %s%s\n", r.model.c_str(), r.scene.c_str(), r.ms,
                r.iterations, r.forward_solves, r.position_error, r.norm, r.generating_norm, r.resolution,
                r.minimum_norm ? "verified" : "no", r.converged ? "" : "  NOT CONVERGED");
    std::fflush(stdout);
    rows.push_back(r);
  };
  for (const char* m : {"ccsub", "prb", "vc", "vcref"})
    for (int n : quick ? std::vector<int>{10} : std::vector<int>{5, 10, 20})
      for (bool soft : quick ? std::vector<bool>{false} : std::vector<bool>{false, true})
        for (bool friction : quick ? std::vector<bool>{false} : std::vector<bool>{false, true})
          for (int load = 0; load < (quick ? 2 : 4); ++load) {
            Scene s = load_scene(examples + "paper_robot_vc.json");
            s.model = m;
            const double k = soft ? 0.1 : 1.0;
            for (Segment& seg : s.robot.segments) seg.disks = n;
            s.robot.backbone.youngs_modulus *= k;
            s.loads.tip_force = k * forces[load];
            s.effects.tendon_friction.coefficient = friction ? 0.1 : 0.0;
            // The seeds of tests/test_inverse_solve.cpp (InverseRoundTrip).
            std::mt19937 rng(1000u * static_cast<unsigned>(n) + 10u * static_cast<unsigned>(load) +
                             (friction ? 100u : 0u) + (soft ? 1u : 7u));
            std::uniform_real_distribution<double> u(0.0, 0.7 * paper::max_tension(s.robot));
            std::vector<double> T(4);
            for (double& t : T) t = u(rng);
            print(round_trip(s, T,
                             "n" + std::to_string(n) + (soft ? "_soft" : "_stiff") + (friction ? "_friction_" : "_") +
                                 load_names[load],
                             reps));
          }
  if (!quick) {
    for (const char* m : {"ccsub", "prb", "vc", "vcref"}) {
      Scene s = load_scene(examples + "helical_tendon.json");
      s.model = m;
      std::mt19937 rng(31);
      std::uniform_real_distribution<double> u(0.0, 3.0);
      for (int draw = 0; draw < 3; ++draw) print(round_trip(s, {u(rng), u(rng)}, "helical_" + std::to_string(draw), reps));
    }
    // The reported cases (tests/test_inverse_solve.cpp, InverseReports).
    struct Report {
      const char* model;
      int n;
      double stiffness, friction;
      Vec3 force;
      std::vector<double> T;
      const char* label;
    };
    const Report reports[] = {
        {"vcref", 20, 1.0, 0.0, Vec3(0.3, 0.0, 0.0),
         {3.1632803679655708, 0.22469750489478771, 1.5490907353853289, 2.7525984383441457}, "report_n20_force_x"},
        {"ccsub", 5, 1.0, 0.1, Vec3::Zero(),
         {0.3712499569559532, 3.5588327626239464, 2.8550477351341064, 2.0715941201045514}, "report_n5_friction"},
        {"vcref", 10, 1.0, 0.1, Vec3(0.2, 0.2, 0.0),
         {1.9028511707842395, 5.1124050446056488, 1.4442107648639084, 4.1291949991455636}, "report_n10_friction_force_xy"},
        {"prb", 20, 0.1, 0.0, Vec3(0.03, 0.0, 0.0),
         {0.35830252388137068, 0.296003138746812, 0.36487728293695204, 0.29386206260523962}, "report_n20_soft_force_x"},
    };
    for (const Report& rep : reports) {
      Scene s = load_scene(examples + "paper_robot_vc.json");
      s.model = rep.model;
      for (Segment& seg : s.robot.segments) seg.disks = rep.n;
      s.robot.backbone.youngs_modulus *= rep.stiffness;
      s.loads.tip_force = rep.force;
      s.effects.tendon_friction.coefficient = rep.friction;
      print(round_trip(s, rep.T, rep.label, reps));
    }
  }

  std::printf("\n%-6s %6s %12s %12s %10s %8s %14s %14s\n", "model", "rows", "median_ms", "max_ms", "over_1s", "failed",
              "above_T0_norm", "max_norm/|T0|");
  bool ok = true;
  std::map<std::string, std::vector<const Row*>> by_model;
  for (const Row& r : rows) by_model[r.model].push_back(&r);
  for (const auto& [name, list] : by_model) {
    std::vector<double> t;
    int failed = 0, slow = 0, above = 0;
    double ratio = 0.0;
    for (const Row* r : list) {
      t.push_back(r->ms);
      if (!r->converged || r->position_error > 1e-9 || !r->minimum_norm) ++failed;
      if (r->ms > 1000.0) ++slow;
      if (r->norm > r->generating_norm * (1.0 + 1e-6)) ++above;
      if (r->generating_norm > 0.0) ratio = std::max(ratio, r->norm / r->generating_norm);
    }
    std::sort(t.begin(), t.end());
    std::printf("%-6s %6zu %12.1f %12.1f %10d %8d %14d %14.3f\n", name.c_str(), list.size(), t[t.size() / 2], t.back(),
                slow, failed, above, ratio);
    ok = ok && failed == 0;
  }
  if (!csv_path.empty()) {
    bench::Csv csv(csv_path,
                   "model,scene,time_ms,iterations,forward_solves,tip_error_m,norm_N,generating_norm_N,"
                   "tension_resolution_N,converged,minimum_norm");
    for (const Row& r : rows)
      csv.row(r.model, r.scene, r.ms, r.iterations, r.forward_solves, r.position_error, r.norm, r.generating_norm,
              r.resolution, r.converged ? 1 : 0, r.minimum_norm ? 1 : 0);
  }
  return ok ? 0 : 1;
}
