// Side by side with the paper's own code: tdcr and the paper's C++ code (tdcr-modeling at commit
// 379d34a, built by benchmarks/paper_code/CMakeLists.txt from the checkout TDCR_PAPER_CODE_DIR
// names) timed in one run on one machine, their cold solves interleaved so that the busy and quiet
// spells of a shared machine fall on both (wall and CPU times are kept: other jobs preempt the
// paper code's long solves more than tdcr's short ones). The speed-ups of the loaded cases in docs/benchmarks.md
// ("Loaded cases") divide stored times of the paper's code, recorded on another day, by tdcr's;
// this benchmark measures both at once.
//
//   bench_side_by_side [--quick] [--out DIR] [--cases N] [--repeat R] [--models LIST] [--solver JSON]
//
// Cases: the 60 loaded cases of benchmarks/data/paper_code_cases_inputs.csv (paper robot, n = 3, 5,
// 10, 20 in turn, tensions U[0, 1.5 T_M], tip force |F| <= 0.5 N in any direction, base frame);
// --cases N takes the first N. Models: VC, CCsub, VCref, PRB (--models: a comma-separated subset).
// Per case and model, set up once and outside the timing:
//   - tdcr: make_model(kind, paper::robot(n), paper::effects(kind)) (Eq. 58, inextensible CCsub and PRB, as the paper code) and one workspace; each timed solve is tdcr::solve
//     without a warm start (a cold solve, the model's own cold rule) with tdcr's default
//     SolverOptions, whatever they are in this build, or those of --solver;
//   - the paper's code: one object of its model class (CosseratRodModel = VC,
//     PiecewiseConstantCurvatureModel = CCsub, SubsegmentCosseratRodModel = VCref,
//     PseudoRigidBodyModel = PRB) set up with the same robot through its public setRobotParameters
//     (tendons (0, +r_d, 0), (0, -r_d, 0) and a dummy (r_d, 0, 0) per segment, as the code is made
//     for 3 tendons a segment), setKeepInits(false): every solve from its straight guess; each
//     timed solve is one forwardKinematics with q = (T1, T2, 0, T3, T4, 0) and the tip force in the
//     base frame (the protocol of ../shared/reference/README.md).
// Then R rounds (--repeat, default 3 like the reference timings), each one solve of each code
// back to back, the paper's code first in odd rounds and tdcr first in even ones. Per code the
// median and minimum of its R wall times.
// converged: tdcr's Solution::converged(); the paper code's flag is what its forwardKinematics
// returned (its squared residual <= 1e-6; the GSL status is ignored by the code).
// Speed-up of a case: the paper code's median over tdcr's median, on cases both converged; per
// model the median and the minimum over the cases; beside it the paper code's minimum over tdcr's
// minimum, median over the cases (in the CSV); and the same speed-ups of the CPU times of the
// calling thread, medians of R (CPU time leaves out the time other jobs hold the core, which on a
// busy machine lands on one solve and not the other at random). Tip distance:
// |tdcr tip - paper code tip| of the last solves; the summary's largest counts only cases whose
// paper-code squared residual is below 1e-12 (its tip is trusted only there). The paper code's
// median against its stored median (benchmarks/data/paper_code_cases_timing.csv) says how this
// run's machine compares with the reference's.
// Writes DIR/side_by_side.csv (per case and model), DIR/side_by_side_summary.csv and
// DIR/side_by_side_summary.md (the summary as a markdown table, used by docs/benchmarks.md). The
// first line of each CSV names the machine, the date, the load average at the start (and, in the
// summary, at the end), the paper code's commit and tdcr's options.
// --solver JSON: tdcr's options as the `solver` object of a scene file (docs/scene-file.md), keys
// not given keep their defaults, e.g. --solver '{"integrator": "rk4_fixed", "rk4_steps": 8,
// "rk4_max_step": 0.001}' (the fixed mesh) or '{"tip_tolerance": 1e-9}'. --quick = --cases 2 --repeat 1 (the smoke run).
#include <gsl/gsl_errno.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <sstream>

#include <nlohmann/json.hpp>

// The paper's code (include directory of TDCR_PAPER_CODE_DIR).
#include "cosseratrodmodel.h"
#include "piecewiseconstantcurvaturemodel.h"
#include "pseudorigidbodymodel.h"
#include "subsegmentcosseratrodmodel.h"

#include "bench_common.hpp"
#include "tdcr/core/paper_robot.hpp"
#include "tdcr/core/scene_io.hpp"

