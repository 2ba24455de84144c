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

using Settings = bench::CaseStudyArgs;  // --repeat: 100 (--quick: 3)

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

// One model of one robot and its workspace: every input on that robot (configurations, load
// steps, a trajectory) is solved with both. nullopt if the model refuses the robot or an input
// (InputError, e.g. CC with a tip force).
class Runner {
 public:
  // The paper's effects by default (its Eq. 58 at the disks, its inextensible CCsub and PRB):
  // scenarios 1-2 reproduce its case study.
  Runner(ModelKind kind, const Robot& robot) : Runner(kind, robot, paper::effects(to_string(kind))) {}
  Runner(ModelKind kind, const Robot& robot, const Effects& effects) {
    try {
      model_ = make_model(kind, robot, effects);
      ws_ = model_->make_workspace();
    } catch (const InputError&) {
      model_.reset();
    }
  }
  explicit operator bool() const { return model_ != nullptr; }
  const StaticModel& model() const { return *model_; }
  ModelWorkspace& workspace() { return *ws_; }
  std::optional<Solution> solve(const ModelInput& input, const SolverOptions& options = SolverOptions(),
                                const Solution* warm = nullptr) {
    if (!model_) return std::nullopt;
    try {
      return tdcr::solve(*model_, *ws_, input, options, warm);
    } catch (const InputError&) {
      return std::nullopt;
    }
  }
  // Median and minimum time of `repeat` cold solves of one input.
  std::optional<bench::Timing> time(const ModelInput& input, const SolverOptions& options, int repeat) {
    if (!model_) return std::nullopt;
    try {
      return bench::time_solves(*model_, *ws_, input, options, repeat);
    } catch (const InputError&) {
      return std::nullopt;
    }
  }

 private:
  std::unique_ptr<StaticModel> model_;
  std::unique_ptr<ModelWorkspace> ws_;
};

// Solve along the loading path: actuation and loads raised in `steps` equal increments, each
// step warm-started from the last (the paper code's "ramp" runs). Soft robots under tip forces
// have several equilibria; comparing models is meaningful only on the branch reached by loading
// the robot from rest, which a direct solve from the straight guess does not guarantee.
std::optional<Solution> ramp_solve(Runner& runner, const ModelInput& input, int steps) {
  std::optional<Solution> prev;
  for (int k = 1; k <= steps; ++k) {
    const double lambda = static_cast<double>(k) / steps;
    ModelInput in = input;
    for (double& v : in.actuation.values) v *= lambda;
    in.loads.tip_force *= lambda;
    in.loads.tip_moment *= lambda;
    in.loads.gravity *= lambda;
    auto sol = runner.solve(in, SolverOptions(), prev ? &*prev : nullptr);
    if (!sol) return std::nullopt;
    if (!sol->converged()) return sol;
    prev = std::move(sol);
  }
  return prev;
}

// The reference: VCref, with continuation as the fallback so that the reference is converged.
std::optional<Solution> reference(Runner& vcref, const ModelInput& input, SolverOptions options = SolverOptions()) {
  options.continuation = true;
  return vcref.solve(input, options);
}

