// tdcr-sweep-mpi SWEEP.json -o OUT.csv: a sweep across MPI ranks. The blocks still missing from
// OUT.csv go round-robin to the ranks; every rank solves its blocks in order and sends each
// block's rows to rank 0, which solves its own share too and writes every block in sample
// order (the same file as `tdcr sweep`, resumable the same way).
//
// Exit status: 0 done, 2 bad input or usage, 3 internal error.
#include <mpi.h>

#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "tdcr/core/error.hpp"
#include "tdcr/sweep/sweep_run.hpp"

namespace {

constexpr int kRowsTag = 1;

int run(int rank, int ranks, const std::vector<std::string>& args) {
  std::string sweep_path, out;
  for (std::size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "-o" && i + 1 < args.size())
      out = args[++i];
    else if (args[i] == "--help" || args[i] == "-h") {
      if (rank == 0) std::printf("usage: mpirun -np K tdcr-sweep-mpi SWEEP.json -o OUT.csv\n");
      return 0;
    } else if (!args[i].empty() && args[i][0] != '-' && sweep_path.empty())
      sweep_path = args[i];
    else
      throw tdcr::InputError(args[i], "", "unexpected argument (usage: tdcr-sweep-mpi SWEEP.json -o OUT.csv)");
  }
  if (sweep_path.empty() || out.empty())
    throw tdcr::InputError("tdcr-sweep-mpi", "", "usage: tdcr-sweep-mpi SWEEP.json -o OUT.csv");
  // Every rank validates the sweep (the same error everywhere, before any solve).
  const tdcr::SweepSpec spec = tdcr::load_sweep(sweep_path);
  const tdcr::SampleRange range = tdcr::shard_samples(spec, {});
  unsigned long long first = 0;
  if (rank == 0) first = tdcr::prepare_sweep_output(out, spec, {});
  MPI_Bcast(&first, 1, MPI_UNSIGNED_LONG_LONG, 0, MPI_COMM_WORLD);
  // Nothing left (a finished file): no block to solve.
  const std::uint64_t block = tdcr::sweep_block_size(spec);
  const std::uint64_t b0 = first / block;
  const std::uint64_t b1 = first >= range.end ? b0 : (range.end + block - 1) / block;
  const auto owner = [&](std::uint64_t b) { return static_cast<int>((b - b0) % static_cast<std::uint64_t>(ranks)); };
  tdcr::SweepSolver solver(spec);
  const auto solve_block = [&](std::uint64_t b) {
    std::string rows;
    solver.solve_range(b * block, std::min((b + 1) * block, range.end), first, rows);
    return rows;
  };
  if (rank != 0) {
    for (std::uint64_t b = b0 + static_cast<std::uint64_t>(rank); b < b1; b += static_cast<std::uint64_t>(ranks)) {
      const std::string rows = solve_block(b);
      MPI_Send(rows.data(), static_cast<int>(rows.size()), MPI_CHAR, 0, kRowsTag, MPI_COMM_WORLD);
    }
    return 0;
  }
  std::FILE* f = b0 < b1 ? std::fopen(out.c_str(), "ab") : nullptr;
  if (b0 < b1 && !f) throw tdcr::InputError("-o", out, "cannot write the output file");
  for (std::uint64_t b = b0; b < b1; ++b) {
    std::string rows;
    if (owner(b) == 0) {
      rows = solve_block(b);
    } else {
      MPI_Status status;
      MPI_Probe(owner(b), kRowsTag, MPI_COMM_WORLD, &status);
      int size = 0;
      MPI_Get_count(&status, MPI_CHAR, &size);
      rows.resize(static_cast<std::size_t>(size));
      MPI_Recv(rows.data(), size, MPI_CHAR, owner(b), kRowsTag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    }
    std::fwrite(rows.data(), 1, rows.size(), f);
    std::fflush(f);
  }
  if (f && std::fclose(f) != 0) throw tdcr::InputError("-o", out, "cannot write the output file");
  std::fprintf(stderr, "%llu samples x %zu models on %d ranks, written to %s\n",
               static_cast<unsigned long long>(range.end - first), spec.models.size(), ranks, out.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, ranks = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  int code = 0;
  try {
    code = run(rank, ranks, std::vector<std::string>(argv + 1, argv + argc));
  } catch (const tdcr::InputError& e) {
    if (rank == 0) std::fprintf(stderr, "error: %s\n", e.what());
    code = 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "internal error (rank %d): %s\n", rank, e.what());
    MPI_Abort(MPI_COMM_WORLD, 3);
  }
  MPI_Finalize();
  return code;
}