namespace {

using tdcr::ModelKind;
using tdcr::Vec3;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct Settings {
  std::string out = "side-by-side-results";
  int cases = 1000;  // all
  int repeat = 3;
  std::vector<ModelKind> models = {ModelKind::VC, ModelKind::CCsub, ModelKind::VCref, ModelKind::PRB};
  std::string solver_json;  // empty: tdcr's defaults
  tdcr::SolverOptions options;
};

// ---- the paper's code ------------------------------------------------------------------------

// One solve of the paper's code: its flag, its squared residual, the tip of its last frame, and the
// wall and CPU time of the forwardKinematics call alone.
struct PaperSolve {
  bool converged = false;
  double residual = kNaN;
  tdcr::bench::CallTime time;
  Vec3 tip = Vec3::Constant(kNaN);
};

// One of the paper code's model classes, set up for a tdcr robot of the paper's kind.
class PaperModel {
 public:
  virtual ~PaperModel() = default;
  // The code's q = (T1, T2, 0, T3, T4, 0) of tdcr's (T1, T2, T3, T4); loads in the base frame.
  virtual PaperSolve solve(const tdcr::ModelInput& input) = 0;
};

template <typename Model>
class PaperModelOf final : public PaperModel {
 public:
  // Two segments of two straight tendons each at (0, +r_d) and (0, -r_d) (tdcr::paper::robot);
  // the paper's code takes a third, dummy tendon per segment at (r_d, 0), and G = E / 2.6.
  explicit PaperModelOf(const tdcr::Robot& robot) {
    const auto& b = robot.backbone;
    if (robot.segments.size() != 2 || b.stiffness || b.shear_modulus || b.inner_radius != 0.0 ||
        std::abs(b.poisson_ratio - 0.3) > 1e-12)
      throw std::invalid_argument("the paper's code takes two segments of a solid backbone with nu = 0.3");
    std::array<double, 2> length{}, pradius{};
    std::array<int, 2> disks{};
    std::vector<Eigen::Vector3d> routing;
    for (int i = 0; i < 2; ++i) {
      const tdcr::Segment& s = robot.segments[i];
      if (s.tendons.size() != 2 || s.tendons[0].routing.type != tdcr::TendonRoutingSpec::Type::Straight ||
          s.tendons[1].routing.type != tdcr::TendonRoutingSpec::Type::Straight)
        throw std::invalid_argument("the paper's code takes two straight tendons per segment here");
      length[i] = s.length;
      disks[i] = s.disks;
      pradius[i] = std::hypot(s.tendons[0].x, s.tendons[0].y);
      for (const tdcr::TendonSpec& t : s.tendons) routing.emplace_back(t.x, t.y, 0.0);
      routing.emplace_back(pradius[i], 0.0, 0.0);  // the dummy tendon, always at 0 N
    }
    model_.setRobotParameters(length, b.youngs_modulus, routing, disks, pradius, b.outer_radius);
    model_.setKeepInits(false);
  }

  PaperSolve solve(const tdcr::ModelInput& input) override {
    const auto& t = input.actuation.values;
    Eigen::MatrixXd q(6, 1);
    q << t.at(0), t.at(1), 0.0, t.at(2), t.at(3), 0.0;
    Eigen::MatrixXd frames;
    PaperSolve out;
    out.time = tdcr::bench::time_call(
        [&] { out.converged = model_.forwardKinematics(frames, q, input.loads.tip_force, input.loads.tip_moment); });
    out.residual = model_.getFinalResudial();
    if (frames.rows() == 4 && frames.cols() >= 4) out.tip = frames.rightCols<4>().block<3, 1>(0, 3);
    return out;
  }

