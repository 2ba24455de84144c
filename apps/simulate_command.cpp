// tdcr simulate SCENE.json --duration T [--dt H] [--model M] [-o OUT.csv|OUT.npz] [--quiet]: the
// scene's robot from rest on the static answer of its timeline's first entry, moving under the
// timeline (tdcr::simulate); one CSV row per output step, or a NumPy .npz of arrays (written here:
// a zip archive of .npy files, stored without compression); a progress bar on standard error
// when it is a terminal (docs/dynamics.md).
#include "simulate_command.hpp"

#include "cli_option.hpp"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "tdcr/core/error.hpp"
#include "tdcr/core/lie.hpp"
#include "tdcr/core/scene_io.hpp"
#include "tdcr/models/dynamics.hpp"
#include "tdcr/models/static_model.hpp"

namespace tdcr::cli {

namespace {

double number(const std::string& name, const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !std::isfinite(v)) throw InputError(name, text, "expected a finite number");
  return v;
}

void write_csv(std::ostream& out, const SimulationResult& r, std::size_t tendons) {
  out << "t,tip_x,tip_y,tip_z,rot_x,rot_y,rot_z,status,iterations,kinetic_energy,potential_energy";
  for (std::size_t k = 0; k < tendons; ++k) out << ",T_" << k + 1;
  out << "\n";
  char line[512];
  for (const SimulationStep& s : r.steps) {
    const Vec3 w = lie::log_so3(s.tip.R);
    std::snprintf(line, sizeof line, "%.10g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%s,%d,%.9g,%.9g", s.t, s.tip.p.x(),
                  s.tip.p.y(), s.tip.p.z(), w.x(), w.y(), w.z(), to_string(s.status).c_str(), s.iterations,
                  s.kinetic_energy, s.potential_energy);
    out << line;
    for (std::size_t k = 0; k < tendons; ++k) {
      std::snprintf(line, sizeof line, ",%.12g", k < s.tensions.size() ? s.tensions[k] : NAN);
      out << line;
    }
    out << "\n";
  }
}

// --- NumPy .npz: a zip archive (stored, no compression) of .npy arrays ---

// CRC-32 (ISO-HDLC, the zip format's): reflected polynomial 0xEDB88320, bit by bit.
std::uint32_t crc32(const std::string& data) {
  std::uint32_t c = 0xFFFFFFFFu;
  for (const unsigned char b : data) {
    c ^= b;
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
  }
  return ~c;
}

void put16(std::string& out, unsigned v) {
  out += static_cast<char>(v & 0xFF);
  out += static_cast<char>((v >> 8) & 0xFF);
}
void put32(std::string& out, std::uint32_t v) {
  put16(out, v & 0xFFFF);
  put16(out, v >> 16);
}

// One .npy file (format 1.0): magic, header length, the header dict padded with spaces to a
// multiple of 64 bytes with its newline, then the data in C order, little endian.
std::string npy(const std::string& descr, const std::vector<std::size_t>& shape, const std::string& data) {
  std::string dims;
  for (const std::size_t d : shape) dims += std::to_string(d) + ", ";
  if (shape.size() > 1) dims.resize(dims.size() - 2);  // (N,) keeps its comma
  std::string header = "{'descr': '" + descr + "', 'fortran_order': False, 'shape': (" + dims + "), }";
  const std::size_t total = 10 + header.size() + 1;
  header.append((64 - total % 64) % 64, ' ');
  header += '\n';
  std::string out = "\x93NUMPY";
  out += static_cast<char>(1);
  out += static_cast<char>(0);
  put16(out, static_cast<unsigned>(header.size()));
  return out + header + data;
}

// Little-endian bytes of doubles and 64-bit integers (this code runs on little-endian hosts only:
// checked at the write).
void append(std::string& out, double v) { out.append(reinterpret_cast<const char*>(&v), sizeof v); }
void append(std::string& out, std::int64_t v) { out.append(reinterpret_cast<const char*>(&v), sizeof v); }

class NpzWriter {
 public:
  void add(const std::string& name, const std::string& npy_file) {
    const std::string file = name + ".npy";
    if (body_.size() + npy_file.size() + 100 > 0xFFFFFFFFull)
      throw std::runtime_error("the .npz output would exceed 4 GB (no zip64 here): simulate fewer steps");
    const std::uint32_t crc = crc32(npy_file), size = static_cast<std::uint32_t>(npy_file.size());
    const std::uint32_t offset = static_cast<std::uint32_t>(body_.size());
    // Local file header: version 2.0, no flags, stored, DOS time 0 (1980-01-01).
    put32(body_, 0x04034b50u);
    put16(body_, 20), put16(body_, 0), put16(body_, 0), put16(body_, 0), put16(body_, 0x21);
    put32(body_, crc), put32(body_, size), put32(body_, size);
    put16(body_, static_cast<unsigned>(file.size())), put16(body_, 0);
    body_ += file;
    body_ += npy_file;
    // Its central directory entry.
    put32(directory_, 0x02014b50u);
    put16(directory_, 20), put16(directory_, 20), put16(directory_, 0), put16(directory_, 0);
    put16(directory_, 0), put16(directory_, 0x21);
    put32(directory_, crc), put32(directory_, size), put32(directory_, size);
    put16(directory_, static_cast<unsigned>(file.size())), put16(directory_, 0), put16(directory_, 0);
    put16(directory_, 0), put16(directory_, 0), put32(directory_, 0), put32(directory_, offset);
    directory_ += file;
    ++entries_;
  }
  void write(std::ostream& out) const {
    std::string end;
    put32(end, 0x06054b50u);
    put16(end, 0), put16(end, 0), put16(end, entries_), put16(end, entries_);
    put32(end, static_cast<std::uint32_t>(directory_.size())), put32(end, static_cast<std::uint32_t>(body_.size()));
    put16(end, 0);
    out << body_ << directory_ << end;
  }

