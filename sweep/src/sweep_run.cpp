// run_sweep: the blocks of a shard solved on worker threads and written in sample order by the
// calling thread as they complete; the command-line entry points.
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <map>
#include <mutex>
#include <thread>

#include "tdcr/core/error.hpp"
#include "tdcr/sweep/sweep_run.hpp"

namespace tdcr {
namespace {

using Clock = std::chrono::steady_clock;

/// A one-line progress bar on stderr, redrawn at most 5 times a second.
class Progress {
 public:
  Progress(bool on, std::uint64_t total) : on_(on && isatty(STDERR_FILENO)), total_(total), start_(Clock::now()) {}
  void update(std::uint64_t done, bool force = false) {
    if (!on_) return;
    const auto now = Clock::now();
    if (!force && now - last_ < std::chrono::milliseconds(200)) return;
    last_ = now;
    const double s = std::chrono::duration<double>(now - start_).count();
    const double frac = total_ ? double(done) / double(total_) : 1.0;
    const int width = 30, filled = static_cast<int>(frac * width);
    const double rate = s > 0 ? double(done) / s : 0.0;
    std::fprintf(stderr, "\r[%s%s] %5.1f%% %llu/%llu samples, %.0f/s, ETA %.0f s   ", std::string(filled, '#').c_str(),
                 std::string(width - filled, ' ').c_str(), 100.0 * frac, static_cast<unsigned long long>(done),
                 static_cast<unsigned long long>(total_), rate, rate > 0 ? double(total_ - done) / rate : 0.0);
    if (done == total_) std::fprintf(stderr, "\n");
    std::fflush(stderr);
  }

 private:
  bool on_;
  std::uint64_t total_;
  Clock::time_point start_, last_;
};

int parse_int(const std::string& text, const std::string& field, int lo, int hi) {
  try {
    std::size_t used = 0;
    const long v = std::stol(text, &used);
    if (used == text.size() && v >= lo && v <= hi) return static_cast<int>(v);
  } catch (const std::exception&) {
  }
  throw InputError(field, text, "must be a whole number from " + std::to_string(lo) + " to " + std::to_string(hi));
}

}  // namespace

SweepRunStats run_sweep(const SweepSpec& spec, const std::string& path, const SweepRunOptions& options) {
  const SampleRange range = shard_samples(spec, options.shard);
  SweepRunStats stats;
  stats.first_sample = prepare_sweep_output(path, spec, options.shard);
  if (stats.first_sample >= range.end) return stats;
  std::FILE* out = std::fopen(path.c_str(), "ab");
  if (!out) throw InputError("-o", path, "cannot write the output file");

  // Blocks are aligned to absolute sample numbers; a resumed block is solved from its start
  // (same warm starts as an uninterrupted run) but writes only the samples still missing.
  const std::uint64_t block = sweep_block_size(spec);
  const std::uint64_t b0 = stats.first_sample / block, b1 = (range.end + block - 1) / block;
  const unsigned hw = std::max(1u, std::thread::hardware_concurrency());
  const int threads = static_cast<int>(std::min<std::uint64_t>(options.threads > 0 ? options.threads : hw, b1 - b0));
  std::atomic<std::uint64_t> next{b0};
  std::mutex mutex;
  std::condition_variable ready;
  std::map<std::uint64_t, std::string> done;
  const auto t0 = Clock::now();

  auto worker = [&] {
    SweepSolver solver(spec);
    for (std::uint64_t b = next++; b < b1; b = next++) {
      std::string rows;
      solver.solve_range(std::max(b * block, range.begin), std::min((b + 1) * block, range.end),
                         stats.first_sample, rows);
      std::lock_guard<std::mutex> lock(mutex);
      done.emplace(b, std::move(rows));
      ready.notify_one();
    }
  };
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t) pool.emplace_back(worker);

