// Loaded cases and a loaded trajectory: speed-up against the paper's own code at equal
// or better tip accuracy, per model (VC, CCsub, VCref, PRB).
//
//   bench_loaded [--quick] [--out DIR] [--cases N] [--repeat R] [--steps N] [--tip-tol M] [--traj-tol M]
//                [--models LIST] [--stability auto|always|never] [--evict-caches]
//
// Part 1, loaded cases: the 60 random cases of benchmarks/data/paper_code_cases_inputs.csv (paper
// robot, n = 3, 5, 10, 20, tensions U[0, 1.5 T_M], tip force |F| <= 0.5 N in any direction, base
// frame), timed against benchmarks/data/paper_code_cases_timing.csv (the paper's code, median of 3
// cold solves). Per case and model one model and one workspace; every timed solve is cold (no warm
// start: the model's default cold rule), median and minimum of R solves (default 5).
//   Tip accuracy: the error of the solve's tip against a tight reference of the same model (VC,
//   VCref: CVODE rtol 1e-12 and Newton tolerance 1e-13; CCsub, PRB: Newton tolerance 1e-13, as the
//   lumped models integrate nothing), warm-started from the default solve so that it lies on the
//   same branch. Our tip against the paper code's tip is a consistency column; for VC also the
//   tip of VC without the kink forces at disks (VcOptions::kink_forces off, the paper code's
//   formulation), solved tightly, against the paper code's.
//   Options: the defaults, and per model the "matched" options: the candidate (RK4 steps per
//   interval and longest step, accuracy-driven RK4 with a tip tolerance from a coarse mesh, CVODE
//   tolerance, Newton tolerance) with the least total time
//   (minimum of 3 solves per case) whose tip error is at most --tip-tol (default 1e-8 m, the
//   paper code's own error at n >= 10) on every case the reference solves. Every candidate's
//   cost and worst error go to loaded_options.csv.
// Part 2, trajectory: paper robot n = 10, tip force (0.05, 0, 0) N (transverse, base frame),
//   T1(k) = T_M (1 - cos(2 pi k / N)) / 2 for k = 1..N (one period: 0 -> T_M -> 0), T2 = T3 = T4 = 0,
//   N = 1000 steps (--steps), each warm-started from the previous Solution, one model and one
//   workspace; rate, Newton iterations per step, and tip error against the tight reference at
//   20 evenly spaced steps (max_tip_err_m; also listed at k = N/4, N/2, 3N/4, N; the references
//   are solved once per model, from the default run's answers). Rows: the defaults, the loaded
//   cases' matched options, and the
//   trajectory's own calibration: every candidate except CVODE run over the whole trajectory, the
//   fastest without failures whose largest tip error at those steps is at most --traj-tol (default
//   1e-9 m, the trajectory's accuracy target), labelled "fastest within ... m: <candidate>".
// Writes DIR/loaded.csv (per case, model, options), loaded_summary.csv (per model and options),
// loaded_options.csv (the candidates), trajectory.csv. Failures of tdcr or of the paper's code are
// kept and counted, never dropped. --cases N takes the first N cases; --models a comma-separated
// subset of vc, ccsub, vcref, prb (for focused runs; benchmarks/run_all.sh runs all four). --stability sets
// SolverOptions::stability of every solve timed (default: the options' default, automatic), e.g. to
// measure what the stability test adds to the defaults. --evict-caches: before every timed solve of
// part 1, write over 32 MB (bench_common.hpp evict_caches), so each solve starts with caches that
// hold none of its code or data, as bench_side_by_side's solves do after the paper code's.
// --quick = --cases 2 --repeat 1 --steps 20 (the ctest smoke run).
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <optional>
#include <sstream>

#include "bench_common.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/core/paper_robot.hpp"
#include "tdcr/models/vc.hpp"

using namespace tdcr;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
// The models benchmarked (--models narrows them; the report needs all four).
std::vector<ModelKind> kModels = {ModelKind::VC, ModelKind::CCsub, ModelKind::VCref, ModelKind::PRB};
// SolverOptions::stability of every candidate (--stability; the default when not given).
StabilityCheck kStability = SolverOptions().stability;