// CC is fed with the tendon displacements of the VC solution of the same tensions (Section 7).
ModelInput cc_input(const Solution& vc) {
  ModelInput in;
  in.actuation.kind = Actuation::Kind::Displacements;
  in.actuation.values = vc.tendon_displacements;
  return in;
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
    // One model and workspace per (model, robot): the 16 configurations are inputs.
    const Robot robot = paper::robot(n);
    std::map<ModelKind, Runner> run;
    for (ModelKind kind : {ModelKind::CC, ModelKind::CCsub, ModelKind::PRB, ModelKind::VC, ModelKind::VCref})
      run.emplace(kind, Runner(kind, robot));
    for (int c = 1; c <= 16; ++c) {
      bench::progress("scenario 1: n = " + std::to_string(n), done, static_cast<int>(ns.size()) * 16);
      const ModelInput base = paper::scene(n, c).input();
      const auto ref = reference(run.at(ModelKind::VCref), base);
      std::map<ModelKind, std::optional<Solution>> sol;
      sol[ModelKind::VC] = run.at(ModelKind::VC).solve(base);
      sol[ModelKind::CCsub] = run.at(ModelKind::CCsub).solve(base);
      sol[ModelKind::PRB] = run.at(ModelKind::PRB).solve(base);
      if (sol[ModelKind::VC] && sol[ModelKind::VC]->converged())
        sol[ModelKind::CC] = run.at(ModelKind::CC).solve(cc_input(*sol[ModelKind::VC]));
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
    const ModelInput timed = paper::scene(n, 2).input();
    const auto vc2 = run.at(ModelKind::VC).solve(timed);
    for (ModelKind kind : {ModelKind::CC, ModelKind::CCsub, ModelKind::PRB, ModelKind::VC, ModelKind::VCref}) {
      if (kind == ModelKind::CC && !vc2) continue;
      const int reps = kind == ModelKind::CC ? cfg.repeat * 100 : cfg.repeat;
      const auto t = run.at(kind).time(kind == ModelKind::CC ? cc_input(*vc2) : timed, SolverOptions(), std::max(1, reps));
      if (!t) continue;
      MeanTipError e{};
      int ncmp = 0, fails = 0;
      if (kind != ModelKind::VCref && !acc[kind].tips.empty()) {
        e = mean_tip_error(acc[kind].tips, acc[kind].refs, length);
        ncmp = static_cast<int>(acc[kind].tips.size());
      }
      if (kind != ModelKind::VCref) fails = acc[kind].failures;
      const auto it = paper.find({to_string(kind), n});
      const double pc = it == paper.end() ? NAN : it->second;
      csv.row(n, to_string(kind), e.e_p_percent, e.e_R_deg, e.max_p_percent, e.max_R_deg, ncmp, fails, t->median_us,
              t->min_us, pc, pc / t->median_us);
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
      std::map<ModelKind, Runner> run;
      for (ModelKind kind : {ModelKind::CCsub, ModelKind::PRB, ModelKind::VC, ModelKind::VCref})
        run.emplace(kind, Runner(kind, robot));
      for (int c : cs) {
        ModelInput in;
        in.actuation.values = paper::configuration_tensions(c, tm);
        in.loads.tip_force = F;
        // Every model, the reference included, follows the loading path (10 load steps).
        const auto ref = ramp_solve(run.at(ModelKind::VCref), in, 10);
        if (!ref || !ref->converged()) ++ref_fail;
        for (ModelKind kind : {ModelKind::CCsub, ModelKind::PRB, ModelKind::VC})
          acc[kind].add(ramp_solve(run.at(kind), in, 10), ref);
      }
      // Timing at half load, configuration 2, as the paper (Section 8.2).
      ModelInput half;
      half.actuation.values = paper::configuration_tensions(2, tm / 2);
      half.loads.tip_force = F / 2;
      for (ModelKind kind : {ModelKind::CCsub, ModelKind::PRB, ModelKind::VC, ModelKind::VCref}) {
        const auto t = run.at(kind).time(half, SolverOptions(), std::max(1, cfg.repeat / 4));
        if (!t) continue;
        MeanTipError e{};
        int ncmp = 0;
        if (kind != ModelKind::VCref && !acc[kind].tips.empty()) {
          e = mean_tip_error(acc[kind].tips, acc[kind].refs, 0.1);
          ncmp = static_cast<int>(acc[kind].tips.size());
        }
        csv.row(f, robot.backbone.effective_stiffness().EI, tm, force_case, to_string(kind), e.e_p_percent, e.e_R_deg,
                e.max_p_percent, e.max_R_deg, ncmp, kind == ModelKind::VCref ? 0 : acc[kind].failures, ref_fail,
                t->median_us, t->min_us);
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
  // One robot (n = 10) throughout, one model and workspace per model: the lumped models have no
  // solver setting that trades accuracy for time; the Cosserat models trade integrator work.
  const Robot robot = paper::robot(10);
  std::map<ModelKind, Runner> models;
  for (ModelKind kind : {ModelKind::CC, ModelKind::CCsub, ModelKind::PRB, ModelKind::VC, ModelKind::VCref})
    models.emplace(kind, Runner(kind, robot));
  for (const Case& cs : cases) {
    ModelInput input = paper::scene(10, 2).input();
    input.loads.tip_force = cs.force;
    SolverOptions truth_options;
    truth_options.integrator = IntegratorKind::Cvode;
    truth_options.cvode_rtol = 1e-10;
    truth_options.cvode_atol = 1e-12;
    const auto truth = reference(models.at(ModelKind::VCref), input, truth_options);
    if (!truth || !truth->converged()) continue;
    auto run = [&](ModelKind kind, const ModelInput& in, const SolverOptions& options, const std::string& setting) {
      const auto t = models.at(kind).time(in, options, reps);
      if (!t) return;
      const TipError e = tip_error(t->last.tip(), truth->tip());
      csv.row(cs.name, to_string(kind), setting, robot.segments[0].disks, 100 * e.position / 0.1, e.angle * 180 / M_PI,
              t->median_us, t->last.converged() ? 1 : 0);
    };
    bench::progress("trade-off: " + cs.name, 0, 1);
    run(ModelKind::CCsub, input, SolverOptions(), "default");
    run(ModelKind::PRB, input, SolverOptions(), "default");
    for (int steps : {1, 2, 4, 8, 16}) {
      SolverOptions o;
      o.integrator = IntegratorKind::FixedStepRK4;
      o.rk4_steps = steps;
      o.rk4_max_step = std::numeric_limits<double>::infinity();  // exactly rk4_steps per interval
      run(ModelKind::VC, input, o, "rk4_" + std::to_string(steps));
      run(ModelKind::VCref, input, o, "rk4_" + std::to_string(steps));
    }
    for (double rtol : {1e-4, 1e-6, 1e-8}) {
      SolverOptions o;
      o.integrator = IntegratorKind::Cvode;
      o.cvode_rtol = rtol;
      o.cvode_atol = rtol * 1e-2;
      std::ostringstream name;
      name << "cvode_" << rtol;
      run(ModelKind::VC, input, o, name.str());
      run(ModelKind::VCref, input, o, name.str());
    }
    if (cs.force.isZero()) {
      const auto vc = models.at(ModelKind::VC).solve(input);
      if (vc) run(ModelKind::CC, cc_input(*vc), SolverOptions(), "from_vc_displacements");
      run(ModelKind::CC, input, SolverOptions(), "from_tensions");
    }
    bench::progress("trade-off: " + cs.name, 1, 1);
  }
}

// Displacement input and elastic tendons: the pulled tendons of the
// baseline given by the displacements of its answer, the others by their tension (0), so the
// inextensible answer is the baseline's; elastic: the same with EA = 1e4 N per tendon (it
// stretches about 0.1 mm). Each solve is a sequence of warm-started tension solves.
void displacement_effects(ModelKind kind, int reps, bench::Csv& csv) {
  const Scene s = paper::scene(10, 2);
  Runner base(kind, s.robot, s.effects);
  const auto b = base.time(s.input(), s.solver, 1);
  if (!b || !b->last.converged()) return;
  for (const bool elastic : {false, true}) {
    Scene d = s;
    d.actuation.kind = Actuation::Kind::Displacements;
    d.actuation.kinds.assign(s.actuation.values.size(), Actuation::Kind::Tensions);
    std::size_t k = 0;
    for (Segment& seg : d.robot.segments)
      for (TendonSpec& t : seg.tendons) {
        if (s.actuation.values[k] > 0.0) {
          d.actuation.kinds[k] = Actuation::Kind::Displacements;
          d.actuation.values[k] = b->last.tendon_displacements[k];
          if (elastic) t.stiffness = 1e4;
        }
        ++k;
      }
    Runner run(kind, d.robot, d.effects);
    const auto t = run.time(d.input(), d.solver, reps);
    if (!t) continue;
    csv.row(to_string(kind), elastic ? "elastic_tendons" : "displacement_input", t->median_us,
            t->last.summary.iterations, t->last.converged() ? 1 : 0);
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
      {"tendon_friction", [](Scene& s) { s.effects.tendon_friction.coefficient = 0.1; }},
  };
  for (ModelKind kind : {ModelKind::CCsub, ModelKind::PRB, ModelKind::VC, ModelKind::VCref}) {
    for (const Variant& v : variants) {
      Scene s = paper::scene(10, 2);
      v.apply(s);
      Runner run(kind, s.robot, s.effects);  // a variant may change the robot or its effects
      const auto t = run.time(s.input(), s.solver, reps);
      if (!t) continue;
      csv.row(to_string(kind), v.name, t->median_us, t->last.summary.iterations, t->last.converged() ? 1 : 0);
    }
    displacement_effects(kind, reps, csv);
    bench::progress("effects: " + to_string(kind), 1, 1);
  }
}

// A trajectory: tension T1 ramped from 0 to T_M in 100 steps (quick: 10), solved cold (straight
// guess each time) and warm (from the previous configuration).
void warmstart(const Settings& cfg) {
  bench::Csv csv(cfg.out + "/warmstart.csv", "model,mode,steps,total_ms,mean_iterations,all_converged");
  const int steps = cfg.quick ? 10 : 100;
  const Robot robot = paper::robot(10);
  for (ModelKind kind : {ModelKind::CCsub, ModelKind::PRB, ModelKind::VC, ModelKind::VCref}) {
    // One model and one workspace for the whole trajectory; only the input changes.
    Runner run(kind, robot);
    if (!run) continue;
    for (const bool warm : {false, true}) {
      double total = 0.0;
      long iters = 0;
      bool ok = true;
      std::optional<Solution> prev;
      bool available = true;
      for (int i = 1; i <= steps && available; ++i) {
        ModelInput in = paper::scene(10, 1).input();
        in.actuation.values[0] = paper::max_tension(robot) * i / steps;
        in.loads.tip_force = Vec3(0.05, 0, 0);
        const auto t0 = std::chrono::steady_clock::now();
        std::optional<Solution> sol = run.solve(in, SolverOptions(), warm && prev ? &*prev : nullptr);
        total += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        if (!sol) {
          available = false;
          break;
        }
        iters += sol->summary.iterations;
        ok = ok && sol->converged();
        prev = std::move(sol);
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
  if (!bench::parse_case_study_args(argc, argv, "bench_case_study", "scenario1|scenario2|tradeoff|effects|warmstart",
                                    100, 3, cfg))
    return 2;
  std::filesystem::create_directories(cfg.out);
  const auto want = [&](const char* part) { return cfg.want(part); };
  if (want("scenario1")) scenario1(cfg);
  if (want("scenario2")) scenario2(cfg);
  if (want("tradeoff")) tradeoff(cfg);
  if (want("effects")) effects(cfg);
  if (want("warmstart")) warmstart(cfg);
  std::cout << "results written to " << cfg.out << "\n";
  return 0;
}