 private:
  std::string body_, directory_;
  unsigned entries_ = 0;
};

// The arrays of docs/dynamics.md ("The npz output"): per output step t, tip, rot, status,
// iterations, residual, kinetic_energy, potential_energy, tensions (N, m), tendon_displacements
// (N, m) where the model reports them, and the disk centres (N, disks, 3).
void write_npz(std::ostream& out, const SimulationResult& r, std::size_t tendons,
               const std::vector<std::vector<Vec3>>& disks) {
  {
    const std::uint16_t probe = 1;
    if (*reinterpret_cast<const unsigned char*>(&probe) != 1)
      throw std::runtime_error("the .npz writer needs a little-endian host");
  }
  const std::size_t N = r.steps.size();
  NpzWriter z;
  std::string t, tip, rot, it, res, ke, pe, T, d;
  std::size_t status_len = 1;
  for (const SimulationStep& s : r.steps) status_len = std::max(status_len, to_string(s.status).size());
  std::string status;
  bool have_pulls = N > 0;
  for (const SimulationStep& s : r.steps) {
    append(t, s.t);
    for (int i = 0; i < 3; ++i) append(tip, s.tip.p[i]);
    const Vec3 w = lie::log_so3(s.tip.R);
    for (int i = 0; i < 3; ++i) append(rot, w[i]);
    const std::string st = to_string(s.status);
    for (std::size_t c = 0; c < status_len; ++c) {  // UTF-32LE, padded with NULs
      const char ch = c < st.size() ? st[c] : '\0';
      status += ch;
      status.append(3, '\0');
    }
    append(it, static_cast<std::int64_t>(s.iterations));
    append(res, s.residual);
    append(ke, s.kinetic_energy);
    append(pe, s.potential_energy);
    for (std::size_t k = 0; k < tendons; ++k) append(T, k < s.tensions.size() ? s.tensions[k] : NAN);
    have_pulls = have_pulls && s.tendon_displacements.size() == tendons;
    for (std::size_t k = 0; k < tendons && k < s.tendon_displacements.size(); ++k) append(d, s.tendon_displacements[k]);
  }
  z.add("t", npy("<f8", {N}, t));
  z.add("tip", npy("<f8", {N, 3}, tip));
  z.add("rot", npy("<f8", {N, 3}, rot));
  z.add("status", npy("<U" + std::to_string(status_len), {N}, status));
  z.add("iterations", npy("<i8", {N}, it));
  z.add("residual", npy("<f8", {N}, res));
  z.add("kinetic_energy", npy("<f8", {N}, ke));
  z.add("potential_energy", npy("<f8", {N}, pe));
  z.add("tensions", npy("<f8", {N, tendons}, T));
  if (have_pulls) z.add("tendon_displacements", npy("<f8", {N, tendons}, d));
  if (disks.size() == N && N > 0) {
    const std::size_t D = disks.front().size();
    std::string p;
    bool same = true;
    for (const std::vector<Vec3>& step : disks) {
      same = same && step.size() == D;
      for (std::size_t j = 0; j < D && j < step.size(); ++j)
        for (int i = 0; i < 3; ++i) append(p, step[j][i]);
    }
    if (same) z.add("disks", npy("<f8", {N, D, 3}, p));
  }
  z.write(out);
}

// --- The progress bar (standard error, when it is a terminal) ---

class Progress {
 public:
  explicit Progress(double duration) : duration_(duration), start_(Clock::now()), last_(start_) {}
  void update(const SimulationStep& s, bool force = false) {
    ++steps_;
    const Clock::time_point now = Clock::now();
    if (!force && now - last_ < std::chrono::milliseconds(100)) return;  // at most 10 redraws a second
    last_ = now;
    const double wall = std::chrono::duration<double>(now - start_).count();
    const double f = std::min(1.0, std::max(0.0, s.t / duration_));
    constexpr int kWidth = 30;
    const int full = static_cast<int>(f * kWidth);
    std::string bar(static_cast<std::size_t>(full), '#');
    bar.append(static_cast<std::size_t>(kWidth - full), '.');
    char ratio[32] = "";
    if (wall > 0.0 && s.t > 0.0) std::snprintf(ratio, sizeof ratio, "x %.3g real time", s.t / wall);
    std::fprintf(stderr, "\r[%s] t = %.4g / %.4g s, %ld steps, %.1f s, %s   ", bar.c_str(), s.t, duration_, steps_, wall,
                 ratio);
    std::fflush(stderr);
    drawn_ = true;
  }
  void finish() {
    if (drawn_) std::fprintf(stderr, "\n");
  }

