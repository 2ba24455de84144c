// Shared helpers of the benchmark executables: timing of repeated solves, CSV output, progress.
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "tdcr/models/static_model.hpp"

namespace tdcr::bench {

/// Median and minimum wall time (us) of `repeat` solves of one model from the same initial guess
/// (no warm start), on one reused workspace, plus the last solution.
struct Timing {
  double median_us = 0.0;
  double min_us = 0.0;
  int repeat = 0;
  Solution last;
};

inline Timing time_solves(const StaticModel& model, ModelWorkspace& ws, const ModelInput& input,
                          const SolverOptions& options, int repeat, const Solution* warm = nullptr) {
  std::vector<double> t;
  Timing out;
  for (int i = 0; i < repeat; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    out.last = solve(model, ws, input, options, warm);
    t.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(t.begin(), t.end());
  out.repeat = repeat;
  out.min_us = t.front();
  out.median_us = t.size() % 2 ? t[t.size() / 2] : 0.5 * (t[t.size() / 2 - 1] + t[t.size() / 2]);
  return out;
}

/// The same for a scene's input and solver options, on a fresh workspace of `model`.
inline Timing time_solves(const StaticModel& model, const Scene& scene, int repeat, const Solution* warm = nullptr) {
  auto ws = model.make_workspace();
  return time_solves(model, *ws, scene.input(), scene.solver, repeat, warm);
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

}  // namespace tdcr::bench
