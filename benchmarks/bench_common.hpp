// Shared helpers of the benchmark executables: timing of repeated solves, CSV output, progress,
// the loaded cases of the paper code's reference data, the machine stamp of a run.
#pragma once

#include <time.h>  // clock_gettime, CLOCK_THREAD_CPUTIME_ID

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "tdcr/models/static_model.hpp"

namespace tdcr::bench {

/// Median of the values (NaN if there are none).
inline double median(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

/// Wall time (us) of one call of `f`.
template <typename F>
double wall_us(F&& f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
}

/// CPU time (us) the calling thread has used so far.
inline double thread_cpu_us() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e6 * double(t.tv_sec) + 1e-3 * double(t.tv_nsec);
}

/// Wall time and the calling thread's CPU time (us) of one call. The CPU time leaves out the
/// time other jobs on the machine hold the core; the wall time does not.
struct CallTime {
  double wall_us = 0.0, cpu_us = 0.0;
};

template <typename F>
CallTime time_call(F&& f) {
  CallTime t;
  const double c0 = thread_cpu_us();
  t.wall_us = wall_us(f);
  t.cpu_us = thread_cpu_us() - c0;
  return t;
}

/// Median and minimum wall time (us) of `repeat` solves of one model from the same initial guess
/// (no warm start), on one reused workspace, plus the last solution.
struct Timing {
  double median_us = 0.0;
  double min_us = 0.0;
  int repeat = 0;
  Solution last;
};

/// Writes to every cache line of a 32 MB buffer: the caches then hold none of the solver's code or
/// data, as after another program's work (bench_loaded --evict-caches; bench_side_by_side's tdcr
/// solves follow a paper-code solve).
inline void evict_caches() {
  static std::vector<unsigned char> junk(std::size_t{32} << 20);
  for (std::size_t i = 0; i < junk.size(); i += 64) junk[i] = static_cast<unsigned char>(junk[i] + 1);
}

inline Timing time_solves(const StaticModel& model, ModelWorkspace& ws, const ModelInput& input,
                          const SolverOptions& options, int repeat, const Solution* warm = nullptr,
                          bool evict = false) {
  std::vector<double> t;
  Timing out;
  for (int i = 0; i < repeat; ++i) {
    if (evict) evict_caches();
    t.push_back(wall_us([&] { out.last = solve(model, ws, input, options, warm); }));
  }
  out.repeat = repeat;
  out.min_us = *std::min_element(t.begin(), t.end());
  out.median_us = median(t);
  return out;
}

/// The same for a scene's input and solver options, on a fresh workspace of `model`.
inline Timing time_solves(const StaticModel& model, const Scene& scene, int repeat, const Solution* warm = nullptr) {
  auto ws = model.make_workspace();
  return time_solves(model, *ws, scene.input(), scene.solver, repeat, warm);
}

/// The models of a comma-separated list of names (`vc,ccsub,vcref,prb`: a --models argument).
inline std::vector<ModelKind> parse_models(const std::string& list) {
  std::vector<ModelKind> out;
  std::stringstream in(list);
  for (std::string name; std::getline(in, name, ',');) out.push_back(parse_model_kind(name));
  return out;
}

/// A CSV file with a header row; rows are written as they come (a sweep cut short keeps its rows).
class Csv {
 public:
  Csv(const std::string& path, const std::string& header) : out_(path) {
    if (!out_) std::fprintf(stderr, "cannot write %s\n", path.c_str());
    out_ << header << "\n";
  }
  template <typename... Args>
  void row(const Args&... args) {
    bool first = true;
    ((out_ << (first ? "" : ",") << args, first = false), ...);
    out_ << "\n";
    out_.flush();
  }
  bool ok() const { return static_cast<bool>(out_); }

 private:
  std::ofstream out_;
};

/// One progress line on stderr, overwritten in place.
inline void progress(const std::string& what, int done, int total) {
  std::fprintf(stderr, "\r%-60s %4d/%-4d", what.c_str(), done, total);
  if (done == total) std::fprintf(stderr, "\n");
  std::fflush(stderr);
}

/// The command line of the case-study benchmarks: [--quick] [--out DIR] [--repeat N] [--only PART].
struct CaseStudyArgs {
  bool quick = false;
  std::string out = "benchmark-results";
  int repeat = 0;    ///< The caller's default unless given (--quick: `quick_repeat`).
  std::string only;  ///< One of the parts, or empty: all of them.
  bool want(const char* part) const { return only.empty() || only == part; }
};

/// Parses the arguments; prints a clear error and returns false on an unknown argument, a repeat
/// count below 1 or a part not in `parts` (separated by '|', as in the usage line).
inline bool parse_case_study_args(int argc, char** argv, const std::string& program, const std::string& parts,
                                  int repeat, int quick_repeat, CaseStudyArgs& args) {
  args.repeat = repeat;
  bool repeat_given = false;
  const std::string usage = "usage: " + program + " [--quick] [--out DIR] [--repeat N] [--only " + parts + "]\n";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--quick") {
      args.quick = true;
    } else if (a == "--out" && i + 1 < argc) {
      args.out = argv[++i];
    } else if (a == "--repeat" && i + 1 < argc) {
      args.repeat = std::atoi(argv[++i]);
      repeat_given = true;
      if (args.repeat < 1) {
        std::fprintf(stderr, "error: --repeat must be a positive integer (got %s)\n", argv[i]);
        return false;
      }
    } else if (a == "--only" && i + 1 < argc) {
      args.only = argv[++i];
      if (("|" + parts + "|").find("|" + args.only + "|") == std::string::npos) {
        std::fprintf(stderr, "error: --only must be one of %s (got %s)\n", parts.c_str(), args.only.c_str());
        return false;
      }
    } else {
      std::fprintf(stderr, "%s", usage.c_str());
      return false;
    }
  }
  if (args.quick && !repeat_given) args.repeat = quick_repeat;
  return true;
}

