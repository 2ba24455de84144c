// Benchmark of the VCref model (multiple shooting, KLU):
//  (a) the paper robot at n = 10 disks per segment, configuration 2 (T_M, 0, 0, 0), cold solves:
//      median and min time, tip difference to a tightly converged CVODE solve, speed-up over the
//      paper code (127 ms median, reference/paper_code_timing.csv), for several RK4 step counts
//      and both initial guesses;
//  (b) cost against the number of disks per segment n (10 ... 100000), default solver options,
//      on two scenes: examples/paper_robot_vcref.json (configuration 2, tendons only) and
//      examples/paper_robot_tip_force.json with model vcref (T_M / 2 and a 0.5 N tip force).
//      A cold solve as `tdcr solve` makes it (model, workspace, solve), timed whole (wall and CPU
//      time); Newton iterations, unknowns, Jacobian nonzeros, CPU time per disk, peak RSS and the
//      part of it the solve added, per disk.
//      Every (scene, n) runs in a child process of its own, so that its peak RSS is its own.
// Usage: bench_vcref [--quick] [--max-disks N] [--csv <path>]
//   --quick: part (a) at 4 RK4 steps, part (b) at n = 10 and 30 (the ctest smoke run);
//   --max-disks: the largest n of part (b) (default 100000: about 4.3 GB and two minutes).
#include <sys/resource.h>
#include <time.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "tdcr/core/paper_robot.hpp"
#include "tdcr/core/scene_io.hpp"
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

// VmHWM (peak) or VmRSS (now) of this process in MB, from /proc/self/status (-1 if unreadable).
double proc_status_mb(const char* key) {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.compare(0, std::strlen(key), key) == 0) return std::atof(line.c_str() + std::strlen(key) + 1) / 1024.0;
  return -1.0;
}

struct ScalingRow {
  int iterations = 0, unknowns = 0, nnz = 0;
  bool converged = false;
  double median_ms = 0, min_ms = 0, cpu_ms = 0, rss_mb = 0, base_mb = 0, tip_y = 0;
};

// CPU time of this process (user + system) in ms: on a shared machine a solve's wall time also
// counts the other processes' turns.
double cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return 1e3 * t.tv_sec + 1e-6 * t.tv_nsec;
}

// Part (b), one disk count: `reps` cold solves (model, workspace, solve) of `scene` with n disks
// per segment. Runs in a child process; the peak RSS is the child's, base_mb its RSS before.
ScalingRow scaling_point(Scene s, int n, int reps) {
  for (Segment& seg : s.robot.segments) seg.disks = n;
  ScalingRow r;
  r.base_mb = proc_status_mb("VmRSS:");
  std::vector<double> t, c;
  Solution sol;
  for (int i = 0; i < reps; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    const double c0 = cpu_ms();
    VcrefModel model(s.robot, s.effects);
    auto ws = model.make_workspace();
    sol = tdcr::solve(model, *ws, s.input(), s.solver);
    c.push_back(cpu_ms() - c0);
    t.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    if (i == 0) {
      r.unknowns = model.unknowns();
      r.nnz = model.jacobian_nonzeros(s.input());
    }
  }
  std::sort(t.begin(), t.end());
  std::sort(c.begin(), c.end());
  r.median_ms = t[t.size() / 2];
  r.min_ms = t.front();
  r.cpu_ms = c[c.size() / 2];
  r.iterations = sol.summary.iterations;
  r.converged = sol.converged();
  r.tip_y = sol.tip().p.y();
  r.rss_mb = proc_status_mb("VmHWM:");
  if (r.rss_mb < 0) r.rss_mb = peak_rss_mb();
  return r;
}