struct Settings {
  std::string out = "benchmark-results";
  int cases = 1000;  // all
  int repeat = 5;
  int steps = 1000;
  double tip_tol = 1e-8;
  double traj_tol = 1e-9;  // the trajectory's accuracy target: 1e-9 m tip accuracy
  bool evict_caches = false;  // part 1's timed solves start with cold caches
};

// ---- data ------------------------------------------------------------------------------------

// The loaded cases and the paper code's stored results (benchmarks/data, bench_common.hpp).
using Case = bench::LoadedCase;
using bench::PaperResult;

// ---- options ---------------------------------------------------------------------------------

struct Candidate {
  std::string label;
  SolverOptions options;
};

bool integrates(ModelKind k) { return k == ModelKind::VC || k == ModelKind::VCref; }

// The tight reference settings of a model (see the header).
SolverOptions tight_options(ModelKind k) {
  SolverOptions o;
  o.function_tolerance = 1e-13;
  if (integrates(k)) {
    o.integrator = IntegratorKind::Cvode;
    o.cvode_rtol = 1e-12;
    o.cvode_atol = 1e-14;
  }
  return o;
}

std::string fmt(double x) {
  std::ostringstream s;
  s << x;
  return s.str();
}

// The candidates before --stability.
std::vector<Candidate> candidate_options(ModelKind k) {
  std::vector<Candidate> c{{"default", SolverOptions()}};
  if (integrates(k)) {
    for (int steps : {1, 2, 4, 8})
      for (double h : {kInf, 4e-3, 2e-3, 1e-3, 5e-4, 2.5e-4}) {
        SolverOptions o;
        o.integrator = IntegratorKind::FixedStepRK4;
        o.rk4_steps = steps;
        o.rk4_max_step = h;
        c.push_back({"rk4 " + std::to_string(steps) + "/interval h<=" + (std::isinf(h) ? "inf" : fmt(h * 1e3) + "mm"), o});
      }
    if (k == ModelKind::VCref)  // VCref's 1e-8 m lies between the 1 mm and 0.5 mm bounds
      for (int steps : {1, 2})
        for (double h : {8e-4, 7e-4, 6e-4}) {
          SolverOptions o;
          o.integrator = IntegratorKind::FixedStepRK4;
          o.rk4_steps = steps;
          o.rk4_max_step = h;
          c.push_back({"rk4 " + std::to_string(steps) + "/interval h<=" + fmt(h * 1e3) + "mm", o});
        }
    // Accuracy-driven RK4 (the default integrator) at other tip tolerances: each case refines
    // until its own tip error estimate meets the tolerance.
    for (double tol : {5e-9, 1e-9}) {
      SolverOptions o;
      o.tip_tolerance = tol;
      c.push_back({"tip tolerance " + fmt(tol) + " m", o});
    }
    for (double rtol : {1e-6, 1e-8}) {
      SolverOptions o;
      o.integrator = IntegratorKind::Cvode;
      o.cvode_rtol = rtol;
      o.cvode_atol = rtol * 1e-2;
      c.push_back({"cvode rtol " + fmt(rtol), o});
    }
  } else {
    for (double ftol : {1e-6, 1e-8}) {
      SolverOptions o;
      o.function_tolerance = ftol;
      c.push_back({"newton ftol " + fmt(ftol), o});
    }
  }
  return c;
}

// Solver settings that trade accuracy for time, the defaults first (all with --stability's rule).
std::vector<Candidate> candidates(ModelKind k) {
  std::vector<Candidate> c = candidate_options(k);
  for (Candidate& x : c) x.options.stability = kStability;
  return c;
}

// ---- loaded cases ----------------------------------------------------------------------------

// One model of one case: a model, a workspace for the timed solves and one for the others.
struct CaseModel {
  std::unique_ptr<StaticModel> model;
  std::unique_ptr<ModelWorkspace> ws, aux;
  std::optional<Solution> reference;  // tight, on the branch of the default solve
  Vec3 paper_form_tip = Vec3::Constant(kNaN);  // VC only: without kink forces, as the paper's code
};

