// Scenario 3 of the case study: robots with helical tendon routing (the paper's Section 10 asks for
// them), the tendon force at the disks (Eq. 32-33 against Eq. 58), and how many disks a design
// needs for a given accuracy.
//
//   bench_helical [--quick] [--out DIR] [--repeat N] [--only scenario3|disk_force|disks]
//
// Writes CSV tables into DIR (default: benchmark-results):
//  - scenario3.csv: per disk count n (stiffness 1) and per stiffness factor (n = 10), for helical
//    routing of 0.25, 0.5 and 1 turn per segment on the paper's two-segment robot, antagonistic
//    pairs ((0, r), (0, -r) per segment, as Table 3) and adjacent pairs ((0, r), (r, 0)), without
//    and with a tip force: every model's mean and largest tip position error (% of the length) and
//    tip rotation error (deg) over the 16 tension configurations of the paper (T_k = 0 or T_M),
//    against VCref (the default disk force) and against VC; and the median wall and thread CPU
//    time of configuration 2 (T1 = T_M). VCref with Eq. 58 is a row of its own ("vcref_eq58").
//    CC refuses helical routing (an InputError naming the routing field): its rows say so.
//  - disk_force.csv: VCref with the disk force kept (Eq. 32-33) and removed (Eq. 58) against VC as
//    the disks grow, on straight and helical robots with and without loads, and the net force Eq.
//    58 drops from robot and tendons (verify_equilibrium's eq58_force).
//  - disks.csv: the smallest disk count per segment whose tip is within an accuracy (a fraction of
//    the length) of the model's own n -> infinity limit (Richardson extrapolation of the three
//    finest counts), for CCsub, PRB and VCref on the paper robot and on helical robots; printed too.
// --quick runs a small sweep in seconds (the ctest smoke run).
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>

#include "bench_common.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/core/metrics.hpp"
#include "tdcr/core/paper_robot.hpp"
#include "tdcr/models/verification.hpp"

using namespace tdcr;

namespace {

using Settings = bench::CaseStudyArgs;  // --repeat: 20 (--quick: 2)

int g_failures = 0;  // disk-force and disk-count solves that did not converge: a nonzero exit

constexpr double kLength = 0.1;  // the paper robot's length (two 50 mm segments)
constexpr double kRadius = 0.008;

enum class Pairs { Antagonistic, Adjacent };
const char* name(Pairs p) { return p == Pairs::Antagonistic ? "antagonistic" : "adjacent"; }

// The paper robot (Table 3, n disks per segment, stiffness factor f) with every tendon routed
// helically by `turns` per segment: a tendon ending at segment i runs over i + 1 segments, so its
// helix has (i + 1) turns over its length and every tendon the same pitch. Adjacent pairs put the
// second tendon of each segment at (r, 0) instead of (0, -r).
Robot helical_robot(int n, double turns, Pairs pairs, double f = 1.0) {
  Robot r = paper::robot(n, f);
  for (std::size_t i = 0; i < r.segments.size(); ++i)
    for (std::size_t k = 0; k < r.segments[i].tendons.size(); ++k) {
      TendonSpec& t = r.segments[i].tendons[k];
      if (k == 1 && pairs == Pairs::Adjacent) t = TendonSpec(kRadius, 0.0);
      if (turns != 0.0) {
        t.routing.type = TendonRoutingSpec::Type::Helical;
        t.routing.turns = turns * static_cast<double>(i + 1);
      }
    }
  return r;
}

// One model of one robot with its effects; nullopt answers where the model refuses the robot or
// an input (CC with helical routing).
class Runner {
 public:
  Runner(ModelKind kind, const Robot& robot, const Effects& effects = Effects()) {
    try {
      model_ = make_model(kind, robot, effects);
      ws_ = model_->make_workspace();
    } catch (const InputError& e) {
      refusal_ = e.what();
    }
  }
  explicit operator bool() const { return model_ != nullptr; }
  const std::string& refusal() const { return refusal_; }
  const StaticModel& model() const { return *model_; }
  std::optional<Solution> solve(const ModelInput& input, SolverOptions options = SolverOptions()) {
    if (!model_) return std::nullopt;
    try {
      return tdcr::solve(*model_, *ws_, input, options);
    } catch (const InputError&) {
      return std::nullopt;
    }
  }
  // Median wall and thread CPU time (us) of `repeat` cold solves.
  std::optional<std::pair<double, double>> time(const ModelInput& input, int repeat) {
    if (!model_) return std::nullopt;
    std::vector<double> wall, cpu;
    for (int i = 0; i < repeat; ++i) {
      const bench::CallTime t = bench::time_call([&] { tdcr::solve(*model_, *ws_, input, SolverOptions()); });
      wall.push_back(t.wall_us);
      cpu.push_back(t.cpu_us);
    }
    return std::make_pair(bench::median(wall), bench::median(cpu));
  }

