// The paper's case study (Sections 6-8, Figs. 10-11) reproduced for every model, and beyond it:
// what accuracy costs in time.
//
//   bench_case_study [--quick] [--out DIR] [--repeat N] [--only scenario1|scenario2|tradeoff|effects|warmstart]
//
// Writes CSV tables into DIR (default: benchmark-results): scenario1.csv (Fig. 10: e_p, e_R of
// CC, CCsub, PRB, VC against VCref and the solve time of configuration 2, per disk count n),
// scenario1_configs.csv (every solve behind it), scenario2.csv (Fig. 11: stiffness sweep with
// planar and transverse tip forces), tradeoff.csv (error against time for every model and
// solver setting), effects.csv (cost of each effect), warmstart.csv (a trajectory solved warm
// and cold). benchmarks/plot_results.py draws them. --quick runs a small sweep in seconds (the
// ctest smoke run); the full sweep takes minutes.
#include <cmath>
#include <limits>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>

#include "bench_common.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/core/lie.hpp"
#include "tdcr/core/metrics.hpp"
#include "tdcr/core/paper_robot.hpp"

using namespace tdcr;

namespace {

struct Settings {
  bool quick = false;
  std::string out = "benchmark-results";
  int repeat = 100;
  std::string only;
};

const std::vector<ModelKind> kCompared = {ModelKind::CC, ModelKind::CCsub, ModelKind::PRB, ModelKind::VC};

// Paper code's median time (us) of configuration 2 per (model, n), from benchmarks/data.
std::map<std::pair<std::string, int>, double> paper_code_times() {
  std::map<std::pair<std::string, int>, double> t;
  std::ifstream in(std::string(TDCR_SOURCE_DIR) + "/benchmarks/data/paper_code_timing.csv");
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line.rfind("model", 0) == 0) continue;
    std::stringstream ss(line);
    std::string model, n, median;
    std::getline(ss, model, ',');
    std::getline(ss, n, ',');
    std::getline(ss, median, ',');
    for (auto& c : model) c = static_cast<char>(std::tolower(c));
    t[{model, std::atoi(n.c_str())}] = std::atof(median.c_str());
  }
  return t;
}

// Build and solve; nullopt if the model refuses the scene (InputError, e.g. CC with a tip force).
std::optional<Solution> try_solve(ModelKind kind, const Scene& scene, const Solution* warm = nullptr) {
  try {
    auto m = make_model(kind, scene);
    auto ws = m->make_workspace();
    return solve(*m, *ws, scene.input(), scene.solver, warm);
  } catch (const InputError& e) {
    return std::nullopt;
  }
}

// Solve along the loading path: actuation and loads raised in `steps` equal increments, each
// step warm-started from the last (the paper code's "ramp" runs). Soft robots under tip forces
// have several equilibria; comparing models is meaningful only on the branch reached by loading
// the robot from rest, which a direct solve from the straight guess does not guarantee.
std::optional<Solution> ramp_solve(ModelKind kind, const Scene& scene, int steps) {
  std::optional<Solution> prev;
  for (int k = 1; k <= steps; ++k) {
    const double lambda = static_cast<double>(k) / steps;
    Scene s = scene;
    for (double& v : s.actuation.values) v *= lambda;
    s.loads.tip_force *= lambda;
    s.loads.tip_moment *= lambda;
    s.loads.gravity *= lambda;
    auto sol = try_solve(kind, s, prev ? &*prev : nullptr);
    if (!sol) return std::nullopt;
    if (!sol->converged()) return sol;
    prev = std::move(sol);
  }
  return prev;
}

// The reference: VCref, with continuation as the fallback so that the reference is converged.
std::optional<Solution> reference(Scene scene) {
  scene.solver.continuation = true;
  return try_solve(ModelKind::VCref, scene);
}

