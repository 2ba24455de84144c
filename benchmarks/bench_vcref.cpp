// Benchmark of the VCref model (multiple shooting, KLU):
//  (a) the paper robot at n = 10 disks per segment, configuration 2 (T_M, 0, 0, 0), cold solves:
//      median and min time, tip difference to a tightly converged CVODE solve, speed-up over the
//      paper code (127 ms median, reference/paper_code_timing.csv), for several RK4 step counts
//      and both initial guesses;
//  (b) cost against the number of disks per segment (10 ... 1000): time, Newton iterations,
//      unknowns, Jacobian nonzeros, peak RSS, and the log-log slope of time against n.
// Usage: bench_vcref [--quick] [--csv <path>]
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "tdcr/core/paper_robot.hpp"
#include "tdcr/models/vcref.hpp"

using namespace tdcr;

namespace {

constexpr double kPaperMedianMs = 127.0;  // paper code, VCref, n = 10, configuration 2

struct Timing {
  double median_ms = 0, min_ms = 0;
  Solution sol;
};

Timing time_solves(const Scene& s, int reps, const VcrefOptions& opt = VcrefOptions()) {
  VcrefModel model(s.robot, s.effects, opt);
  std::vector<double> t;
  Timing r;
  auto ws = model.make_workspace();  // one workspace, reused; every solve cold (no warm start)
  for (int i = 0; i < reps; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    r.sol = tdcr::solve(model, *ws, s.input(), s.solver);
    t.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(t.begin(), t.end());
  r.median_ms = t[t.size() / 2];
  r.min_ms = t.front();
  return r;
}

double peak_rss_mb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss / 1024.0;
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false;
  std::string csv;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--quick")) quick = true;
    else if (!std::strcmp(argv[i], "--csv") && i + 1 < argc) csv = argv[++i];
    else {
      std::fprintf(stderr, "usage: %s [--quick] [--csv <path>]\n", argv[0]);
      return 2;
    }
  }
  std::vector<std::string> rows;
  rows.push_back("part,n,initial_guess,integrator,rk4_steps,median_ms,min_ms,iterations,unknowns,nnz,peak_rss_mb,tip_error_m,speedup_vs_paper");

  // (a) Paper robot, n = 10, configuration 2.
  Scene ref_scene = paper::scene(10, 2);
  ref_scene.solver.integrator = IntegratorKind::Cvode;
  ref_scene.solver.cvode_rtol = 1e-12;
  ref_scene.solver.cvode_atol = 1e-14;
  ref_scene.solver.function_tolerance = 1e-12;
  const Timing ref = time_solves(ref_scene, 1);
  if (!ref.sol.converged()) {
    std::fprintf(stderr, "reference CVODE solve failed: %s\n", ref.sol.summary.message.c_str());
    return 1;
  }
  const int reps = quick ? 5 : 100;
  std::printf("(a) paper robot, n = 10, configuration 2 (T_M,0,0,0), %d cold solves each\n", reps);
  std::printf("    reference: CVODE rtol 1e-12, tip = (%.9f, %.9f, %.9f) m, %.1f ms\n", ref.sol.tip().p.x(),
              ref.sol.tip().p.y(), ref.sol.tip().p.z(), ref.median_ms);
  std::printf("%-9s %-6s %6s %10s %10s %6s %12s %9s\n", "guess", "integ", "steps", "median_ms", "min_ms", "iters",
              "tip_err_m", "speedup");
  for (auto guess : {VcrefOptions::InitialGuess::ConstantCurvature, VcrefOptions::InitialGuess::Straight}) {
    for (int steps : {1, 2, 4, 8}) {
      if (quick && steps != 4) continue;
      Scene s = paper::scene(10, 2);
      s.solver.rk4_steps = steps;
      s.solver.rk4_max_step = std::numeric_limits<double>::infinity();  // exactly rk4_steps per interval
      VcrefOptions opt;
      opt.initial_guess = guess;
      const Timing t = time_solves(s, reps, opt);
      const double err = (t.sol.tip().p - ref.sol.tip().p).norm();
      const char* g = guess == VcrefOptions::InitialGuess::Straight ? "straight" : "cc_arcs";
      std::printf("%-9s %-6s %6d %10.3f %10.3f %6d %12.3e %8.1fx%s\n", g, "rk4", steps, t.median_ms, t.min_ms,
                  t.sol.summary.iterations, err, kPaperMedianMs / t.median_ms, t.sol.converged() ? "" : "  FAILED");
      char line[512];
      std::snprintf(line, sizeof line, "a,10,%s,rk4,%d,%.4f,%.4f,%d,%d,,%.1f,%.3e,%.2f", g, steps, t.median_ms,
                    t.min_ms, t.sol.summary.iterations, t.sol.summary.unknowns, peak_rss_mb(), err,
                    kPaperMedianMs / t.median_ms);
      rows.push_back(line);
    }
  }

  // (b) Scaling with the number of disks per segment.
  std::vector<int> ns = quick ? std::vector<int>{10, 30} : std::vector<int>{10, 30, 100, 300, 1000};
  const int steps_b = 2;
  std::printf("\n(b) cost against disks per segment, configuration 2, rk4 %d steps per interval\n", steps_b);
  std::printf("%6s %9s %7s %10s %10s %6s %10s %12s\n", "n", "unknowns", "nnz", "median_ms", "min_ms", "iters",
              "rss_mb", "tip_y_m");
  std::vector<double> logn, logt;
  for (int n : ns) {
    Scene s = paper::scene(n, 2);
    s.solver.rk4_steps = steps_b;
    s.solver.rk4_max_step = std::numeric_limits<double>::infinity();  // exactly rk4_steps per interval
    VcrefModel model(s.robot, s.effects);
    const int r = quick ? 2 : (n <= 30 ? 21 : n <= 100 ? 11 : n <= 300 ? 5 : 3);
    const Timing t = time_solves(s, r);
    std::printf("%6d %9d %7d %10.2f %10.2f %6d %10.1f %12.6f%s\n", n, model.unknowns(), model.jacobian_nonzeros(s.input()),
                t.median_ms, t.min_ms, t.sol.summary.iterations, peak_rss_mb(), t.sol.tip().p.y(),
                t.sol.converged() ? "" : "  FAILED");
    char line[512];
    std::snprintf(line, sizeof line, "b,%d,cc_arcs,rk4,%d,%.4f,%.4f,%d,%d,%d,%.1f,,", n, steps_b, t.median_ms, t.min_ms,
                  t.sol.summary.iterations, model.unknowns(), model.jacobian_nonzeros(s.input()), peak_rss_mb());
    rows.push_back(line);
    if (n >= 30) {
      logn.push_back(std::log(n));
      logt.push_back(std::log(t.median_ms));
    }
  }
  if (logn.size() >= 2) {
    double mx = 0, my = 0;
    for (std::size_t i = 0; i < logn.size(); ++i) mx += logn[i], my += logt[i];
    mx /= logn.size();
    my /= logn.size();
    double sxy = 0, sxx = 0;
    for (std::size_t i = 0; i < logn.size(); ++i) sxy += (logn[i] - mx) * (logt[i] - my), sxx += (logn[i] - mx) * (logn[i] - mx);
    std::printf("log-log slope of time against n (n >= 30): %.3f (linear = 1)\n", sxy / sxx);
  }
  if (!csv.empty()) {
    std::ofstream out(csv);
    for (const auto& l : rows) out << l << "\n";
    std::printf("wrote %s\n", csv.c_str());
  }
  return 0;
}