 private:
  Model model_;
};

std::unique_ptr<PaperModel> make_paper_model(ModelKind kind, const tdcr::Robot& robot) {
  switch (kind) {
    case ModelKind::VC: return std::make_unique<PaperModelOf<::CosseratRodModel>>(robot);
    case ModelKind::CCsub: return std::make_unique<PaperModelOf<::PiecewiseConstantCurvatureModel>>(robot);
    case ModelKind::VCref: return std::make_unique<PaperModelOf<::SubsegmentCosseratRodModel>>(robot);
    case ModelKind::PRB: return std::make_unique<PaperModelOf<::PseudoRigidBodyModel>>(robot);
    default: throw std::invalid_argument("the paper's code has no solver for " + tdcr::to_string(kind));
  }
}

// ---- tdcr's options --------------------------------------------------------------------------

// tdcr's SolverOptions from the `solver` object of a scene file: parsed and checked by tdcr's own
// scene parser (names, types, bounds), keys not given at their defaults.
tdcr::SolverOptions parse_solver(const std::string& json) {
  nlohmann::json scene = nlohmann::json::parse(tdcr::scene_to_json(tdcr::paper::scene(3, 1)));
  scene["solver"] = nlohmann::json::parse(json);
  return tdcr::parse_scene(scene.dump(), "--solver").solver;
}

// ---- the run ---------------------------------------------------------------------------------

std::string load_average() {
  std::ifstream in("/proc/loadavg");
  double a = kNaN, b = kNaN, c = kNaN;
  in >> a >> b >> c;
  std::ostringstream s;
  s << a << " " << b << " " << c;
  return s.str();
}

struct Tally {
  int cases = 0, tdcr_converged = 0, paper_converged = 0, both = 0, tips_compared = 0, tips_over = 0;
  std::vector<double> tdcr_us, paper_us, speedup, speedup_of_mins, tdcr_cpu_us, paper_cpu_us, cpu_speedup,
      paper_vs_stored;
  double max_tip_distance = 0.0, tdcr_total_us = 0.0, paper_total_us = 0.0;
};

int run(const Settings& cfg) {
  std::filesystem::create_directories(cfg.out);
  std::vector<tdcr::bench::LoadedCase> cases = tdcr::bench::loaded_cases();
  if (static_cast<int>(cases.size()) > cfg.cases) cases.resize(cfg.cases);
  const std::string options = cfg.solver_json.empty() ? "default" : "custom";
  std::string machine = tdcr::bench::machine_stamp();
  machine.pop_back();  // its newline
  const std::string about = "; paper code commit " + std::string(TDCR_PAPER_CODE_COMMIT) + "; tdcr options: " +
                            (cfg.solver_json.empty() ? "default" : cfg.solver_json) + "; repeat " +
                            std::to_string(cfg.repeat);
  const std::string load_start = load_average();
  tdcr::bench::Csv csv(cfg.out + "/side_by_side.csv",
                       machine + "; load average at start " + load_start + about +
                           "\ncase_id,model,options,n,paper_median_us,paper_min_us,tdcr_median_us,tdcr_min_us,speedup,"
                           "speedup_of_mins,paper_cpu_median_us,tdcr_cpu_median_us,cpu_speedup,paper_converged,"
                           "paper_residual,tdcr_converged,tdcr_status,tdcr_iterations,tdcr_continuation_steps,"
                           "tip_distance_m,paper_tip_x,paper_tip_y,paper_tip_z,tdcr_tip_x,tdcr_tip_y,tdcr_tip_z,"
                           "paper_stored_median_us");
  if (!csv.ok()) throw std::runtime_error("cannot write to " + cfg.out);

  std::map<ModelKind, Tally> tally;
  const auto t_run = std::chrono::steady_clock::now();
  int done = 0;
  const int total = static_cast<int>(cases.size() * cfg.models.size());
  for (const auto& c : cases) {
    const tdcr::Robot robot = tdcr::paper::robot(c.n);
    for (ModelKind kind : cfg.models) {
      // The paper code's Eq. 58 and its inextensible CCsub and PRB.
      const auto model = tdcr::make_model(kind, robot, tdcr::paper::effects(tdcr::to_string(kind)));
      const auto ws = model->make_workspace();
      const auto paper = make_paper_model(kind, robot);
      std::vector<double> t_tdcr, t_paper, cpu_tdcr, cpu_paper;
      tdcr::Solution s;
      PaperSolve p;
      for (int r = 0; r < cfg.repeat; ++r) {
        auto tdcr_solve = [&] {
          const auto t = tdcr::bench::time_call([&] { s = tdcr::solve(*model, *ws, c.input, cfg.options); });
          t_tdcr.push_back(t.wall_us);
          cpu_tdcr.push_back(t.cpu_us);
        };
        auto paper_solve = [&] {
          p = paper->solve(c.input);
          t_paper.push_back(p.time.wall_us);
          cpu_paper.push_back(p.time.cpu_us);
        };
        if (r % 2 == 0) {
          paper_solve();
          tdcr_solve();
        } else {
          tdcr_solve();
          paper_solve();
        }
      }
      const double tdcr_med = tdcr::bench::median(t_tdcr), paper_med = tdcr::bench::median(t_paper);
      const double tdcr_min = *std::min_element(t_tdcr.begin(), t_tdcr.end());
      const double paper_min = *std::min_element(t_paper.begin(), t_paper.end());
      const bool both = s.converged() && p.converged;
      const double speedup = both ? paper_med / tdcr_med : kNaN;
      const double speedup_of_mins = both ? paper_min / tdcr_min : kNaN;
      const double tdcr_cpu = tdcr::bench::median(cpu_tdcr), paper_cpu = tdcr::bench::median(cpu_paper);
      const double cpu_speedup = both ? paper_cpu / tdcr_cpu : kNaN;
      const Vec3 tip = s.disk_frames.empty() ? Vec3::Constant(kNaN) : s.tip().p;
      const double distance = (tip - p.tip).norm();
      const auto stored = c.paper.find(kind);
      const double stored_us = stored == c.paper.end() ? kNaN : stored->second.median_us;

      Tally& t = tally[kind];
      ++t.cases;
      t.tdcr_converged += s.converged();
      t.paper_converged += p.converged;
      t.tdcr_us.push_back(tdcr_med);
      t.paper_us.push_back(paper_med);
      t.tdcr_cpu_us.push_back(tdcr_cpu);
      t.paper_cpu_us.push_back(paper_cpu);
      for (double x : t_tdcr) t.tdcr_total_us += x;
      for (double x : t_paper) t.paper_total_us += x;
      if (!std::isnan(stored_us)) t.paper_vs_stored.push_back(paper_med / stored_us);
      if (both) {
        ++t.both;
        t.speedup.push_back(speedup);
        t.speedup_of_mins.push_back(speedup_of_mins);
        t.cpu_speedup.push_back(cpu_speedup);
        if (p.residual < 1e-12) {
          ++t.tips_compared;
          t.max_tip_distance = std::max(t.max_tip_distance, std::isnan(distance) ? kNaN : distance);
          if (!(distance <= 1e-6)) ++t.tips_over;
        }
      }
      csv.row(c.id, tdcr::to_string(kind), options, c.n, paper_med, paper_min, tdcr_med, tdcr_min, speedup,
              speedup_of_mins, paper_cpu, tdcr_cpu, cpu_speedup, p.converged ? 1 : 0, p.residual, s.converged() ? 1 : 0,
              tdcr::to_string(s.summary.termination), s.summary.iterations, s.summary.continuation_steps, distance,
              p.tip.x(), p.tip.y(), p.tip.z(), tip.x(), tip.y(), tip.z(), stored_us);
      tdcr::bench::progress("side by side: case " + std::to_string(c.id) + " " + tdcr::to_string(kind), ++done,
                            total);
    }
  }
  const double run_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_run).count();
  const std::string load_end = load_average();