// CC is fed with the tendon displacements of the VC solution of the same tensions (Section 7).
Scene cc_scene(const Scene& scene, const Solution& vc) {
  Scene s = scene;
  s.actuation.kind = Actuation::Kind::Displacements;
  s.actuation.values = vc.tendon_displacements;
  s.loads = Loads{};
  s.model = "cc";
  return s;
}

struct ErrorAccumulator {
  std::vector<Frame> tips, refs;
  int failures = 0;
  void add(const std::optional<Solution>& s, const std::optional<Solution>& ref) {
    if (!s || !ref || !ref->converged()) return;
    if (!s->converged()) {
      ++failures;
      return;
    }
    tips.push_back(s->tip());
    refs.push_back(ref->tip());
  }
};

void scenario1(const Settings& cfg) {
  const std::vector<int> ns = cfg.quick ? std::vector<int>{1, 2, 5, 10}
                                        : std::vector<int>{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 20, 30, 50, 100};
  const auto paper = paper_code_times();
  bench::Csv csv(cfg.out + "/scenario1.csv",
                 "n,model,e_p_pct,e_R_deg,e_p_max_pct,e_R_max_deg,n_compared,failures,median_us,min_us,"
                 "paper_code_median_us,speedup");
  bench::Csv configs(cfg.out + "/scenario1_configs.csv",
                     "n,config,model,converged,iterations,residual_norm,tip_x,tip_y,tip_z,pos_err_pct,angle_err_deg");
  int done = 0;
  for (int n : ns) {
    std::map<ModelKind, ErrorAccumulator> acc;
    const double length = 0.1;
    for (int c = 1; c <= 16; ++c) {
      bench::progress("scenario 1: n = " + std::to_string(n), done, static_cast<int>(ns.size()) * 16);
      const Scene base = paper::scene(n, c);
      const auto ref = reference(base);
      std::map<ModelKind, std::optional<Solution>> sol;
      sol[ModelKind::VC] = try_solve(ModelKind::VC, base);
      sol[ModelKind::CCsub] = try_solve(ModelKind::CCsub, base);
      sol[ModelKind::PRB] = try_solve(ModelKind::PRB, base);
      if (sol[ModelKind::VC] && sol[ModelKind::VC]->converged())
        sol[ModelKind::CC] = try_solve(ModelKind::CC, cc_scene(base, *sol[ModelKind::VC]));
      if (ref) sol[ModelKind::VCref] = ref;
      for (auto& [kind, s] : sol) {
        if (!s) continue;
        if (kind != ModelKind::VCref) acc[kind].add(s, ref);
        const TipError e = ref && ref->converged() ? tip_error(s->tip(), ref->tip()) : TipError{NAN, NAN};
        configs.row(n, c, to_string(kind), s->converged() ? 1 : 0, s->summary.iterations, s->summary.residual_norm,
                    s->tip().p.x(), s->tip().p.y(), s->tip().p.z(), 100 * e.position / length, e.angle * 180 / M_PI);
      }
      ++done;
    }
    // Timing: configuration 2 (T_M, 0, 0, 0) from the straight guess, as the paper.
    const Scene timed = paper::scene(n, 2);
    const auto vc2 = try_solve(ModelKind::VC, timed);
    for (ModelKind kind : {ModelKind::CC, ModelKind::CCsub, ModelKind::PRB, ModelKind::VC, ModelKind::VCref}) {
      std::unique_ptr<StaticModel> model;
      try {
        if (kind == ModelKind::CC) {
          if (!vc2) continue;
          model = make_model(kind, cc_scene(timed, *vc2));
        } else {
          model = make_model(kind, timed);
        }
      } catch (const InputError&) {
        continue;
      }
      const int reps = kind == ModelKind::CC ? cfg.repeat * 100 : cfg.repeat;
      const bench::Timing t = bench::time_solves(*model, timed, std::max(1, reps));
      MeanTipError e{};
      int ncmp = 0, fails = 0;
      if (kind != ModelKind::VCref && !acc[kind].tips.empty()) {
        e = mean_tip_error(acc[kind].tips, acc[kind].refs, length);
        ncmp = static_cast<int>(acc[kind].tips.size());
      }
      if (kind != ModelKind::VCref) fails = acc[kind].failures;
      const auto it = paper.find({to_string(kind), n});
      const double pc = it == paper.end() ? NAN : it->second;
      csv.row(n, to_string(kind), e.e_p_percent, e.e_R_deg, e.max_p_percent, e.max_R_deg, ncmp, fails, t.median_us,
              t.min_us, pc, pc / t.median_us);
    }
  }
  bench::progress("scenario 1", done, done);
}