double tip_error(const Solution& s, const std::optional<Solution>& ref) {
  if (!s.converged() || !ref || !ref->converged()) return kNaN;
  return (s.tip().p - ref->tip().p).norm();
}

using bench::median;

// Calibration: every candidate solved once per case; the chosen one is the cheapest whose tip error
// is within the tolerance on every case the reference solves.
Candidate choose_options(ModelKind kind, const std::vector<Case>& cases, std::vector<CaseModel>& cm,
                         const Settings& cfg, bench::Csv& csv) {
  const auto cands = candidates(kind);
  std::optional<size_t> best;
  double best_time = kInf;
  struct Row {
    int converged = 0, checked = 0;
    double worst = 0.0, median_us = 0.0, total_us = 0.0;
    bool ok = true;
  };
  std::vector<Row> rows(cands.size());
  for (size_t j = 0; j < cands.size(); ++j) {
    Row& r = rows[j];
    std::vector<double> times;
    for (size_t i = 0; i < cases.size(); ++i) {
      const auto t = bench::time_solves(*cm[i].model, *cm[i].aux, cases[i].input, cands[j].options,
                                        std::min(3, cfg.repeat));
      times.push_back(t.min_us);  // the minimum: least disturbed by other jobs on the machine
      r.total_us += t.min_us;
      r.converged += t.last.converged();
      if (!cm[i].reference || !cm[i].reference->converged()) continue;
      ++r.checked;
      const double e = tip_error(t.last, cm[i].reference);
      if (!(e <= cfg.tip_tol)) r.ok = false;
      r.worst = std::max(r.worst, std::isnan(e) ? kInf : e);
    }
    r.median_us = median(times);
    if (r.ok && r.total_us < best_time) {
      best_time = r.total_us;
      best = j;
    }
    bench::progress("loaded cases: " + to_string(kind) + " options", static_cast<int>(j + 1),
                    static_cast<int>(cands.size()));
  }
  if (!best) std::cerr << to_string(kind) << ": no candidate within " << cfg.tip_tol << " m on every case; using defaults\n";
  const size_t chosen = best.value_or(0);
  for (size_t j = 0; j < cands.size(); ++j)
    csv.row(to_string(kind), cands[j].label, cases.size(), rows[j].converged, rows[j].checked, rows[j].worst,
            rows[j].median_us, rows[j].total_us, rows[j].ok ? 1 : 0, j == chosen ? 1 : 0);
  return cands[chosen];
}

struct Tally {
  int cases = 0, converged = 0, failed = 0, paper_failed = 0, both = 0, ref_failed = 0, branch = 0;
  std::vector<double> median_us, speedup;
  double worst_err = 0.0, worst_paper_diff = 0.0;
};

