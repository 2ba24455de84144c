// The order in which a block's samples are solved: neighbours next to each other, so that each
// warm start comes from a nearby sample (docs/sweeps.md, "Solve order").
#include <algorithm>
#include <cmath>

#include "tdcr/sweep/sweep_run.hpp"

namespace tdcr {
namespace {

/// Hilbert index of a point with `dims` coordinates of `bits` bits each (dims * bits <= 64):
/// J. Skilling, "Programming the Hilbert curve", AIP Conf. Proc. 707 (2004): the coordinates are
/// transformed in place to the curve's transposed index, whose bits are then interleaved.
std::uint64_t hilbert_index(std::uint32_t* x, int dims, int bits) {
  const std::uint32_t m = 1u << (bits - 1);
  for (std::uint32_t q = m; q > 1; q >>= 1) {  // inverse undo of the excess work
    const std::uint32_t p = q - 1;
    for (int i = 0; i < dims; ++i) {
      if (x[i] & q) {
        x[0] ^= p;
      } else {
        const std::uint32_t t = (x[0] ^ x[i]) & p;
        x[0] ^= t;
        x[i] ^= t;
      }
    }
  }
  for (int i = 1; i < dims; ++i) x[i] ^= x[i - 1];  // Gray encode
  std::uint32_t t = 0;
  for (std::uint32_t q = m; q > 1; q >>= 1)
    if (x[dims - 1] & q) t ^= q - 1;
  for (int i = 0; i < dims; ++i) x[i] ^= t;
  std::uint64_t h = 0;
  for (int b = bits - 1; b >= 0; --b)
    for (int i = 0; i < dims; ++i) h = (h << 1) | ((x[i] >> b) & 1u);
  return h;
}

/// The range [lo, hi] of an axis's values.
void axis_range(const SweepAxis& a, double& lo, double& hi) {
  if (a.values.empty()) {
    lo = std::min(a.from, a.to), hi = std::max(a.from, a.to);
  } else {
    lo = *std::min_element(a.values.begin(), a.values.end());
    hi = *std::max_element(a.values.begin(), a.values.end());
  }
}

}  // namespace

std::uint64_t sweep_block_size(const SweepSpec& spec) {
  return spec.random && spec.warm_order ? kSweepRandomBlock : kSweepBlock;
}

void sweep_solve_order(const SweepSpec& spec, std::uint64_t first, std::uint64_t last, std::vector<std::uint64_t>& order) {
  order.resize(last - first);
  for (std::uint64_t i = first; i < last; ++i) order[i - first] = i;
  // A grid is already in neighbour order (the last axis fastest): kept as it is.
  if (!spec.random || !spec.warm_order) return;
  std::vector<std::size_t> scene_axes, input_axes;
  for (std::size_t a = 0; a < spec.axes.size(); ++a) (spec.axes[a].rebuilds_model() ? scene_axes : input_axes).push_back(a);
  const int dims = static_cast<int>(std::min<std::size_t>(input_axes.size(), 32));
  const int bits = dims > 0 ? std::min(20, 64 / dims) : 0;
  std::vector<double> lo(spec.axes.size()), hi(spec.axes.size());
  for (std::size_t a = 0; a < spec.axes.size(); ++a) axis_range(spec.axes[a], lo[a], hi[a]);

  // Sort key: the scene axes' values first (a model serves a run of equal scenes), then the
  // Hilbert index of the input axes normalised to [0, 1], then the sample number.
  struct Key {
    std::vector<double> scene;
    std::uint64_t hilbert = 0, sample = 0;
    bool operator<(const Key& o) const {
      if (scene != o.scene) return scene < o.scene;
      return hilbert != o.hilbert ? hilbert < o.hilbert : sample < o.sample;
    }
  };
  std::vector<Key> keys(order.size());
  std::vector<double> values;
  std::uint32_t cell[32];
  const double cells = std::ldexp(1.0, bits) - 1.0;
  for (std::size_t k = 0; k < keys.size(); ++k) {
    spec.sample_values(order[k], values);
    for (std::size_t a : scene_axes) keys[k].scene.push_back(values[a]);
    for (int d = 0; d < dims; ++d) {
      const std::size_t a = input_axes[static_cast<std::size_t>(d)];
      const double u = hi[a] > lo[a] ? (values[a] - lo[a]) / (hi[a] - lo[a]) : 0.0;
      cell[d] = static_cast<std::uint32_t>(std::lround(std::clamp(u, 0.0, 1.0) * cells));
    }
    keys[k].hilbert = dims > 0 ? hilbert_index(cell, dims, bits) : 0;
    keys[k].sample = order[k];
  }
  std::sort(keys.begin(), keys.end());
  for (std::size_t k = 0; k < keys.size(); ++k) order[k] = keys[k].sample;
}

}  // namespace tdcr