 private:
  std::unique_ptr<StaticModel> model_;
  std::unique_ptr<ModelWorkspace> ws_;
  std::string refusal_;
};

Effects eq58() {
  Effects e;
  e.disk_normal_force = DiskNormalForce::Removed;
  return e;
}

struct Acc {
  std::vector<Frame> tips, refs;
  int failures = 0;
};

// scenario3.csv: one block of rows (every model against VCref and against VC) for one robot family.
void scenario3_block(const Settings& cfg, bench::Csv& csv, const std::string& part, int n, double f, double turns,
                     Pairs pairs, bool loaded, const std::vector<int>& configs) {
  const Robot robot = helical_robot(n, turns, pairs, f);
  const double tm = paper::max_tension(robot);
  const Vec3 F = loaded ? Vec3(0.25, 0.0, 0.0) : Vec3::Zero();
  std::map<std::string, Runner> run;
  run.emplace("cc", Runner(ModelKind::CC, robot));
  run.emplace("ccsub", Runner(ModelKind::CCsub, robot));
  run.emplace("prb", Runner(ModelKind::PRB, robot));
  run.emplace("vc", Runner(ModelKind::VC, robot));
  run.emplace("vcref_eq58", Runner(ModelKind::VCref, robot, eq58()));
  run.emplace("vcref", Runner(ModelKind::VCref, robot));
  const std::vector<std::string> models = {"cc", "ccsub", "prb", "vc", "vcref_eq58", "vcref"};
  std::map<std::string, std::map<std::string, Acc>> acc;  // reference -> model -> errors
  int ref_failures = 0;
  for (int c : configs) {
    ModelInput in;
    in.actuation.values = paper::configuration_tensions(c, tm);
    in.loads.tip_force = F;
    std::map<std::string, std::optional<Solution>> sol;
    for (const std::string& m : models) {
      SolverOptions o;
      if (m == "vcref" || m == "vc") o.continuation = true;  // the references: converged where possible
      sol[m] = run.at(m).solve(in, o);
    }
    for (const std::string ref : {"vcref", "vc"}) {
      const auto& r = sol[ref];
      if (!r || !r->converged()) {
        if (ref == std::string("vcref")) ++ref_failures;
        continue;
      }
      for (const std::string& m : models) {
        if (m == ref || !sol[m]) continue;
        Acc& a = acc[ref][m];
        if (!sol[m]->converged()) {
          ++a.failures;
          continue;
        }
        a.tips.push_back(sol[m]->tip());
        a.refs.push_back(r->tip());
      }
    }
  }
  ModelInput timed;
  timed.actuation.values = paper::configuration_tensions(2, tm);
  timed.loads.tip_force = F;
  for (const std::string& m : models) {
    Runner& r = run.at(m);
    if (!r) {
      // CC: no helical routing (constant curvature needs tendons parallel to the backbone).
      std::string why = r.refusal();
      std::string clean;
      for (char ch : why)
        if (ch != '"') clean += ch == ',' ? ';' : ch;  // one CSV field
      why = clean;
      csv.row(part, n, f, turns, name(pairs), loaded ? 1 : 0, m, "-", NAN, NAN, NAN, NAN, 0, 0, ref_failures, NAN, NAN,
              "refuses: " + why);
      continue;
    }
    const auto t = r.time(timed, cfg.repeat);
    for (const std::string ref : {"vcref", "vc"}) {
      if (m == ref) continue;
      const Acc& a = acc[ref][m];
      MeanTipError e{NAN, NAN, NAN, NAN};
      if (!a.tips.empty()) e = mean_tip_error(a.tips, a.refs, kLength);
      csv.row(part, n, f, turns, name(pairs), loaded ? 1 : 0, m, ref, e.e_p_percent, e.e_R_deg, e.max_p_percent,
              e.max_R_deg, a.tips.size(), a.failures, ref_failures, t ? t->first : NAN, t ? t->second : NAN, "");
    }
  }
}

void scenario3(const Settings& cfg) {
  bench::Csv csv(cfg.out + "/scenario3.csv",
                 "part,n,stiffness_factor,turns,pairs,tip_force,model,reference,e_p_pct,e_R_deg,e_p_max_pct,"
                 "e_R_max_deg,n_compared,failures,ref_failures,median_us,median_cpu_us,note");
  const std::vector<int> ns = cfg.quick ? std::vector<int>{2, 10} : std::vector<int>{1, 2, 3, 5, 10, 20, 50};
  const std::vector<double> turns = cfg.quick ? std::vector<double>{0.5} : std::vector<double>{0.25, 0.5, 1.0};
  const std::vector<double> stiffness = cfg.quick ? std::vector<double>{1.0} : std::vector<double>{0.3, 1.0, 3.0};
  std::vector<int> configs;
  if (cfg.quick)
    configs = {2, 6, 11};
  else
    for (int c = 1; c <= 16; ++c) configs.push_back(c);
  const std::vector<Pairs> pairs = {Pairs::Antagonistic, Pairs::Adjacent};
  const int total = static_cast<int>(turns.size() * pairs.size() * (2 * ns.size() + stiffness.size()));
  int done = 0;
  for (double t : turns)
    for (Pairs p : pairs) {
      for (bool loaded : {false, true})
        for (int n : ns) {
          bench::progress("scenario 3: n", done++, total);
          scenario3_block(cfg, csv, "n", n, 1.0, t, p, loaded, configs);
        }
      for (double f : stiffness) {
        bench::progress("scenario 3: stiffness", done++, total);
        scenario3_block(cfg, csv, "stiffness", 10, f, t, p, true, configs);
      }
    }
  bench::progress("scenario 3", total, total);
}

// ---- the tendon force at a disk ----------------------------------------------------------------

struct DiskCase {
  std::string name;
  double turns;
  Pairs pairs;
  std::vector<double> tensions;
  Vec3 tip_force;
};

// One 100 mm segment of the paper robot's backbone with the given routing (robot of the case).
Robot one_segment(int n, double turns, Pairs pairs) {
  Robot r = paper::robot(n);
  r.segments.resize(1);
  r.segments[0].length = kLength;
  if (pairs == Pairs::Adjacent) r.segments[0].tendons[1] = TendonSpec(kRadius, 0.0);
  if (turns != 0.0)
    for (TendonSpec& t : r.segments[0].tendons) {
      t.routing.type = TendonRoutingSpec::Type::Helical;
      t.routing.turns = turns;
    }
  return r;
}

void disk_force(const Settings& cfg) {
  bench::Csv csv(cfg.out + "/disk_force.csv",
                 "case,n,kept_vs_vc_m,removed_vs_vc_m,removed_vs_kept_m,kept_angle_vs_vc_deg,removed_angle_vs_vc_deg,"
                 "eq58_net_force_N,eq58_net_moment_Nm,kept_balance_rel,removed_balance_rel");
  const std::vector<DiskCase> cases = {
      {"straight", 0.0, Pairs::Antagonistic, {2.0, 0.0}, Vec3::Zero()},
      {"straight_tip_force", 0.0, Pairs::Antagonistic, {2.0, 0.0}, Vec3(0.5, 0.0, 0.0)},
      {"helix_0.5", 0.5, Pairs::Antagonistic, {2.0, 0.0}, Vec3::Zero()},
      {"helix_0.5_adjacent_pair", 0.5, Pairs::Adjacent, {2.0, 1.0}, Vec3::Zero()},
      {"helix_0.5_tip_force", 0.5, Pairs::Antagonistic, {2.0, 0.0}, Vec3(0.0, 0.3, 0.0)},
      {"helix_1_adjacent_pair_tip_force", 1.0, Pairs::Adjacent, {2.0, 1.0}, Vec3(0.3, 0.0, 0.0)},
  };
  const std::vector<int> ns = cfg.quick ? std::vector<int>{10, 20} : std::vector<int>{10, 20, 50, 100, 200};
  std::cout << "\nVCref's tip against VC's (mm), disk force kept (Eq. 32-33) and removed (Eq. 58); one 100 mm\n"
               "segment of the paper robot's backbone; net force Eq. 58 drops from robot and tendons (N)\n";
  std::cout << std::left << std::setw(34) << "case" << std::right << std::setw(6) << "n" << std::setw(12) << "kept"
            << std::setw(12) << "removed" << std::setw(12) << "dropped" << "\n";
  for (const DiskCase& c : cases) {
    for (int n : ns) {
      const Robot robot = one_segment(n, c.turns, c.pairs);
      ModelInput in;
      in.actuation.values = c.tensions;
      in.loads.tip_force = c.tip_force;
      Runner vc(ModelKind::VC, robot), kept(ModelKind::VCref, robot), removed(ModelKind::VCref, robot, eq58());
      const auto a = vc.solve(in), k = kept.solve(in), r = removed.solve(in);
      if (!a || !k || !r || !a->converged() || !k->converged() || !r->converged()) {
        std::cerr << "disk force: " << c.name << " n = " << n << " did not converge\n";
        ++g_failures;
        continue;
      }
      const TipError ek = tip_error(k->tip(), a->tip()), er = tip_error(r->tip(), a->tip());
      const EquilibriumCheck qk = verify_equilibrium(kept.model(), in, *k);
      const EquilibriumCheck qr = verify_equilibrium(removed.model(), in, *r);
      csv.row(c.name, n, ek.position, er.position, (r->tip().p - k->tip().p).norm(), ek.angle * 180 / M_PI,
              er.angle * 180 / M_PI, qr.eq58_force.norm(), qr.eq58_moment.norm(), qk.relative_error(),
              qr.relative_error());
      std::cout << std::left << std::setw(34) << c.name << std::right << std::setw(6) << n << std::setw(12)
                << std::setprecision(3) << 1e3 * ek.position << std::setw(12) << 1e3 * er.position << std::setw(12)
                << qr.eq58_force.norm() << "\n";
    }
  }
}

// ---- how many disks a design needs ---------------------------------------------------------------

struct DesignCase {
  std::string name;
  double turns;
  Pairs pairs;
  int config;
  Vec3 tip_force;
};

void disks(const Settings& cfg) {
  bench::Csv csv(cfg.out + "/disks.csv", "robot,model,accuracy_fraction,n_min,error_at_n_min_m,limit_uncertainty_m,order");
  const std::vector<DesignCase> cases =
      cfg.quick ? std::vector<DesignCase>{{"helix_0.5_antagonistic_c2", 0.5, Pairs::Antagonistic, 2, Vec3::Zero()}}
                : std::vector<DesignCase>{
                      {"paper_c2", 0.0, Pairs::Antagonistic, 2, Vec3::Zero()},
                      {"paper_c2_tip_force", 0.0, Pairs::Antagonistic, 2, Vec3(0.25, 0, 0)},
                      {"helix_0.5_antagonistic_c2", 0.5, Pairs::Antagonistic, 2, Vec3::Zero()},
                      {"helix_1_adjacent_c6_tip_force", 1.0, Pairs::Adjacent, 6, Vec3(0.25, 0, 0)},
                  };
  const std::vector<int> ns = cfg.quick ? std::vector<int>{2, 4, 8, 16, 32}
                                        : std::vector<int>{1, 2, 3, 4, 5, 6, 8, 10, 12, 15, 20, 25, 30, 40, 50, 60, 80, 100, 120};
  const std::vector<double> accuracies = {1e-2, 1e-3, 1e-4};
  std::cout << "\nSmallest disk count per segment within an accuracy (fraction of the length) of the model's own\n"
               "n -> infinity limit (Richardson from the three finest counts; '>' the finest count is not enough)\n";
  std::cout << std::left << std::setw(32) << "robot" << std::setw(8) << "model" << std::right;
  for (double a : accuracies) std::cout << std::setw(10) << a;
  std::cout << "   order\n";
  for (const DesignCase& c : cases)
    for (ModelKind kind : {ModelKind::CCsub, ModelKind::PRB, ModelKind::VCref}) {
      std::vector<Vec3> tips;
      bool ok = true;
      for (int n : ns) {
        const Robot robot = helical_robot(n, c.turns, c.pairs);
        ModelInput in;
        in.actuation.values = paper::configuration_tensions(c.config, paper::max_tension(robot));
        in.loads.tip_force = c.tip_force;
        Runner r(kind, robot);
        SolverOptions o;
        o.continuation = true;
        const auto s = r.solve(in, o);
        if (!s || !s->converged()) {
          ok = false;
          break;
        }
        tips.push_back(s->tip().p);
      }
      if (!ok) {
        std::cerr << "disks: " << c.name << " " << to_string(kind) << " did not converge\n";
        ++g_failures;
        continue;
      }
      // The three finest counts n1 < n2 < n3: observed order p from the two differences (the
      // counts are not in a fixed ratio, so p solves d12 / d23 = (h1^p - h2^p) / (h2^p - h3^p)
      // with h = 1/n, by bisection), then the limit x3 - d23 h3^p / (h2^p - h3^p).
      const std::size_t m = tips.size();
      const double h1 = 1.0 / ns[m - 3], h2 = 1.0 / ns[m - 2], h3 = 1.0 / ns[m - 1];
      const double d12 = (tips[m - 2] - tips[m - 3]).norm(), d23 = (tips[m - 1] - tips[m - 2]).norm();
      double lo = 0.25, hi = 6.0;
      const auto g = [&](double p) {
        return (std::pow(h1, p) - std::pow(h2, p)) / (std::pow(h2, p) - std::pow(h3, p)) - d12 / d23;
      };
      for (int it = 0; it < 100; ++it) {
        const double mid = 0.5 * (lo + hi);
        (g(mid) > 0) == (g(hi) > 0) ? hi = mid : lo = mid;
      }
      const double p = 0.5 * (lo + hi);
      const double w = std::pow(h3, p) / (std::pow(h2, p) - std::pow(h3, p));
      const Vec3 limit = tips[m - 1] + w * (tips[m - 1] - tips[m - 2]);
      const double uncertainty = w * d23;  // the finest count's own distance to the limit
      std::cout << std::left << std::setw(32) << c.name << std::setw(8) << to_string(kind) << std::right;
      for (double acc : accuracies) {
        const double tol = acc * kLength;
        // The smallest count from which every finer count stays within the tolerance.
        int n_min = -1;
        double err = NAN;
        for (std::size_t i = m; i-- > 0;) {
          const double e = (tips[i] - limit).norm();
          if (e > tol) break;
          n_min = ns[i];
          err = e;
        }
        const bool resolved = n_min > 0 && n_min < ns[m - 3] && uncertainty < 0.5 * tol;
        csv.row(c.name, to_string(kind), acc, resolved ? n_min : -1, err, uncertainty, p);
        std::ostringstream cell;
        if (resolved)
          cell << n_min;
        else
          cell << ">" << ns[m - 3];
        std::cout << std::setw(10) << cell.str();
      }
      std::cout << std::setw(8) << std::setprecision(2) << p << "\n";
    }
}

}  // namespace

int main(int argc, char** argv) {
  Settings cfg;
  if (!bench::parse_case_study_args(argc, argv, "bench_helical", "scenario3|disk_force|disks", 20, 2, cfg)) return 2;
  std::filesystem::create_directories(cfg.out);
  const auto want = [&](const char* part) { return cfg.want(part); };
  if (want("disk_force")) disk_force(cfg);
  if (want("disks")) disks(cfg);
  if (want("scenario3")) scenario3(cfg);
  std::cout << "results written to " << cfg.out << "\n";
  if (g_failures > 0) {
    std::cerr << "error: " << g_failures << " disk-force or disk-count solves did not converge\n";
    return 1;
  }
  return 0;
}