void loaded(const Settings& cfg, std::map<ModelKind, Candidate>& matched, const std::string& stamp) {
  std::vector<Case> cases = bench::loaded_cases();
  if (static_cast<int>(cases.size()) > cfg.cases) cases.resize(cfg.cases);
  bench::Csv csv(cfg.out + "/loaded.csv",
                 stamp + "case_id,model,options,n,tdcr_median_us,tdcr_min_us,paper_median_us,paper_min_us,speedup,"
                         "iterations,continuation_steps,status,converged,paper_converged,paper_residual,tip_x,tip_y,"
                         "tip_z,tip_err_ref_m,tip_diff_paper_m,paper_form_tip_diff_paper_m,tip_error_estimate_m");
  bench::Csv sum(cfg.out + "/loaded_summary.csv",
                 stamp + "model,options,cases,converged,failed,paper_failed,both_converged,median_us,speedup_median,"
                         "speedup_min,max_tip_err_ref_m,reference_failed,max_tip_diff_paper_m,tip_diff_paper_over_1e-6");
  bench::Csv opt(cfg.out + "/loaded_options.csv",
                 stamp + "model,options,cases,converged,checked,max_tip_err_ref_m,median_us,total_us,within_tol,chosen");
  if (!csv.ok() || !sum.ok() || !opt.ok()) throw std::runtime_error("cannot write to " + cfg.out);
  for (ModelKind kind : kModels) {
    // One model per case, built once; the reference on the branch of the default cold solve.
    std::vector<CaseModel> cm(cases.size());
    for (size_t i = 0; i < cases.size(); ++i) {
      cm[i].model = make_model(kind, paper::robot(cases[i].n), paper::effects(to_string(kind)));
      cm[i].ws = cm[i].model->make_workspace();
      cm[i].aux = cm[i].model->make_workspace();
      const Solution first = solve(*cm[i].model, *cm[i].aux, cases[i].input, SolverOptions());
      cm[i].reference = solve(*cm[i].model, *cm[i].aux, cases[i].input, tight_options(kind),
                              first.converged() ? &first : nullptr);
      if (kind == ModelKind::VC) {
        VcOptions paper_form;
        paper_form.kink_forces = false;
        const VcModel vc(paper::robot(cases[i].n), paper::effects("vc"), paper_form);
        auto ws = vc.make_workspace();
        const Solution s = solve(vc, *ws, cases[i].input, tight_options(kind));
        if (s.converged()) cm[i].paper_form_tip = s.tip().p;
      }
      bench::progress("loaded cases: " + to_string(kind) + " references", static_cast<int>(i + 1),
                      static_cast<int>(cases.size()));
    }
    matched[kind] = choose_options(kind, cases, cm, cfg, opt);
    std::vector<Candidate> variants{candidates(kind).front()};
    if (matched[kind].label != "default") variants.push_back(matched[kind]);
    for (const Candidate& v : variants) {
      Tally t;
      for (size_t i = 0; i < cases.size(); ++i) {
        const Case& c = cases[i];
        const PaperResult& p = c.paper.at(kind);
        const bench::Timing tm = bench::time_solves(*cm[i].model, *cm[i].ws, c.input, v.options, cfg.repeat, nullptr,
                                                       cfg.evict_caches);
        const Solution& s = tm.last;
        const double err = tip_error(s, cm[i].reference);
        const double diff = s.converged() ? (s.tip().p - p.tip).norm() : kNaN;
        const bool both = s.converged() && p.converged;
        const double speedup = both ? p.median_us / tm.median_us : kNaN;
        ++t.cases;
        t.converged += s.converged();
        t.failed += !s.converged();
        t.paper_failed += !p.converged;
        t.ref_failed += !(cm[i].reference && cm[i].reference->converged());
        t.median_us.push_back(tm.median_us);
        if (both) {
          ++t.both;
          t.speedup.push_back(speedup);
        }
        if (!std::isnan(err)) t.worst_err = std::max(t.worst_err, err);
        if (both && p.residual < 1e-12) {  // the paper code's tip is trusted only on a small residual
          t.worst_paper_diff = std::max(t.worst_paper_diff, diff);
          if (diff > 1e-6) {
            ++t.branch;
            std::cerr << "case " << c.id << " " << to_string(kind) << " (" << v.label << "): tip differs from the "
                      << "paper code's by " << diff << " m\n";
          }
        }
        csv.row(c.id, to_string(kind), v.label, c.n, tm.median_us, tm.min_us, p.median_us, p.min_us,
                speedup, s.summary.iterations, s.summary.continuation_steps, to_string(s.summary.termination),
                s.converged() ? 1 : 0, p.converged ? 1 : 0, p.residual, s.tip().p.x(), s.tip().p.y(), s.tip().p.z(),
                err, diff, (cm[i].paper_form_tip - p.tip).norm(), s.summary.tip_error_estimate);
        bench::progress("loaded cases: " + to_string(kind) + " " + v.label, static_cast<int>(i + 1),
                        static_cast<int>(cases.size()));
      }
      const double smin = t.speedup.empty() ? kNaN : *std::min_element(t.speedup.begin(), t.speedup.end());
      sum.row(to_string(kind), v.label, t.cases, t.converged, t.failed, t.paper_failed, t.both,
              median(t.median_us), median(t.speedup), smin, t.worst_err, t.ref_failed, t.worst_paper_diff, t.branch);
      std::printf("%-6s %-26s cases %3d  converged %3d  failed %2d  paper failed %2d  median %9.1f us  "
                  "speed-up median %7.1fx min %7.1fx  max tip err %.2e m  (ref failed %d)  max |tip - paper| %.2e m "
                  "(%d over 1e-6)\n",
                  to_string(kind).c_str(), v.label.c_str(), t.cases, t.converged, t.failed, t.paper_failed,
                  median(t.median_us), median(t.speedup), smin, t.worst_err, t.ref_failed, t.worst_paper_diff,
                  t.branch);
    }
  }
}

