// The values of each sweep sample and the scene and input they make.
#include <cmath>

#include <nlohmann/json.hpp>

#include "sweep_detail.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/core/scene_io.hpp"

namespace tdcr {
namespace {

using json = nlohmann::json;

/// Sets the number at `path` (`a.b[2].c`) in `doc`. Objects on the way that the base scene
/// leaves out are created (the scene parser then names any unknown key); a missing load vector
/// starts at zero; an array index must exist.
void set_path(json& doc, const std::string& path, double value) {
  json* node = &doc;
  std::size_t pos = 0;
  while (pos < path.size()) {
    if (path[pos] == '.') ++pos;
    if (path[pos] == '[') {
      const std::size_t close = path.find(']', pos);
      const std::string digits = path.substr(pos + 1, close - pos - 1);  // the field regex allows only digits
      const std::size_t k = sweep_detail::index_value(digits);
      if (!node->is_array() || k >= node->size())
        throw InputError(path, "", "does not exist in the base scene (index " + digits + ")");
      node = &(*node)[k];
      pos = close + 1;
      continue;
    }
    std::size_t end = path.find_first_of(".[", pos);
    if (end == std::string::npos) end = path.size();
    const std::string key = path.substr(pos, end - pos);
    if (!node->is_object()) throw InputError(path, "", "does not exist in the base scene (" + key + " is inside a value)");
    if (!node->contains(key)) {
      const bool vector3 = key == "tip_force" || key == "tip_moment" || key == "gravity";
      (*node)[key] = vector3 ? json::array({0.0, 0.0, 0.0}) : end < path.size() && path[end] == '[' ? json::array() : json::object();
    }
    node = &(*node)[key];
    pos = end;
  }
  // Whole numbers are written as integers so that integer fields (disks, rk4_steps) accept them.
  if (std::floor(value) == value && std::abs(value) < 9.0e15)
    *node = static_cast<std::int64_t>(value);
  else
    *node = value;
}

}  // namespace

bool SweepSpec::has_scene_axes() const {
  for (const SweepAxis& a : axes)
    if (a.rebuilds_model()) return true;
  return false;
}

std::uint64_t SweepSpec::sample_count() const {
  if (random) return random_samples;
  std::uint64_t n = 1;
  for (const SweepAxis& a : axes) n *= a.values.size();
  return n;
}

void SweepSpec::sample_values(std::uint64_t i, std::vector<double>& out) const {
  out.resize(axes.size());
  if (!random) {
    for (std::size_t a = axes.size(); a-- > 0;) {
      const std::uint64_t n = axes[a].values.size();
      out[a] = axes[a].values[i % n];
      i /= n;
    }
    return;
  }
  for (std::size_t a = 0; a < axes.size(); ++a) {
    const std::uint64_t h = sweep_detail::splitmix64(seed ^ sweep_detail::splitmix64(i * axes.size() + a));
    const double u = double(h >> 11) * 0x1.0p-53;  // uniform in [0, 1)
    const SweepAxis& ax = axes[a];
    out[a] = ax.values.empty() ? ax.from + u * (ax.to - ax.from)
                               : ax.values[std::min<std::size_t>(std::size_t(u * double(ax.values.size())), ax.values.size() - 1)];
  }
}

Scene SweepSpec::scene_with(const std::vector<double>& values) const {
  bool any = false;
  for (std::size_t a = 0; a < axes.size(); ++a) any = any || (axes[a].rebuilds_model() && std::isfinite(values[a]));
  if (!any) return base;
  json doc = json::parse(base_scene_json);
  for (std::size_t a = 0; a < axes.size(); ++a)
    if (axes[a].rebuilds_model() && std::isfinite(values[a])) set_path(doc, axes[a].field, values[a]);
  return parse_scene(doc.dump(), source + ": scene");
}

ModelInput SweepSpec::input_with(const Scene& scene, const std::vector<double>& values) const {
  ModelInput input = scene.input();
  for (std::size_t a = 0; a < axes.size(); ++a) {
    const SweepAxis& ax = axes[a];
    if (!std::isfinite(values[a])) continue;
    switch (ax.target) {
      case SweepAxis::Target::Tension:
      case SweepAxis::Target::Displacement: input.actuation.values[ax.index] = values[a]; break;
      case SweepAxis::Target::TipForce: input.loads.tip_force[ax.index] = values[a]; break;
      case SweepAxis::Target::TipMoment: input.loads.tip_moment[ax.index] = values[a]; break;
      case SweepAxis::Target::Gravity: input.loads.gravity[ax.index] = values[a]; break;
      case SweepAxis::Target::Scene: break;
    }
  }
  return input;
}

}  // namespace tdcr
