// Sweep throughput: solves per second per core of VC and VCref on the paper robot with a tip
// force (examples/paper_robot_tip_force.json) over a tension x tip-force grid, solved in grid
// order (neighbours warm-start each other) and as seeded random samples of the same ranges.
//
// Usage: bench_sweep [--quick] [--threads N] [--samples N]
//   --quick: 64 samples, for the ctest smoke run. Default 2000 samples (VC), 500 (VCref).
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>

#include "tdcr/sweep/sweep_run.hpp"

namespace {

tdcr::SweepSpec make_spec(const std::string& model, bool random, int samples) {
  const std::string scene = std::string(TDCR_SOURCE_DIR) + "/examples/paper_robot_tip_force.json";
  int nt = 1;
  while (nt * nt < samples) ++nt;
  const int nf = (samples + nt - 1) / nt;
  const std::string axes =
      random ? R"([{"field": "actuation.tensions[0]", "from": 0, "to": 5},
                  {"field": "loads.tip_force[1]", "from": 0, "to": 0.5}])"
             : R"([{"field": "actuation.tensions[0]", "from": 0, "to": 5, "count": )" + std::to_string(nt) +
                   R"(}, {"field": "loads.tip_force[1]", "from": 0, "to": 0.5, "count": )" + std::to_string(nf) + "}]";
  const std::string sampling =
      random ? R"("sampling": "random", "seed": 1, "samples": )" + std::to_string(nt * nf) + ", " : "";
  return tdcr::parse_sweep(R"({"scene": ")" + scene + R"(", "models": [")" + model + R"("], )" + sampling +
                           R"("axes": )" + axes + "}");
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false;
  int threads = 1, samples = 0;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--quick") == 0) quick = true;
    else if (std::strcmp(argv[i], "--threads") == 0 && i + 1 < argc) threads = std::atoi(argv[++i]);
    else if (std::strcmp(argv[i], "--samples") == 0 && i + 1 < argc) samples = std::atoi(argv[++i]);
  }
  const std::string out = (std::filesystem::temp_directory_path() / "tdcr_bench_sweep.csv").string();
  std::printf("%-6s %-7s %8s %8s %10s %14s %10s\n", "model", "order", "samples", "threads", "wall_s", "solves/s/core",
              "converged");
  for (const char* model : {"vc", "vcref"}) {
    for (bool random : {false, true}) {
      const int n = quick ? 64 : samples > 0 ? samples : std::strcmp(model, "vc") == 0 ? 2000 : 500;
      const tdcr::SweepSpec spec = make_spec(model, random, n);
      std::filesystem::remove(out);
      tdcr::SweepRunOptions o;
      o.threads = threads;
      o.progress = false;
      const tdcr::SweepRunStats s = tdcr::run_sweep(spec, out, o);
      // Converged rows: the status column holds "converged".
      std::FILE* f = std::fopen(out.c_str(), "r");
      int converged = 0;
      char line[4096];
      while (f && std::fgets(line, sizeof line, f)) converged += std::strstr(line, ",converged,") != nullptr;
      if (f) std::fclose(f);
      std::printf("%-6s %-7s %8llu %8d %10.3f %14.0f %10d\n", model, random ? "random" : "grid",
                  static_cast<unsigned long long>(s.samples_solved), threads, s.wall_s,
                  double(s.samples_solved) / s.wall_s / threads, converged);
      std::fflush(stdout);
      if (converged == 0) return 1;
    }
  }
  std::filesystem::remove(out);
  return 0;
}