// ---- trajectory ------------------------------------------------------------------------------

void trajectory(const Settings& cfg, const std::map<ModelKind, Candidate>& matched, const std::string& stamp) {
  bench::Csv csv(cfg.out + "/trajectory.csv",
                 stamp + "model,options,steps,total_ms,rate_hz,mean_us_per_step,mean_iterations,max_iterations,failed,"
                         "tip_err_quarter_m,tip_err_half_m,tip_err_three_quarter_m,tip_err_end_m,max_tip_err_m,"
                         "checked_steps");
  const Robot robot = paper::robot(10);
  const double t_max = paper::max_tension(robot);
  const int n = cfg.steps;
  // Tip error at 20 evenly spaced steps (every step if there are fewer); the CSV also names the
  // steps N/4, N/2, 3N/4 and N.
  const std::vector<int> quarters{std::max(1, n / 4), std::max(1, n / 2), std::max(1, 3 * n / 4), n};
  std::vector<int> checks = quarters;
  for (int i = 1; i <= 20; ++i) checks.push_back(std::max(1, i * n / 20));
  std::sort(checks.begin(), checks.end());
  checks.erase(std::unique(checks.begin(), checks.end()), checks.end());
  auto input = [&](int k) {
    ModelInput in;
    in.actuation.values = {t_max * 0.5 * (1.0 - std::cos(2.0 * M_PI * k / n)), 0.0, 0.0, 0.0};
    in.loads.tip_force = Vec3(0.05, 0.0, 0.0);
    return in;
  };
  struct Run {
    double total_ms = 0.0;
    long iters = 0;
    int max_iters = 0, failed = 0;
    std::map<int, double> err;  // per checked step
    double worst() const {
      double w = 0.0;
      for (const auto& [k, e] : err) w = std::max(w, std::isnan(e) ? kInf : e);
      return w;
    }
  };
  // The whole trajectory with one model and one workspace (only the input changes), then the
  // tip error at the check steps against the tight reference. The references of a model are
  // solved once, warm-started from the answers of its first run (the defaults), and shared by
  // its other runs: a candidate that lands on another branch shows as a large error.
  auto run = [&](ModelKind kind, const SolverOptions& options, std::map<int, Solution>& refs) {
    auto model = make_model(kind, robot, paper::effects(to_string(kind)));
    auto ws = model->make_workspace();
    std::optional<Solution> prev;
    std::map<int, Solution> kept;
    Run r;
    const auto t0 = std::chrono::steady_clock::now();
    for (int k = 1; k <= n; ++k) {
      Solution s = solve(*model, *ws, input(k), options, prev ? &*prev : nullptr);
      r.iters += s.summary.iterations;
      r.max_iters = std::max(r.max_iters, s.summary.iterations);
      if (!s.converged()) ++r.failed;
      if (std::find(checks.begin(), checks.end(), k) != checks.end()) kept[k] = s;
      if (s.converged()) prev = std::move(s);
    }
    r.total_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    auto ref_ws = model->make_workspace();
    for (int k : checks) {
      const Solution& s = kept.at(k);
      if (!refs.count(k)) refs[k] = solve(*model, *ref_ws, input(k), tight_options(kind), s.converged() ? &s : nullptr);
      r.err[k] = tip_error(s, refs.at(k));
    }
    return r;
  };
  auto report = [&](ModelKind kind, const std::string& label, const Run& r) {
    const auto& e = r.err;
    csv.row(to_string(kind), label, n, r.total_ms, 1e3 * n / r.total_ms, 1e3 * r.total_ms / n,
            static_cast<double>(r.iters) / n, r.max_iters, r.failed, e.at(quarters[0]), e.at(quarters[1]),
            e.at(quarters[2]), e.at(quarters[3]), r.worst(), e.size());
    std::printf("trajectory %-6s %-46s %5d steps  %8.0f Hz  %6.2f iterations/step (max %d)  failed %d  max tip err "
                "%.1e m (%zu steps)\n",
                to_string(kind).c_str(), label.c_str(), n, 1e3 * n / r.total_ms, static_cast<double>(r.iters) / n,
                r.max_iters, r.failed, r.worst(), e.size());
  };
  for (ModelKind kind : kModels) {
    std::vector<Candidate> variants{candidates(kind).front()};
    if (matched.count(kind) && matched.at(kind).label != "default") variants.push_back(matched.at(kind));
    std::map<int, Solution> refs;
    for (const Candidate& v : variants) report(kind, v.label, run(kind, v.options, refs));
    // The trajectory's own calibration: every candidate but CVODE (never the fastest) run over
    // the whole trajectory once; the fastest without failures whose largest tip error at the
    // checked steps is at most --traj-tol is reported with its label and the tolerance.
    std::optional<Run> best;
    std::string best_label;
    for (const Candidate& v : candidates(kind)) {
      if (v.options.integrator == IntegratorKind::Cvode) continue;
      const Run r = run(kind, v.options, refs);
      if (r.failed == 0 && r.worst() <= cfg.traj_tol && (!best || r.total_ms < best->total_ms)) {
        best = r;
        best_label = v.label;
      }
    }
    if (best) report(kind, "fastest within " + fmt(cfg.traj_tol) + " m: " + best_label, *best);
    else std::printf("trajectory %-6s no candidate within %g m at every check step\n", to_string(kind).c_str(), cfg.traj_tol);
  }
}

}  // namespace

