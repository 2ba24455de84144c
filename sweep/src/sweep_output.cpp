// The sweep's CSV file: header, shards, resuming, merging.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "tdcr/core/error.hpp"
#include "tdcr/sweep/sweep_run.hpp"

namespace tdcr {
namespace {

std::string read_all(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "", "cannot read the file (does it exist?)");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string hash_line(const SweepSpec& spec) {
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(spec.hash));
  std::string models;
  for (ModelKind m : spec.models) models += (models.empty() ? "" : ",") + to_string(m);
  return std::string("# tdcr sweep ") + hex + " samples=" + std::to_string(spec.sample_count()) + " models=" + models + "\n";
}

std::string csv_columns(const SweepSpec& spec) {
  std::string h = "sample";
  for (const SweepAxis& a : spec.axes) h += ',' + a.field;
  return h + ",model,status,reason,tip_x,tip_y,tip_z,rot_x,rot_y,rot_z,iterations,solve_time_s\n";
}

/// The shard line names the block size: the merge checks each shard's row count with it.
std::string shard_line(const SweepShard& shard, std::uint64_t block) {
  return "# shard " + std::to_string(shard.index) + "/" + std::to_string(shard.count) + " block=" + std::to_string(block) + "\n";
}

std::size_t count_lines(const std::string& s, std::size_t from) {
  return static_cast<std::size_t>(std::count(s.begin() + static_cast<std::ptrdiff_t>(from), s.end(), '\n'));
}

/// First sample of shard i of `count` over n samples (shards hold whole blocks).
std::uint64_t shard_edge(std::uint64_t n, std::uint64_t block, int i, int count) {
  const std::uint64_t blocks = (n + block - 1) / block;
  return std::min(n, blocks * static_cast<std::uint64_t>(i) / static_cast<std::uint64_t>(count) * block);
}

}  // namespace

SampleRange shard_samples(const SweepSpec& spec, const SweepShard& shard) {
  const std::uint64_t n = spec.sample_count();
  const std::uint64_t block = sweep_block_size(spec);
  return {shard_edge(n, block, shard.index, shard.count), shard_edge(n, block, shard.index + 1, shard.count)};
}

std::string sweep_header(const SweepSpec& spec, const SweepShard& shard) {
  return hash_line(spec) + (shard.count > 1 ? shard_line(shard, sweep_block_size(spec)) : "") + csv_columns(spec);
}

std::uint64_t prepare_sweep_output(const std::string& path, const SweepSpec& spec, const SweepShard& shard) {
  const SampleRange range = shard_samples(spec, shard);
  const std::string header = sweep_header(spec, shard);
  std::string text;
  if (std::filesystem::exists(path)) text = read_all(path);
  if (text.size() < header.size() && header.compare(0, text.size(), text) == 0) {
    // New, empty, or cut off inside the header: start over.
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f || std::fwrite(header.data(), 1, header.size(), f) != header.size() || std::fclose(f) != 0)
      throw InputError("-o", path, "cannot write the output file");
    return range.begin;
  }
  if (text.compare(0, header.size(), header) != 0)
    throw InputError("-o", path,
                     "holds the rows of another sweep or shard (its header differs: the sweep file, its base scene "
                     "or --shard changed); remove it or write to another file");
  const std::size_t rows_per_sample = spec.models.size();
  const std::size_t samples = count_lines(text, header.size()) / rows_per_sample;
  if (samples > range.end - range.begin)
    throw InputError("-o", path, "has more rows than the sweep has samples");
  // Keep the complete samples; drop a cut-off line or a sample with some of its models only.
  std::size_t keep = header.size();
  for (std::size_t r = 0; r < samples * rows_per_sample; ++r) keep = text.find('\n', keep) + 1;
  if (keep < text.size()) std::filesystem::resize_file(path, keep);
  return range.begin + samples;
}

void merge_sweep_shards(const std::string& out, const std::vector<std::string>& shards) {
  if (shards.empty()) throw InputError("sweep-merge", "", "no shard files given");
  struct Part {
    int index = -1;
    std::string path, rows;
  };
  std::vector<Part> parts;
  std::string first_line, columns;
  int count = -1;
  std::uint64_t block = 0;
  for (const std::string& path : shards) {
    const std::string text = read_all(path);
    std::istringstream in(text);
    std::string l1, l2, l3;
    std::getline(in, l1);
    std::getline(in, l2);
    std::getline(in, l3);
    int i = -1, n = -1;
    unsigned long long b = 0;
    if (l1.rfind("# tdcr sweep ", 0) != 0 || std::sscanf(l2.c_str(), "# shard %d/%d block=%llu", &i, &n, &b) != 3 || i < 0 ||
        n < 1 || i >= n || b < 1)
      throw InputError(path, l2, "is not a shard file of tdcr sweep --shard i/N");
    if (parts.empty()) first_line = l1, columns = l3, count = n, block = b;
    if (l1 != first_line || l3 != columns) throw InputError(path, l1, "belongs to another sweep than " + parts[0].path);
    if (b != block) throw InputError(path, l2, "has blocks of " + std::to_string(b) + " samples, the others of " + std::to_string(block));
    if (n != count) throw InputError(path, l2, "is a shard of /" + std::to_string(n) + ", the others of /" + std::to_string(count));
    for (const Part& p : parts)
      if (p.index == i) throw InputError(path, l2, "shard given twice (also " + p.path + ")");
    const std::size_t body = l1.size() + l2.size() + l3.size() + 3;
    parts.push_back({i, path, text.size() > body ? text.substr(body) : std::string()});
  }
  if (static_cast<int>(parts.size()) != count)
    throw InputError("sweep-merge", std::to_string(parts.size()) + " of " + std::to_string(count),
                     "every shard 0.." + std::to_string(count - 1) + " is needed");
  std::sort(parts.begin(), parts.end(), [](const Part& a, const Part& b) { return a.index < b.index; });
  // The hash line holds the sample and model counts: check that each shard is complete.
  unsigned long long samples = 0;
  std::sscanf(first_line.c_str(), "# tdcr sweep %*s samples=%llu", &samples);
  const std::size_t models = static_cast<std::size_t>(std::count(first_line.begin(), first_line.end(), ',')) + 1;
  for (const Part& p : parts) {
    const std::size_t expected = (shard_edge(samples, block, p.index + 1, count) - shard_edge(samples, block, p.index, count)) * models;
    const std::size_t got = count_lines(p.rows, 0);
    if (got != expected || (!p.rows.empty() && p.rows.back() != '\n'))
      throw InputError(p.path, std::to_string(got) + " of " + std::to_string(expected) + " rows",
                       "incomplete shard: rerun its tdcr sweep --shard command to finish it");
  }
  std::FILE* f = std::fopen(out.c_str(), "wb");
  if (!f) throw InputError("sweep-merge", out, "cannot write the output file");
  const std::string head = first_line + "\n" + columns + "\n";
  bool ok = std::fwrite(head.data(), 1, head.size(), f) == head.size();
  for (const Part& p : parts) ok = ok && std::fwrite(p.rows.data(), 1, p.rows.size(), f) == p.rows.size();
  if (std::fclose(f) != 0 || !ok) throw InputError("sweep-merge", out, "cannot write the output file");
}

}  // namespace tdcr