  Progress progress(options.progress, range.end - stats.first_sample);
  bool ok = true;
  for (std::uint64_t b = b0; b < b1; ++b) {
    std::string rows;
    {
      std::unique_lock<std::mutex> lock(mutex);
      ready.wait(lock, [&] { return done.count(b) > 0; });
      rows = std::move(done[b]);
      done.erase(b);
    }
    ok = ok && std::fwrite(rows.data(), 1, rows.size(), out) == rows.size() && std::fflush(out) == 0;
    stats.samples_solved = std::min((b + 1) * block, range.end) - stats.first_sample;
    progress.update(stats.samples_solved, b + 1 == b1);
  }
  for (std::thread& t : pool) t.join();
  ok = std::fclose(out) == 0 && ok;
  if (!ok) throw InputError("-o", path, "cannot write the output file (disk full?)");
  stats.wall_s = std::chrono::duration<double>(Clock::now() - t0).count();
  return stats;
}

std::string sweep_usage() {
  return "usage: tdcr sweep SWEEP.json -o OUT.csv [--threads N] [--shard i/N] [--quiet]\n"
         "       tdcr sweep-merge OUT.csv SHARD.csv...\n"
         "\n"
         "Solve every sample of a sweep file (docs/sweeps.md) for its models on all cores; one CSV\n"
         "row per sample and model, in sample order. Rerunning with the same -o resumes.\n"
         "  -o FILE          the CSV file (required)\n"
         "  --threads N      worker threads (default: every core)\n"
         "  --shard i/N      solve part i (0-based) of N only (job arrays); join with sweep-merge\n"
         "  --quiet          no progress bar\n";
}

int sweep_command(const std::vector<std::string>& args) {
  std::string sweep_path, out;
  SweepRunOptions options;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= args.size()) throw InputError(a, "", "missing argument");
      return args[++i];
    };
    if (a == "--help" || a == "-h") {
      std::printf("%s", sweep_usage().c_str());
      return 0;
    } else if (a == "-o" || a == "--output") {
      out = value();
    } else if (a == "--threads") {
      options.threads = parse_int(value(), "--threads", 1, 4096);
    } else if (a == "--shard") {
      const std::string v = value();
      const auto slash = v.find('/');
      if (slash == std::string::npos) throw InputError("--shard", v, "must be i/N with 0 <= i < N");
      options.shard.count = parse_int(v.substr(slash + 1), "--shard", 1, 1000000);
      options.shard.index = parse_int(v.substr(0, slash), "--shard", 0, options.shard.count - 1);
    } else if (a == "--quiet") {
      options.progress = false;
    } else if (!a.empty() && a[0] == '-') {
      throw InputError(a, "", "unknown option of tdcr sweep (see tdcr sweep --help)");
    } else if (sweep_path.empty()) {
      sweep_path = a;
    } else {
      throw InputError(a, "", "unexpected argument (one sweep file per run)");
    }
  }
  if (sweep_path.empty()) throw InputError("sweep", "", "missing sweep file (see tdcr sweep --help)");
  if (out.empty()) throw InputError("-o", "", "missing output file (see tdcr sweep --help)");
  const SweepSpec spec = load_sweep(sweep_path);
  const SweepRunStats s = run_sweep(spec, out, options);
  const SampleRange range = shard_samples(spec, options.shard);
  if (s.first_sample > range.begin)
    std::fprintf(stderr, "resumed at sample %llu\n", static_cast<unsigned long long>(s.first_sample));
  std::fprintf(stderr, "%llu samples x %zu models solved in %.3f s, written to %s\n",
               static_cast<unsigned long long>(s.samples_solved), spec.models.size(), s.wall_s, out.c_str());
  return 0;
}

int sweep_merge_command(const std::vector<std::string>& args) {
  if (!args.empty() && (args[0] == "--help" || args[0] == "-h")) {
    std::printf("%s", sweep_usage().c_str());
    return 0;
  }
  if (args.size() < 2) throw InputError("sweep-merge", "", "usage: tdcr sweep-merge OUT.csv SHARD.csv...");
  merge_sweep_shards(args[0], std::vector<std::string>(args.begin() + 1, args.end()));
  return 0;
}

}  // namespace tdcr
