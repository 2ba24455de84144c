// Solve time of the lumped static models CCsub and PRB on the paper's robot (Table 3), cold
// solves from each model's cold guess (fixed-point passes from the straight robot: 0-1 Newton
// iterations for these tendon-only configurations; one model and one workspace per row), against
// the paper's own code (reference/paper_code_timing.csv: configuration 2 = (T_M, 0, 0, 0), its
// straight guess, median of up to 100 cold solves). Usage: bench_lumped [--quick] [--reps N]
//
// Configuration 2 loads segment 1 only: segment 2 carries no load and is exactly straight, so
// tdcr leaves its subsegments out of the unknowns (the paper's code solves for them). Rows with
// configuration 5 = (0, 0, T_M, 0) load every subsegment and show the cost of the full system.
//
// Then a scaling sweep (n = 5..200 disks per segment; --quick: n = 5, 10, 20) on configuration 5
// without a tip force (the cold guesses are exact there for tendons alone: 0-1 Newton
// iterations), with a small one (tip_force: 0.054 N, load parameter L^2 |F| / EI = 0.13) and a
// large one (tip_0.5N: 0.5 N across the bending plane and along it, load parameter 1.2, the
// largest force of bench_loaded's cases): median time of the automatic formulation over --reps cold solves
// in one workspace (median_us), the first solve of that fresh workspace (first_us: also sizes
// buffers and analyses the sparsity pattern), the log-log slope of median_us vs n from n = 10 to
// 200, and the tip distance to the recursive (dense) formulation.
// Usage: bench_lumped [--quick] [--reps N] [--sweep-only]
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "bench_common.hpp"
#include "tdcr/core/paper_robot.hpp"
#include "tdcr/models/ccsub.hpp"
#include "tdcr/models/prb.hpp"

using namespace tdcr;

namespace {

std::unique_ptr<LumpedModel> lumped(const std::string& name, const Scene& s, LumpedFormulation f) {
  if (name == "ccsub") return std::make_unique<CcsubModel>(s.robot, s.effects, f);
  return std::make_unique<PrbModel>(s.robot, s.effects, f);
}

// The scaling sweep; false if a solve failed.
bool sweep(bool quick, int reps) {
  const std::vector<int> ns = quick ? std::vector<int>{5, 10, 20} : std::vector<int>{5, 10, 20, 50, 100, 200};
  std::printf("\nscaling sweep, configuration 5 (every subsegment loaded)\n");
  std::printf("%-6s %-9s %4s %8s %6s %12s %12s %12s %12s\n", "model", "load", "n", "unknowns", "iters", "median_us",
              "first_us", "dense_us", "tip_diff_m");
  bool ok = true;
  for (const char* name : {"ccsub", "prb"}) {
    struct Load {
      const char* label;
      Vec3 tip_force;
    };
    for (const Load& load : {Load{"tendons", Vec3::Zero()}, Load{"tip_force", Vec3(0.05, 0.02, 0.0)},
                             Load{"tip_0.5N", Vec3(0.4, 0.3, 0.0)}}) {
      double t10 = 0.0, t200 = 0.0;
      for (int n : ns) {
        Scene s = paper::scene(n, 5, name);
        s.loads.tip_force = load.tip_force;
        const auto model = lumped(name, s, LumpedFormulation::Automatic);
        // The first solve of a fresh workspace (sizes the buffers, analyses the sparsity pattern,
        // colours the columns), then `reps` cold solves in that workspace (the median).
        auto ws = model->make_workspace();
        const double first_us = bench::time_solves(*model, *ws, s.input(), s.solver, 1).median_us;
        const bench::Timing t = bench::time_solves(*model, *ws, s.input(), s.solver, reps);
        // The recursive formulation for comparison (dense LU: expensive above n = 50).
        double dense_us = NAN, diff = NAN;
        if (n <= (quick ? 20 : 100)) {
          const auto dense = lumped(name, s, LumpedFormulation::Recursive);
          const bench::Timing d = bench::time_solves(*dense, s, n >= 50 ? 1 : std::max(1, reps / 4));
          dense_us = d.median_us;
          diff = (d.last.tip().p - t.last.tip().p).norm();
          ok = ok && d.last.converged();
        }
        ok = ok && t.last.converged();
        if (n == 10) t10 = t.median_us;
        if (n == 200) t200 = t.median_us;
        std::printf("%-6s %-9s %4d %8d %6d %12.1f %12.1f %12.1f %12.2e %s\n", name, load.label, n,
                    t.last.summary.unknowns, t.last.summary.iterations, t.median_us, first_us, dense_us, diff,
                    t.last.converged() ? "" : t.last.summary.message.c_str());
      }
      if (t10 > 0.0 && t200 > 0.0)
        std::printf("%-6s %-9s log-log slope n = 10..200: %.2f\n", name, load.label,
                    std::log(t200 / t10) / std::log(20.0));
    }
  }
  return ok;
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false, sweep_only = false;
  int reps = 100;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--quick")) quick = true;
    else if (!std::strcmp(argv[i], "--sweep-only")) sweep_only = true;
    else if (!std::strcmp(argv[i], "--reps") && i + 1 < argc) reps = std::atoi(argv[++i]);
  }
  if (quick) reps = 3;
  // Paper code, configuration 2, median us (reference/paper_code_timing.csv).
  const std::map<std::pair<std::string, int>, double> paper = {
      {{"ccsub", 1}, 51.501},   {{"prb", 1}, 664.6435},  {{"ccsub", 2}, 217.225},
      {{"ccsub", 10}, 12700.0}, {{"prb", 10}, 227000.0}, {{"prb", 40}, 28e6}};
  std::vector<int> ns = quick ? std::vector<int>{10} : std::vector<int>{1, 2, 5, 10, 20, 40};

  if (sweep_only) return sweep(quick, reps) ? 0 : 1;
  std::printf("%-6s %4s %6s %8s %6s %12s %12s %14s %9s %s\n", "model", "n", "config", "unknowns", "iters",
              "median_us", "min_us", "paper_med_us", "speedup", "status");
  bool all_ok = true;
  for (const char* name : {"ccsub", "prb"}) {
    for (int n : ns) {
      for (int config : {2, 5}) {
        const Scene s = paper::scene(n, config, name);
        auto model = make_model(parse_model_kind(name), s);
        const bench::Timing t = bench::time_solves(*model, s, reps);
        const auto it = paper.find({name, n});
        const bool ok = t.last.converged();
        all_ok = all_ok && ok;
        char speed[32] = "-", ref[32] = "-";
        if (config == 2 && it != paper.end()) {
          std::snprintf(ref, sizeof ref, "%.1f", it->second);
          std::snprintf(speed, sizeof speed, "%.0fx", it->second / t.median_us);
        }
        std::printf("%-6s %4d %6d %8d %6d %12.1f %12.1f %14s %9s %s\n", name, n, config, t.last.summary.unknowns,
                    t.last.summary.iterations, t.median_us, t.min_us, ref, speed,
                    ok ? "converged" : t.last.summary.message.c_str());
      }
    }
  }
  all_ok = sweep(quick, reps) && all_ok;
  return all_ok ? 0 : 1;
}
