// Soft robots under tip forces (the soft-robot target): every static model within 10x of the
// fastest model on the same scene, VC under 20 ms.
//
// Usage: bench_soft [--quick] [--out DIR] [--repeat R] [--seed S] [--rk4-tip-tol M]
//
// Scenes: the paper robot (Table 3) with E x 0.1, 0.178, 0.25 (soft) and 1 (control), n = 10 and
// 20 disks per segment, each under three loaded cases drawn once from a seeded generator (default
// seed 13, SplitMix64, the same draws for every E and n): the four tensions uniform in
// [0, 1.5 T_M] with T_M of the softened robot (Eq. 55: the same bending as the loaded cases of
// bench_loaded, whose tensions are U[0, 1.5 T_M] on the stiff robot), and a tip force of magnitude
// uniform in [0.3, 1] N along +y (in the bending plane, with tendons 1 and 3), -y (in the
// plane, against them) and +x (transverse to it). Models: CCsub, PRB, VC, VCref, each solved cold
// (no warm start: the model's own cold rule, direct solve or loading path from rest) R times on
// one model and one workspace (default R = 3), median time. Each model's tip is compared with
// VCref's on the same scene.
//
// Output: DIR/soft.csv (one row per scene and model: scene, E factor, n, direction, |F|, model,
// status, continuation steps, Newton iterations, median wall and CPU time in us, ratio of CPU
// times to the fastest converged model of the scene, tip distance to VCref in m) and a per-model summary on stdout. --quick: E x 0.1,
// n = 10, the +y case, R = 1 (the ctest smoke run). --rk4-tip-tol M: every model solves with
// SolverOptions::tip_tolerance = M instead of the default (1e-7 of the robot's length); the
// output file is then DIR/soft_tol.csv.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "bench_common.hpp"
#include "tdcr/core/paper_robot.hpp"

using namespace tdcr;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// SplitMix64 step: the same numbers on every platform.
std::uint64_t splitmix64(std::uint64_t& state) {
  std::uint64_t x = (state += 0x9E3779B97F4A7C15ull);
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}
double uniform(std::uint64_t& state, double lo, double hi) {
  return lo + (hi - lo) * double(splitmix64(state) >> 11) * 0x1.0p-53;
}

/// One loaded case, independent of E and n: tensions as fractions of T_M, the force.
struct LoadDraw {
  std::string direction;  // "+y", "-y", "+x"
  Vec3 unit;
  double force = 0.0;            // |F| (N)
  std::vector<double> fraction;  // tension / T_M per tendon
};

struct Row {
  ModelKind model;
  std::string status;
  int steps = 0, iterations = 0;
  double median_us = kNaN, cpu_us = kNaN;
  Vec3 tip = Vec3::Constant(kNaN);
  bool converged = false;
};

/// CPU time of this thread (us): on a shared machine it is what the solve cost, wall time is not.
using bench::median;

}  // namespace

