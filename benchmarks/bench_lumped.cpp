// Solve time of the lumped static models CCsub and PRB on the paper's robot (Table 3), cold
// solves from the straight initial guess (one model and one workspace per row), against the paper's own code (reference/
// paper_code_timing.csv: configuration 2 = (T_M, 0, 0, 0), straight guess, median of up to 100
// cold solves). Usage: bench_lumped [--quick] [--reps N]
//
// Configuration 2 loads segment 1 only: segment 2 carries no load and is exactly straight, so
// tdcr leaves its subsegments out of the unknowns (the paper's code solves for them). Rows with
// configuration 5 = (0, 0, T_M, 0) load every subsegment and show the cost of the full system.
#include <cstdio>
#include <cstring>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "bench_common.hpp"
#include "tdcr/core/paper_robot.hpp"

using namespace tdcr;

int main(int argc, char** argv) {
  bool quick = false;
  int reps = 100;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--quick")) quick = true;
    else if (!std::strcmp(argv[i], "--reps") && i + 1 < argc) reps = std::atoi(argv[++i]);
  }
  if (quick) reps = 3;
  // Paper code, configuration 2, median us (reference/paper_code_timing.csv).
  const std::map<std::pair<std::string, int>, double> paper = {
      {{"ccsub", 1}, 51.501},   {{"prb", 1}, 664.6435},  {{"ccsub", 2}, 217.225},
      {{"ccsub", 10}, 12700.0}, {{"prb", 10}, 227000.0}, {{"prb", 40}, 28e6}};
  std::vector<int> ns = quick ? std::vector<int>{10} : std::vector<int>{1, 2, 5, 10, 20, 40};

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
  return all_ok ? 0 : 1;
}