// scaling_point in a child process (fork), its result sent back through a pipe.
bool scaling_point_in_child(const Scene& s, int n, int reps, ScalingRow& out) {
  int fd[2];
  if (pipe(fd) != 0) return false;
  std::fflush(stdout);
  const pid_t pid = fork();
  if (pid < 0) return false;
  if (pid == 0) {
    close(fd[0]);
    const ScalingRow r = scaling_point(s, n, reps);
    const ssize_t w = write(fd[1], &r, sizeof r);
    _exit(w == static_cast<ssize_t>(sizeof r) ? 0 : 1);
  }
  close(fd[1]);
  ssize_t got = 0;
  char* buf = reinterpret_cast<char*>(&out);
  for (ssize_t k; got < static_cast<ssize_t>(sizeof out) && (k = read(fd[0], buf + got, sizeof out - got)) > 0;) got += k;
  close(fd[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  return got == static_cast<ssize_t>(sizeof out) && WIFEXITED(status) && WEXITSTATUS(status) == 0;
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false;
  int max_disks = 100000;
  std::string csv;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--quick")) quick = true;
    else if (!std::strcmp(argv[i], "--csv") && i + 1 < argc) csv = argv[++i];
    else if (!std::strcmp(argv[i], "--max-disks") && i + 1 < argc) max_disks = std::atoi(argv[++i]);
    else {
      std::fprintf(stderr, "usage: %s [--quick] [--max-disks N] [--csv <path>]\n", argv[0]);
      return 2;
    }
  }
  if (max_disks < 1) {
    std::fprintf(stderr, "--max-disks must be a positive disk count\n");
    return 2;
  }
  std::vector<std::string> rows;
  rows.push_back(
      "part,scene,n,initial_guess,integrator,rk4_steps,median_ms,min_ms,cpu_ms,iterations,unknowns,nnz,peak_rss_mb,"
      "us_per_disk,kb_per_disk,tip_error_m,speedup_vs_paper");

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
      s.solver.integrator = IntegratorKind::FixedStepRK4;
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
      std::snprintf(line, sizeof line, "a,tendons,10,%s,rk4,%d,%.4f,%.4f,,%d,%d,,%.1f,,,%.3e,%.2f", g, steps, t.median_ms,
                    t.min_ms, t.sol.summary.iterations, t.sol.summary.unknowns, peak_rss_mb(), err,
                    kPaperMedianMs / t.median_ms);
      rows.push_back(line);
    }
  }

  // (b) Scaling with the number of disks per segment: default options, two scenes.
  struct Case {
    const char* name;
    const char* file;
  };
  const Case cases[] = {{"tendons", "paper_robot_vcref.json"}, {"tip force", "paper_robot_tip_force.json"}};
  std::vector<int> ns = quick ? std::vector<int>{10, 30}
                              : std::vector<int>{10, 30, 100, 300, 1000, 3000, 10000, 30000, 100000};
  ns.erase(std::remove_if(ns.begin(), ns.end(), [&](int n) { return n > max_disks; }), ns.end());
  std::printf("\n(b) cost against disks per segment n, default options (RK4, %d steps per interval, at most %g mm each),\n"
              "    cold solves (model, workspace, solve) in a child process per row\n",
              SolverOptions().rk4_steps, 1e3 * SolverOptions().rk4_max_step);
  for (const Case& c : cases) {
    Scene s = load_scene(std::string(TDCR_SOURCE_DIR) + "/examples/" + c.file);
    s.model = "vcref";
    std::printf("  %s (examples/%s, model vcref)\n", c.name, c.file);
    std::printf("%7s %9s %9s %6s %11s %11s %11s %11s %9s %10s\n", "n", "unknowns", "nnz", "iters", "median_ms",
                "min_ms", "cpu_ms", "us_per_disk", "rss_mb", "kb_per_disk");
    std::vector<double> logn, logt;
    for (int n : ns) {
      const int reps = quick ? 2 : n <= 100 ? 11 : n <= 1000 ? 5 : n <= 10000 ? 3 : 1;
      ScalingRow r;
      if (!scaling_point_in_child(s, n, reps, r)) {
        std::printf("%7d  the child process failed (out of memory?)\n", n);
        continue;
      }
      const int disks = n * static_cast<int>(s.robot.segments.size());
      // Per disk: the CPU time, and the RSS the solve added to the process's.
      const double us_per_disk = 1e3 * r.cpu_ms / disks, kb_per_disk = 1024.0 * (r.rss_mb - r.base_mb) / disks;
      std::printf("%7d %9d %9d %6d %11.2f %11.2f %11.2f %11.2f %9.1f %10.2f%s\n", n, r.unknowns, r.nnz, r.iterations,
                  r.median_ms, r.min_ms, r.cpu_ms, us_per_disk, r.rss_mb, kb_per_disk, r.converged ? "" : "  FAILED");
      char line[512];
      std::snprintf(line, sizeof line, "b,%s,%d,cc_arcs,rk4,%d,%.4f,%.4f,%.4f,%d,%d,%d,%.1f,%.3f,%.3f,,", c.name, n,
                    s.solver.rk4_steps, r.median_ms, r.min_ms, r.cpu_ms, r.iterations, r.unknowns, r.nnz, r.rss_mb,
                    us_per_disk, kb_per_disk);
      rows.push_back(line);
      if (n >= 30) {
        logn.push_back(std::log(n));
        logt.push_back(std::log(r.cpu_ms));
      }
    }
    if (logn.size() >= 2) {
      double mx = 0, my = 0;
      for (std::size_t i = 0; i < logn.size(); ++i) mx += logn[i], my += logt[i];
      mx /= logn.size();
      my /= logn.size();
      double sxy = 0, sxx = 0;
      for (std::size_t i = 0; i < logn.size(); ++i)
        sxy += (logn[i] - mx) * (logt[i] - my), sxx += (logn[i] - mx) * (logn[i] - mx);
      std::printf("  log-log slope of CPU time against n (n >= 30): %.3f (linear = 1)\n", sxy / sxx);
    }
  }
  if (!csv.empty()) {
    std::ofstream out(csv);
    for (const auto& l : rows) out << l << "\n";
    std::printf("wrote %s\n", csv.c_str());
  }
  return 0;
}