void scenario2(const Settings& cfg) {
  const std::vector<int> ks = cfg.quick ? std::vector<int>{0, 4, 8} : std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7, 8};
  const std::vector<int> configs = cfg.quick ? std::vector<int>{1, 2, 6, 16} : std::vector<int>{};
  bench::Csv csv(cfg.out + "/scenario2.csv",
                 "stiffness_factor,EI,T_M,force_case,model,e_p_pct,e_R_deg,e_p_max_pct,e_R_max_deg,n_compared,failures,"
                 "ref_failures,median_us,min_us");
  const int n = 10;
  int done = 0, total = static_cast<int>(ks.size()) * 2;
  for (int k : ks) {
    const double f = std::pow(10.0, -1.0 + 0.25 * k);
    for (const std::string force_case : {"planar", "transverse"}) {
      bench::progress("scenario 2: f = " + std::to_string(f) + " " + force_case, done++, total);
      const Vec3 F = force_case == "planar" ? Vec3(0, 0.5, 0) : Vec3(0.5, 0, 0);
      std::map<ModelKind, ErrorAccumulator> acc;
      int ref_fail = 0;
      Robot robot = paper::robot(n, f);
      const double tm = paper::max_tension(robot);
      std::vector<int> cs = configs;
      if (cs.empty())
        for (int c = 1; c <= 16; ++c) cs.push_back(c);
      for (int c : cs) {
        Scene s;
        s.robot = robot;
        s.actuation.values = paper::configuration_tensions(c, tm);
        s.loads.tip_force = F;
        // Every model, the reference included, follows the loading path (10 load steps).
        const auto ref = ramp_solve(ModelKind::VCref, s, 10);
        if (!ref || !ref->converged()) ++ref_fail;
        for (ModelKind kind : {ModelKind::CCsub, ModelKind::PRB, ModelKind::VC})
          acc[kind].add(ramp_solve(kind, s, 10), ref);
      }
      // Timing at half load, configuration 2, as the paper (Section 8.2).
      Scene half;
      half.robot = robot;
      half.actuation.values = paper::configuration_tensions(2, tm / 2);
      half.loads.tip_force = F / 2;
      for (ModelKind kind : {ModelKind::CCsub, ModelKind::PRB, ModelKind::VC, ModelKind::VCref}) {
        std::unique_ptr<StaticModel> model;
        try {
          model = make_model(kind, half);
        } catch (const InputError&) {
          continue;
        }
        const bench::Timing t = bench::time_solves(*model, half, std::max(1, cfg.repeat / 4));
        MeanTipError e{};
        int ncmp = 0;
        if (kind != ModelKind::VCref && !acc[kind].tips.empty()) {
          e = mean_tip_error(acc[kind].tips, acc[kind].refs, 0.1);
          ncmp = static_cast<int>(acc[kind].tips.size());
        }
        csv.row(f, robot.backbone.effective_stiffness().EI, tm, force_case, to_string(kind), e.e_p_percent, e.e_R_deg,
                e.max_p_percent, e.max_R_deg, ncmp, kind == ModelKind::VCref ? 0 : acc[kind].failures, ref_fail,
                t.median_us, t.min_us);
      }
    }
  }
  bench::progress("scenario 2", total, total);
}