 private:
  using Clock = std::chrono::steady_clock;
  double duration_;
  Clock::time_point start_, last_;
  long steps_ = 0;
  bool drawn_ = false;
};

}  // namespace

std::string simulate_usage() {
  return "       tdcr simulate SCENE.json --duration T [--dt H] [--model NAME] [-o OUT.csv|OUT.npz] [--quiet]\n";
}

int run_simulate(const std::vector<std::string>& args) {
  std::vector<std::string> files;
  SimulationOptions options;
  bool have_duration = false;
  std::optional<std::string> model_name, output;
  bool quiet = false;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const auto [name, inline_value] = tdcr_cli::split_option(args[i]);
    auto value = [&, name = name, inline_value = inline_value] {
      return tdcr_cli::option_value(args, i, name, inline_value);
    };
    if (name == "--duration") options.duration = number(name, value()), have_duration = true;
    else if (name == "--dt") options.dt = number(name, value());
    else if (name == "--model") model_name = value();
    else if (name == "-o" || name == "--output") output = value();
    else if (name == "--quiet" || name == "-q") quiet = true;
    else if (name.size() > 1 && name[0] == '-') throw InputError("simulate", args[i], "unknown option (see tdcr --help)");
    else files.push_back(args[i]);
  }
  if (files.size() != 1) throw InputError("simulate", files.empty() ? "" : files[1], "give one scene file (see tdcr --help)");
  if (!have_duration) throw InputError("--duration", "", "missing: how long to simulate (s)");
  try {
    options.validate();
  } catch (const InputError& e) {
    throw InputError("--" + e.field(), e.value(), "must be a finite time > 0 (s), at most 1e7 steps");
  }
  const bool npz = output && output->size() >= 4 && output->compare(output->size() - 4, 4, ".npz") == 0;
  Scene scene = load_scene(files[0]);
  if (model_name) scene.model = *model_name;
  validate_scene(scene);
  if (scene.model == "auto") throw InputError("model", "auto", "simulate needs a named model (ccsub, prb, vc or vcref)");
  if (!scene.dynamics) throw InputError("dynamics", "", "missing: a scene to simulate gives a \"dynamics\" object");
  Timeline timeline = scene.timeline;
  if (timeline.entries.empty()) timeline.entries.push_back(TimelineEntry{0.0, scene.input()});  // constant input
  const auto model = make_model(parse_model_kind(scene.model), scene);
  // Open the output first: a run is not wasted on an output that cannot be written.
  std::ofstream file;
  if (output) {
    file.open(*output, npz ? std::ios::binary : std::ios::out);
    if (!file) throw InputError("-o", *output, "cannot be written");
  }
  const std::size_t tendons = static_cast<std::size_t>(model->robot().tendon_count());
  std::optional<Progress> progress;
  if (!quiet && isatty(fileno(stderr))) progress.emplace(options.duration);
  std::vector<std::vector<Vec3>> disks;  // the .npz's disk centres
  SimulationObserver observer;
  if (progress || npz)
    observer = [&](const SimulationStep& s, const Solution& shape) {
      if (npz) {
        disks.emplace_back();
        for (const Frame& f : shape.disk_frames) disks.back().push_back(f.p);
      }
      if (progress) progress->update(s, s.t >= options.duration);
    };
  const SimulationResult r = simulate(*model, *scene.dynamics, timeline, options, scene.solver, observer);
  if (progress) progress->finish();
  std::ostream& out = output ? static_cast<std::ostream&>(file) : std::cout;
  if (npz)
    write_npz(out, r, tendons, disks);
  else
    write_csv(out, r, tendons);
  if (output) {
    file.close();
    if (!file) throw InputError("-o", *output, "could not be written completely");
  }
  if (!r.completed) {
    std::fprintf(stderr, "simulation stopped: %s\n", r.message.c_str());
    return 1;
  }
  return 0;
}

}  // namespace tdcr::cli