  // The summary, as CSV and as a markdown table.
  std::ostringstream stamp;
  stamp << machine << "; load average (1, 5, 15 min) at start " << load_start << ", at end " << load_end << about
        << "; run " << run_s << " s";
  tdcr::bench::Csv sum(cfg.out + "/side_by_side_summary.csv",
                       stamp.str() +
                           "\nmodel,options,cases,tdcr_converged,tdcr_failed,paper_converged,paper_failed,"
                           "both_converged,tdcr_median_us,paper_median_us,speedup_median,speedup_min,speedup_max,"
                           "speedup_of_mins_median,tdcr_cpu_median_us,paper_cpu_median_us,cpu_speedup_median,"
                           "cpu_speedup_min,"
                           "paper_vs_stored_median,tips_compared,max_tip_distance_m,tip_distance_over_1e-6,"
                           "tdcr_total_s,paper_total_s");
  std::ofstream md(cfg.out + "/side_by_side_summary.md");
  md << "| model | tdcr options | tdcr converged | paper's code converged | tdcr median | paper's code median "
        "| speed-up median | speed-up min | CPU time: speed-up median | CPU time: speed-up min | paper's code / "
        "its stored times (median) | max tip distance (cases) |\n"
     << "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n";
  auto time = [](double us) {
    std::ostringstream s;
    s.precision(3);
    if (us >= 1000) s << us / 1000 << " ms";
    else s << us << " us";
    return s.str();
  };
  for (ModelKind kind : cfg.models) {
    const Tally& t = tally[kind];
    const double smin = t.speedup.empty() ? kNaN : *std::min_element(t.speedup.begin(), t.speedup.end());
    const double smax = t.speedup.empty() ? kNaN : *std::max_element(t.speedup.begin(), t.speedup.end());
    const double max_dist = t.tips_compared ? t.max_tip_distance : kNaN;
    const double cpu_min = t.cpu_speedup.empty() ? kNaN : *std::min_element(t.cpu_speedup.begin(), t.cpu_speedup.end());
    sum.row(tdcr::to_string(kind), options, t.cases, t.tdcr_converged, t.cases - t.tdcr_converged, t.paper_converged,
            t.cases - t.paper_converged, t.both, tdcr::bench::median(t.tdcr_us), tdcr::bench::median(t.paper_us),
            tdcr::bench::median(t.speedup), smin, smax, tdcr::bench::median(t.speedup_of_mins),
            tdcr::bench::median(t.tdcr_cpu_us), tdcr::bench::median(t.paper_cpu_us), tdcr::bench::median(t.cpu_speedup),
            cpu_min, tdcr::bench::median(t.paper_vs_stored), t.tips_compared,
            max_dist, t.tips_over, 1e-6 * t.tdcr_total_us, 1e-6 * t.paper_total_us);
    std::ostringstream row;
    row.precision(3);
    row << "| " << tdcr::bench::paper_name(kind) << " | " << options << " | " << t.tdcr_converged << " / " << t.cases
        << " | " << t.paper_converged << " / " << t.cases << " | " << time(tdcr::bench::median(t.tdcr_us)) << " | "
        << time(tdcr::bench::median(t.paper_us)) << " | " << tdcr::bench::median(t.speedup) << "x | " << smin
        << "x | " << tdcr::bench::median(t.cpu_speedup) << "x | " << cpu_min << "x | "
        << tdcr::bench::median(t.paper_vs_stored)
        << " | " << std::scientific << std::setprecision(1) << max_dist << " m (" << t.tips_compared << ") |\n";
    md << row.str();
    std::printf("%-6s tdcr converged %3d/%d  paper converged %3d/%d  tdcr median %9.1f us  paper median %11.1f us  "
                "speed-up median %7.1fx min %7.1fx  paper/stored %.2f  max tip distance %.1e m (%d cases, %d over "
                "1e-6 m)\n",
                tdcr::to_string(kind).c_str(), t.tdcr_converged, t.cases, t.paper_converged, t.cases,
                tdcr::bench::median(t.tdcr_us), tdcr::bench::median(t.paper_us), tdcr::bench::median(t.speedup), smin,
                tdcr::bench::median(t.paper_vs_stored), max_dist, t.tips_compared, t.tips_over);
  }
  md << "\n" << stamp.str().substr(2) << ".\n";
  std::printf("%s\n", stamp.str().c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Settings cfg;
  auto value = [&](int& i) -> std::string {
    if (i + 1 >= argc) throw std::invalid_argument(argv[i]);
    return argv[++i];
  };
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      if (a == "--quick") {
        cfg.cases = 2;
        cfg.repeat = 1;
      } else if (a == "--out") {
        cfg.out = value(i);
      } else if (a == "--cases") {
        cfg.cases = std::stoi(value(i));
      } else if (a == "--repeat") {
        cfg.repeat = std::stoi(value(i));
      } else if (a == "--models") {
        cfg.models = tdcr::bench::parse_models(value(i));
      } else if (a == "--solver") {
        cfg.solver_json = value(i);
        cfg.options = parse_solver(cfg.solver_json);
      } else {
        throw std::invalid_argument(a);
      }
    }
    if (cfg.cases < 1 || cfg.repeat < 1 || cfg.models.empty()) throw std::invalid_argument("range");
    for (ModelKind k : cfg.models)
      if (k != ModelKind::VC && k != ModelKind::CCsub && k != ModelKind::VCref && k != ModelKind::PRB)
        throw std::invalid_argument("model " + tdcr::to_string(k));
  } catch (const std::exception& e) {
    std::cerr << "bad argument (" << e.what() << ")\n"
              << "usage: bench_side_by_side [--quick] [--out DIR] [--cases N>=1] [--repeat R>=1] "
                 "[--models vc,ccsub,vcref,prb] [--solver '{\"key\": value, ...}' (scene-file solver object)]\n";
    return 2;
  }
  // GSL's default handler aborts the process on an error inside the paper's code; off, the error
  // comes back as a status, which the code checks (it stops that integration, the solve fails).
  gsl_set_error_handler_off();
  try {
    return run(cfg);
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
}