// Error against a converged high-accuracy VCref, and time, for every model and solver setting.
void tradeoff(const Settings& cfg) {
  bench::Csv csv(cfg.out + "/tradeoff.csv", "case,model,setting,n,e_p_pct,e_R_deg,median_us,converged");
  struct Case {
    std::string name;
    Vec3 force;
  };
  const std::vector<Case> cases = {{"tendons_only", Vec3::Zero()}, {"transverse_force", Vec3(0.25, 0, 0)}};
  const int reps = std::max(1, cfg.repeat / 5);
  for (const Case& cs : cases) {
    Scene truth_scene = paper::scene(10, 2);
    truth_scene.loads.tip_force = cs.force;
    truth_scene.solver.integrator = IntegratorKind::Cvode;
    truth_scene.solver.cvode_rtol = 1e-10;
    truth_scene.solver.cvode_atol = 1e-12;
    const auto truth = reference(truth_scene);
    if (!truth || !truth->converged()) continue;
    auto run = [&](ModelKind kind, Scene s, const std::string& setting) {
      s.loads.tip_force = cs.force;
      std::unique_ptr<StaticModel> model;
      try {
        model = make_model(kind, s);
      } catch (const InputError&) {
        return;
      }
      const bench::Timing t = bench::time_solves(*model, s, reps);
      const TipError e = tip_error(t.last.tip(), truth->tip());
      int n = s.robot.segments[0].disks;
      csv.row(cs.name, to_string(kind), setting, n, 100 * e.position / 0.1, e.angle * 180 / M_PI, t.median_us,
              t.last.converged() ? 1 : 0);
    };
    bench::progress("trade-off: " + cs.name, 0, 1);
    // One robot (n = 10) throughout: the lumped models have no solver setting that trades
    // accuracy for time; the Cosserat models trade integrator work.
    run(ModelKind::CCsub, paper::scene(10, 2), "default");
    run(ModelKind::PRB, paper::scene(10, 2), "default");
    for (int steps : {1, 2, 4, 8, 16}) {
      Scene s = paper::scene(10, 2);
      s.solver.rk4_steps = steps;
      s.solver.rk4_max_step = std::numeric_limits<double>::infinity();  // exactly rk4_steps per interval
      run(ModelKind::VC, s, "rk4_" + std::to_string(steps));
      run(ModelKind::VCref, s, "rk4_" + std::to_string(steps));
    }
    for (double rtol : {1e-4, 1e-6, 1e-8}) {
      Scene s = paper::scene(10, 2);
      s.solver.integrator = IntegratorKind::Cvode;
      s.solver.cvode_rtol = rtol;
      s.solver.cvode_atol = rtol * 1e-2;
      std::ostringstream name;
      name << "cvode_" << rtol;
      run(ModelKind::VC, s, name.str());
      run(ModelKind::VCref, s, name.str());
    }
    if (cs.force.isZero()) {
      const auto vc = try_solve(ModelKind::VC, paper::scene(10, 2));
      if (vc) run(ModelKind::CC, cc_scene(paper::scene(10, 2), *vc), "from_vc_displacements");
      run(ModelKind::CC, [] { Scene s = paper::scene(10, 2); s.model = "cc"; return s; }(), "from_tensions");
    }
    bench::progress("trade-off: " + cs.name, 1, 1);
  }
}

