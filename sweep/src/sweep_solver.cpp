// One thread's solver of sweep samples: models, workspaces, warm starts, CSV rows.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>

#include "tdcr/core/error.hpp"
#include "tdcr/core/lie.hpp"
#include "tdcr/sweep/sweep_run.hpp"

namespace tdcr {
namespace {

void append_number(std::string& out, double v, const char* format = "%.17g") {
  char buf[40];
  std::snprintf(buf, sizeof buf, format, v);
  out += buf;
}

/// A CSV field: quoted when it holds a comma or quote; line breaks become spaces (one row per line).
void append_text(std::string& out, const std::string& text) {
  std::string t = text;
  for (char& c : t)
    if (c == '\n' || c == '\r') c = ' ';
  if (t.find_first_of(",\"") == std::string::npos) {
    out += t;
    return;
  }
  out += '"';
  for (char c : t) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  out += '"';
}

}  // namespace

struct SweepSolver::Impl {
  struct Slot {
    std::unique_ptr<StaticModel> model;
    std::unique_ptr<ModelWorkspace> workspace;
    Solution previous;
    bool warm = false;
  };
  const SweepSpec& spec;
  std::vector<Slot> slots;
  std::vector<double> values, scene_key;
  std::vector<std::uint64_t> order;     // the block's solve order
  std::vector<std::string> sample_rows;  // rows of a block solved out of sample order
  Scene scene;
  std::string scene_error;  // why the current scene cannot be built (bad combination of axes)
  bool built = false;

  explicit Impl(const SweepSpec& s) : spec(s), slots(s.models.size()) {}

  /// Rebuilds scene and models if a scene axis differs from the previous sample's.
  void update_scene() {
    std::vector<double> key;
    for (std::size_t a = 0; a < spec.axes.size(); ++a)
      if (spec.axes[a].rebuilds_model()) key.push_back(values[a]);
    if (built && key == scene_key) return;
    scene_key = key;
    built = true;
    scene_error.clear();
    try {
      scene = spec.scene_with(values);
      for (std::size_t m = 0; m < slots.size(); ++m) {
        slots[m].model = make_model(spec.models[m], scene);
        slots[m].workspace = slots[m].model->make_workspace();
        slots[m].warm = false;
      }
    } catch (const std::exception& e) {
      scene_error = e.what();
      for (Slot& s : slots) s.model.reset(), s.warm = false;
    }
  }

  void row(std::string& out, std::uint64_t i, std::size_t m, const char* status, const std::string& reason,
           const Solution* s) {
    out += std::to_string(i);
    for (double v : values) out += ',', append_number(out, v);
    out += ',' + to_string(spec.models[m]) + ',' + status + ',';
    append_text(out, reason);
    if (s && !s->disk_frames.empty()) {
      const Vec3 p = s->tip().p, w = lie::log_so3(s->tip().R);
      for (int k = 0; k < 3; ++k) out += ',', append_number(out, p[k]);
      for (int k = 0; k < 3; ++k) out += ',', append_number(out, w[k]);
    } else {
      out += ",,,,,,";
    }
    out += ',' + std::to_string(s ? s->summary.iterations : 0) + ',';
    append_number(out, s ? s->summary.solve_time_s : 0.0, "%.6g");
    out += '\n';
  }
};

SweepSolver::SweepSolver(const SweepSpec& spec) : impl_(std::make_unique<Impl>(spec)) {}
SweepSolver::~SweepSolver() = default;

void SweepSolver::solve_range(std::uint64_t first, std::uint64_t last, std::uint64_t emit_from, std::string& rows) {
  Impl& d = *impl_;
  for (Impl::Slot& s : d.slots) s.warm = false;
  sweep_solve_order(d.spec, first, last, d.order);
  // Solved out of sample order: each sample's rows are kept until the block is done.
  const bool sorted = std::is_sorted(d.order.begin(), d.order.end());
  d.sample_rows.assign(sorted ? 0 : d.order.size(), std::string());
  for (std::uint64_t i : d.order) {
    d.spec.sample_values(i, d.values);
    d.update_scene();
    const bool emit = i >= emit_from;
    std::string& out = sorted ? rows : d.sample_rows[i - first];
    for (std::size_t m = 0; m < d.slots.size(); ++m) {
      Impl::Slot& slot = d.slots[m];
      if (!slot.model) {
        if (emit) d.row(out, i, m, "input_error", d.scene_error, nullptr);
        continue;
      }
      try {
        const ModelInput input = d.spec.input_with(d.scene, d.values);
        Solution s = solve(*slot.model, *slot.workspace, input, d.scene.solver, slot.warm ? &slot.previous : nullptr);
        if (emit) d.row(out, i, m, to_string(s.summary.termination).c_str(), s.summary.message, &s);
        slot.warm = s.converged();
        if (slot.warm) slot.previous = std::move(s);
      } catch (const InputError& e) {
        slot.warm = false;
        if (emit) d.row(out, i, m, "input_error", e.what(), nullptr);
      } catch (const std::exception& e) {
        slot.warm = false;
        if (emit) d.row(out, i, m, "error", e.what(), nullptr);
      }
    }
  }
  for (const std::string& r : d.sample_rows) rows += r;
}

}  // namespace tdcr