int main(int argc, char** argv) {
  Settings cfg;
  auto number = [&](int& i) {
    if (i + 1 >= argc) throw std::invalid_argument(argv[i]);
    return std::stod(argv[++i]);
  };
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      if (a == "--quick") {
        cfg.cases = 2;
        cfg.repeat = 1;
        cfg.steps = 20;
      } else if (a == "--out" && i + 1 < argc) {
        cfg.out = argv[++i];
      } else if (a == "--cases") {
        cfg.cases = static_cast<int>(number(i));
      } else if (a == "--repeat") {
        cfg.repeat = static_cast<int>(number(i));
      } else if (a == "--steps") {
        cfg.steps = static_cast<int>(number(i));
      } else if (a == "--tip-tol") {
        cfg.tip_tol = number(i);
      } else if (a == "--traj-tol") {
        cfg.traj_tol = number(i);
      } else if (a == "--stability" && i + 1 < argc) {
        const std::string v = argv[++i];
        if (v != "auto" && v != "always" && v != "never") throw std::invalid_argument(v);
        kStability = v == "auto" ? StabilityCheck::Automatic : v == "always" ? StabilityCheck::Always : StabilityCheck::Never;
      } else if (a == "--models" && i + 1 < argc) {
        kModels = bench::parse_models(argv[++i]);
      } else if (a == "--evict-caches") {
        cfg.evict_caches = true;
      } else {
        throw std::invalid_argument(a);
      }
    }
    if (cfg.cases < 1 || cfg.repeat < 1 || cfg.steps < 4 || !(cfg.tip_tol > 0) || !(cfg.traj_tol > 0)) throw std::invalid_argument("range");
  } catch (const std::exception&) {
    std::cerr << "usage: bench_loaded [--quick] [--out DIR] [--cases N>=1] [--repeat R>=1] [--steps N>=4] "
                 "[--tip-tol M>0] [--traj-tol M>0] [--models vc,ccsub,vcref,prb] [--stability auto|always|never] [--evict-caches]\n";
    return 2;
  }
  std::filesystem::create_directories(cfg.out);
  const std::string stamp = bench::machine_stamp();
  std::map<ModelKind, Candidate> matched;
  try {
    loaded(cfg, matched, stamp);
    trajectory(cfg, matched, stamp);
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
  std::cout << "results written to " << cfg.out << "\n";
  return 0;
}