// The same solve with and without each effect: what an effect costs when a scene calls for it.
void effects(const Settings& cfg) {
  bench::Csv csv(cfg.out + "/effects.csv", "model,effect,median_us,iterations,converged");
  const int reps = std::max(1, cfg.repeat / 5);
  struct Variant {
    std::string name;
    void (*apply)(Scene&);
  };
  const std::vector<Variant> variants = {
      {"baseline", [](Scene&) {}},
      {"tip_wrench", [](Scene& s) { s.loads.tip_force = Vec3(0, 0.1, 0); s.loads.tip_moment = Vec3(1e-3, 0, 0); }},
      {"gravity", [](Scene& s) { s.loads.gravity = Vec3(0, 0, -9.81); s.robot.backbone.density = 6450;
                                 for (auto& g : s.robot.segments) g.disk_mass = 2e-4; }},
      {"no_shear_extension", [](Scene& s) { s.effects.shear_extension = false; }},
      {"disk_normal_force_kept", [](Scene& s) { s.effects.disk_normal_force = DiskNormalForce::Kept; }},
  };
  for (ModelKind kind : {ModelKind::CCsub, ModelKind::PRB, ModelKind::VC, ModelKind::VCref}) {
    for (const Variant& v : variants) {
      Scene s = paper::scene(10, 2);
      v.apply(s);
      std::unique_ptr<StaticModel> model;
      try {
        model = make_model(kind, s);
      } catch (const InputError&) {
        continue;
      }
      const bench::Timing t = bench::time_solves(*model, s, reps);
      csv.row(to_string(kind), v.name, t.median_us, t.last.summary.iterations, t.last.converged() ? 1 : 0);
    }
    bench::progress("effects: " + to_string(kind), 1, 1);
  }
}

// A trajectory: tension T1 ramped from 0 to T_M in 100 steps (quick: 10), solved cold (straight
// guess each time) and warm (from the previous configuration).
void warmstart(const Settings& cfg) {
  bench::Csv csv(cfg.out + "/warmstart.csv", "model,mode,steps,total_ms,mean_iterations,all_converged");
  const int steps = cfg.quick ? 10 : 100;
  for (ModelKind kind : {ModelKind::CCsub, ModelKind::PRB, ModelKind::VC, ModelKind::VCref}) {
    for (const bool warm : {false, true}) {
      double total = 0.0;
      long iters = 0;
      bool ok = true;
      std::optional<Solution> prev;
      bool available = true;
      for (int i = 1; i <= steps && available; ++i) {
        Scene s = paper::scene(10, 1);
        s.actuation.values[0] = paper::max_tension(s.robot) * i / steps;
        s.loads.tip_force = Vec3(0.05, 0, 0);
        std::unique_ptr<StaticModel> model;
        try {
          model = make_model(kind, s);
        } catch (const InputError&) {
          available = false;
          break;
        }
        auto ws = model->make_workspace();
        const auto t0 = std::chrono::steady_clock::now();
        Solution sol = solve(*model, *ws, s.input(), s.solver, warm && prev ? &*prev : nullptr);
        total += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        iters += sol.summary.iterations;
        ok = ok && sol.converged();
        prev = sol;
      }
      if (available)
        csv.row(to_string(kind), warm ? "warm" : "cold", steps, total, static_cast<double>(iters) / steps, ok ? 1 : 0);
    }
    bench::progress("warm start: " + to_string(kind), 1, 1);
  }
}

}  // namespace

int main(int argc, char** argv) {
  Settings cfg;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--quick") {
      cfg.quick = true;
      cfg.repeat = 3;
    } else if (a == "--out" && i + 1 < argc) {
      cfg.out = argv[++i];
    } else if (a == "--repeat" && i + 1 < argc) {
      cfg.repeat = std::atoi(argv[++i]);
      if (cfg.repeat < 1) {
        std::cerr << "error: --repeat must be a positive integer\n";
        return 2;
      }
    } else if (a == "--only" && i + 1 < argc) {
      cfg.only = argv[++i];
    } else {
      std::cerr << "usage: bench_case_study [--quick] [--out DIR] [--repeat N] "
                   "[--only scenario1|scenario2|tradeoff|effects|warmstart]\n";
      return 2;
    }
  }
  std::filesystem::create_directories(cfg.out);
  auto want = [&](const char* part) { return cfg.only.empty() || cfg.only == part; };
  if (want("scenario1")) scenario1(cfg);
  if (want("scenario2")) scenario2(cfg);
  if (want("tradeoff")) tradeoff(cfg);
  if (want("effects")) effects(cfg);
  if (want("warmstart")) warmstart(cfg);
  std::cout << "results written to " << cfg.out << "\n";
  return 0;
}