// ---- the paper code's reference data (benchmarks/data) ---------------------------------------

/// A CSV file of benchmarks/data as rows of named fields ('#' lines are comments). TDCR_SOURCE_DIR:
/// the benchmark targets define it.
inline std::vector<std::map<std::string, std::string>> read_data_csv(const std::string& name) {
  const std::string path = std::string(TDCR_SOURCE_DIR) + "/benchmarks/data/" + name;
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path);
  std::vector<std::string> header;
  std::vector<std::map<std::string, std::string>> rows;
  std::string line;
  auto split = [](const std::string& s) {
    std::vector<std::string> v;
    std::stringstream ss(s);
    std::string x;
    while (std::getline(ss, x, ',')) v.push_back(x);
    return v;
  };
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (header.empty()) {
      header = split(line);
      continue;
    }
    const auto v = split(line);
    std::map<std::string, std::string> r;
    for (size_t i = 0; i < header.size() && i < v.size(); ++i) r[header[i]] = v[i];
    rows.push_back(r);
  }
  return rows;
}

/// The paper's name of a model, as in the reference data's `model` column.
inline std::string paper_name(ModelKind k) {
  switch (k) {
    case ModelKind::VC: return "VC";
    case ModelKind::CCsub: return "CCsub";
    case ModelKind::VCref: return "VCref";
    case ModelKind::PRB: return "PRB";
    default: return to_string(k);
  }
}

/// One model's row of benchmarks/data/paper_code_cases_timing.csv: the paper's code on a loaded
/// case (its flag, squared residual, tip, and the stored times of 3 cold solves).
struct PaperResult {
  bool converged = false;
  double residual = std::numeric_limits<double>::quiet_NaN();
  double median_us = std::numeric_limits<double>::quiet_NaN();
  double min_us = std::numeric_limits<double>::quiet_NaN();
  Vec3 tip = Vec3::Constant(std::numeric_limits<double>::quiet_NaN());
};

/// A loaded case of benchmarks/data/paper_code_cases_inputs.csv (paper robot with n disks per
/// segment, tensions T1..T4, tip force in the base frame) and the paper code's stored results of
/// it per model (VC, CCsub, VCref, PRB).
struct LoadedCase {
  int id = 0, n = 0;
  ModelInput input;
  std::map<ModelKind, PaperResult> paper;
};

/// The 60 loaded cases, by case id.
inline std::vector<LoadedCase> loaded_cases() {
  std::map<int, LoadedCase> by_id;
  for (const auto& r : read_data_csv("paper_code_cases_inputs.csv")) {
    LoadedCase& c = by_id[std::stoi(r.at("case_id"))];
    c.id = std::stoi(r.at("case_id"));
    c.n = std::stoi(r.at("n"));
    c.input.actuation.kind = Actuation::Kind::Tensions;
    c.input.actuation.values = {std::stod(r.at("T1")), std::stod(r.at("T2")), std::stod(r.at("T3")),
                                std::stod(r.at("T4"))};
    c.input.loads.tip_force = Vec3(std::stod(r.at("Fx")), std::stod(r.at("Fy")), std::stod(r.at("Fz")));
  }
  for (const auto& r : read_data_csv("paper_code_cases_timing.csv")) {
    LoadedCase& c = by_id.at(std::stoi(r.at("case_id")));
    for (ModelKind k : {ModelKind::VC, ModelKind::CCsub, ModelKind::VCref, ModelKind::PRB}) {
      if (paper_name(k) != r.at("model")) continue;
      PaperResult& p = c.paper[k];
      p.converged = r.at("converged") == "1";
      p.residual = std::stod(r.at("residual"));
      p.median_us = std::stod(r.at("median_us"));
      p.min_us = std::stod(r.at("min_us"));
      p.tip = Vec3(std::stod(r.at("tip_x")), std::stod(r.at("tip_y")), std::stod(r.at("tip_z")));
    }
  }
  std::vector<LoadedCase> out;
  for (auto& [id, c] : by_id) out.push_back(std::move(c));
  return out;
}

/// The first line of a run's CSV files: "# machine: <cpu>, <cores> cores; date: <UTC>".
inline std::string machine_stamp() {
  std::string cpu = "unknown";
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("model name", 0) == 0) {
      cpu = line.substr(line.find(':') + 2);
      break;
    }
  const std::time_t now = std::time(nullptr);
  char date[32];
  std::strftime(date, sizeof date, "%Y-%m-%dT%H:%MZ", std::gmtime(&now));
  return "# machine: " + cpu + ", " + std::to_string(std::thread::hardware_concurrency()) + " cores; date: " + date +
         "\n";
}

}  // namespace tdcr::bench