int main(int argc, char** argv) {
  bool quick = false;
  int repeat = 3;
  std::uint64_t seed = 13;
  std::string out_dir = ".";
  double tip_tol = 0.0;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--quick") == 0) quick = true;
    else if (std::strcmp(argv[i], "--out") == 0 && i + 1 < argc) out_dir = argv[++i];
    else if (std::strcmp(argv[i], "--repeat") == 0 && i + 1 < argc) repeat = std::atoi(argv[++i]);
    else if (std::strcmp(argv[i], "--seed") == 0 && i + 1 < argc) seed = std::strtoull(argv[++i], nullptr, 10);
    else if (std::strcmp(argv[i], "--rk4-tip-tol") == 0 && i + 1 < argc) tip_tol = std::atof(argv[++i]);
    else {
      std::fprintf(stderr, "usage: bench_soft [--quick] [--out DIR] [--repeat R] [--seed S] [--rk4-tip-tol M]\n");
      return 2;
    }
  }
  if (quick) repeat = 1;
  if (repeat < 1) repeat = 1;

  std::vector<LoadDraw> draws;
  std::uint64_t state = seed;
  for (const auto& [dir, unit] : {std::pair<const char*, Vec3>{"+y", Vec3(0, 1, 0)}, {"-y", Vec3(0, -1, 0)},
                                  {"+x", Vec3(1, 0, 0)}}) {
    LoadDraw d;
    d.direction = dir;
    d.unit = unit;
    d.force = uniform(state, 0.3, 1.0);
    for (int k = 0; k < 4; ++k) d.fraction.push_back(uniform(state, 0.0, 1.5));
    draws.push_back(d);
  }
  const std::vector<double> factors = quick ? std::vector<double>{0.1} : std::vector<double>{0.1, 0.178, 0.25, 1.0};
  const std::vector<int> disks = quick ? std::vector<int>{10} : std::vector<int>{10, 20};
  if (quick) draws.resize(1);
  const std::vector<ModelKind> models = {ModelKind::CCsub, ModelKind::PRB, ModelKind::VC, ModelKind::VCref};

  std::filesystem::create_directories(out_dir);
  SolverOptions integrating;  // VC and VCref
  if (tip_tol > 0.0) {
    integrating.tip_tolerance = tip_tol;
  }
  char tol_note[64] = "";
  if (tip_tol > 0.0) std::snprintf(tol_note, sizeof tol_note, " tip_tolerance=%g", tip_tol);
  bench::Csv csv(out_dir + (tip_tol > 0.0 ? "/soft_tol.csv" : "/soft.csv"),
                 "# bench_soft" + std::string(quick ? " --quick" : "") + " repeat=" + std::to_string(repeat) +
                     " seed=" + std::to_string(seed) + tol_note +
                     "\nscene,e_factor,n,direction,force_n,tensions_n,model,status,continuation_steps,iterations,"
                     "median_us,median_cpu_us,ratio_to_fastest,tip_dist_vcref_m");
  std::map<ModelKind, std::vector<double>> ratios, soft_ratios, control_ratios, times;
  std::map<ModelKind, int> converged;
  int scenes = 0, total = int(factors.size() * disks.size() * draws.size());
  for (double factor : factors) {
    for (int n : disks) {
      for (const LoadDraw& d : draws) {
        char name[64];
        std::snprintf(name, sizeof name, "E%gx_n%d_%s", factor, n, d.direction.c_str());
        bench::progress(name, scenes, total);
        Scene scene = paper::scene(n, 1);
        scene.robot = paper::robot(n, factor);
        const double t_max = paper::max_tension(scene.robot);
        std::string tensions;
        for (std::size_t k = 0; k < d.fraction.size(); ++k) {
          scene.actuation.values[k] = d.fraction[k] * t_max;
          char b[32];
          std::snprintf(b, sizeof b, "%s%.4g", k ? " " : "", scene.actuation.values[k]);
          tensions += b;
        }
        scene.loads.tip_force = d.force * d.unit;
        std::vector<Row> rows;
        for (ModelKind kind : models) {
          Row r;
          r.model = kind;
          try {
            const auto model = make_model(kind, scene.robot, scene.effects);
            const auto ws = model->make_workspace();
            const ModelInput input = scene.input();
            std::vector<double> wall, cpu;
            Solution last;
            for (int k = 0; k < repeat; ++k) {
              const bench::CallTime t = bench::time_call([&] {
                last = solve(*model, *ws, input,
                             kind == ModelKind::VC || kind == ModelKind::VCref ? integrating : scene.solver);
              });
              wall.push_back(t.wall_us);
              cpu.push_back(t.cpu_us);
            }
            r.status = to_string(last.summary.termination);
            r.steps = last.summary.continuation_steps;
            r.iterations = last.summary.iterations;
            r.median_us = median(wall);
            r.cpu_us = median(cpu);
            r.converged = last.converged();
            if (r.converged) r.tip = last.tip().p;
          } catch (const std::exception& e) {
            r.status = "error";
            std::fprintf(stderr, "\n%s %s: %s\n", name, to_string(kind).c_str(), e.what());
          }
          rows.push_back(r);
        }
        // Ratios from CPU times: the same as wall times on an idle machine, robust on a shared one.
        double fastest = kNaN;
        Vec3 ref = rows.back().tip;  // VCref
        for (const Row& r : rows)
          if (r.converged && !(r.cpu_us >= fastest)) fastest = r.cpu_us;
        for (const Row& r : rows) {
          const double ratio = r.converged ? r.cpu_us / fastest : kNaN;
          const double dist = (r.tip - ref).norm();
          csv.row(name, factor, n, d.direction, d.force, tensions, to_string(r.model), r.status, r.steps, r.iterations,
                  r.median_us, r.cpu_us, ratio, std::isfinite(dist) ? dist : kNaN);
          if (r.converged) {
            ratios[r.model].push_back(ratio);
            (factor < 1.0 ? soft_ratios : control_ratios)[r.model].push_back(ratio);
            converged[r.model]++;
          }
          if (factor < 1.0) times[r.model].push_back(r.cpu_us);
        }
        ++scenes;
      }
    }
  }
  bench::progress("done", scenes, total);
  // Ratios over all scenes, then the soft scenes (E < 1, the target's) and the stiff control apart.
  std::printf("%-6s %9s %10s %14s %14s %16s %14s %20s\n", "model", "converged", "of scenes", "median ratio",
              "max ratio", "soft: med/max", "control: max", "soft: median/max CPU");
  bool ok = true;
  const auto largest = [](const std::vector<double>& v) {
    double m = v.empty() ? kNaN : v.front();
    for (double x : v) m = std::max(m, x);
    return m;
  };
  // "-" where a group has no converged scene (e.g. no control scene in --quick).
  const auto ratio = [](double x) {
    char b[32];
    if (std::isfinite(x)) std::snprintf(b, sizeof b, "%.1fx", x);
    else std::snprintf(b, sizeof b, "-");
    return std::string(b);
  };
  for (ModelKind kind : models) {
    const std::vector<double>& r = ratios[kind];
    const std::vector<double>& t = times[kind];
    const std::string soft = ratio(median(soft_ratios[kind])) + "/" + ratio(largest(soft_ratios[kind]));
    std::printf("%-6s %9d %10d %14s %14s %16s %14s %11.2f/%.2f ms\n", to_string(kind).c_str(), converged[kind],
                scenes, ratio(median(r)).c_str(), ratio(largest(r)).c_str(), soft.c_str(),
                ratio(largest(control_ratios[kind])).c_str(), 1e-3 * median(t), 1e-3 * largest(t));
    ok = ok && converged[kind] > 0;
  }
  std::printf("targets: every model within 10x of the fastest on each scene; VC under 20 ms\n");
  std::printf("results in %s/%s\n", out_dir.c_str(), tip_tol > 0.0 ? "soft_tol.csv" : "soft.csv");
  return ok ? 0 : 1;
}
