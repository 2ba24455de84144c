/// @file sweep_run.hpp
/// @brief Running a sweep: solving samples with warm starts, the CSV output (resumable, in
/// sample order whatever the thread count), shards for job arrays and their merge.
///
/// The samples are cut into blocks of consecutive samples (sweep_block_size). A block is solved
/// by one thread with one model and workspace per model, in its solve order (sweep_solve_order:
/// grid order, or random samples sorted along a Hilbert curve), each sample warm-started from the
/// previously solved sample of the block if that converged; the first one starts cold. The rows
/// are written in sample order and depend on the sweep only, not on the threads, shards or MPI
/// ranks that solved them (the solve time column aside).
///
/// The output file starts with `# tdcr sweep <hash> ...` (the sweep file's hash: a rerun into a
/// file of another sweep is refused), for a shard a `# shard i/N` line, then the CSV header
/// `sample,<axis fields>,model,status,reason,tip_x,tip_y,tip_z,rot_x,rot_y,rot_z,iterations,solve_time_s`
/// (m; rot = rotation vector of the tip frame, rad; s), one row per (sample, model).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "tdcr/sweep/sweep_file.hpp"

namespace tdcr {

/// Samples per block of a grid (the unit of work and of warm-start chains), in grid order.
constexpr std::uint64_t kSweepBlock = 32;
/// Samples per block of a random sweep solved in Hilbert order: enough for near neighbours
/// (docs/sweeps.md, "Solve order"), few enough to share 1e5 samples among many threads.
constexpr std::uint64_t kSweepRandomBlock = 2048;

/// @brief The block size of `spec`: kSweepRandomBlock for random samples in warm-start order,
/// else kSweepBlock.
std::uint64_t sweep_block_size(const SweepSpec& spec);

/// @brief The order in which samples [first, last) (one block) are solved. A grid, or a sweep
/// with "order": "sample", keeps sample order. Random samples are sorted by the values of their
/// scene axes (a model serves a run of equal scenes), then along a Hilbert curve through the
/// input axes normalised to [0, 1], so that consecutive samples are near neighbours.
void sweep_solve_order(const SweepSpec& spec, std::uint64_t first, std::uint64_t last, std::vector<std::uint64_t>& order);

/// @brief Part i of N of a sweep (whole blocks; shard i of N solves the i-th contiguous part).
struct SweepShard {
  int index = 0;  ///< i, 0-based.
  int count = 1;  ///< N.
};

/// @brief Samples [begin, end) of a shard.
struct SampleRange {
  std::uint64_t begin = 0;  ///< First sample.
  std::uint64_t end = 0;    ///< One past the last sample.
};
/// @brief The samples of shard i of N: whole blocks, contiguous, in shard order.
SampleRange shard_samples(const SweepSpec& spec, const SweepShard& shard);

/// @brief Solves samples of one sweep in order (one per thread): the models, their workspaces
/// and the previous converged solutions. Rebuilds the models when a scene axis changes.
class SweepSolver {
 public:
  /// @brief A solver of `spec`'s samples (the models are built at the first sample).
  explicit SweepSolver(const SweepSpec& spec);
  ~SweepSolver();  ///< Frees the models and workspaces.
  /// @brief Solves the block [first, last) in its solve order (cold at its first sample) and
  /// appends the CSV rows of samples >= emit_from to `rows`, in sample order. A sample that fails or whose input is refused is a row
  /// with its status and reason, never an exception.
  void solve_range(std::uint64_t first, std::uint64_t last, std::uint64_t emit_from, std::string& rows);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// @brief The header lines of the output of `shard` (hash line, shard line if N > 1, CSV header).
std::string sweep_header(const SweepSpec& spec, const SweepShard& shard);

/// @brief Prepares `path` for the samples of `shard`: writes the header into a new or empty
/// file; for a file of the same sweep keeps every complete sample's rows (a cut-off last line
/// or sample is removed) and returns the first sample still to solve. Throws InputError if the
/// file holds another sweep or shard.
std::uint64_t prepare_sweep_output(const std::string& path, const SweepSpec& spec, const SweepShard& shard);

/// @brief Options of run_sweep.
struct SweepRunOptions {
  int threads = 0;        ///< Worker threads; 0: every core (std::thread::hardware_concurrency).
  SweepShard shard;       ///< The part to solve.
  bool progress = true;   ///< A progress bar on stderr if it is a terminal.
};

/// @brief What run_sweep did.
struct SweepRunStats {
  std::uint64_t first_sample = 0;    ///< Where this run began (> shard begin: resumed).
  std::uint64_t samples_solved = 0;  ///< Samples solved and written by this run.
  double wall_s = 0.0;               ///< Wall time of the solves (s).
};

/// @brief Solves the shard's samples not yet in `path` and appends their rows in sample order,
/// flushed block by block.
SweepRunStats run_sweep(const SweepSpec& spec, const std::string& path, const SweepRunOptions& options = {});

/// @brief Joins the complete shard files of one sweep (any order) into `out`, equal to the file
/// of a single run. Throws InputError naming the shard file if one is missing, repeated,
/// incomplete or of another sweep.
void merge_sweep_shards(const std::string& out, const std::vector<std::string>& shards);

/// @brief `tdcr sweep SWEEP.json -o OUT.csv [--threads N] [--shard i/N]` (args after "sweep").
/// Returns the exit status; throws InputError on bad input.
int sweep_command(const std::vector<std::string>& args);
/// @brief `tdcr sweep-merge OUT.csv SHARD...` (args after "sweep-merge").
int sweep_merge_command(const std::vector<std::string>& args);
/// @brief The usage text of both commands.
std::string sweep_usage();

}  // namespace tdcr
