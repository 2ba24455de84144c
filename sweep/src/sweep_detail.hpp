// Private helpers of the sweep library.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "tdcr/sweep/sweep_file.hpp"

namespace tdcr::sweep_detail {

/// "Leave this axis at the base scene's value" (sample values are always finite).
inline void base_values(const SweepSpec& spec, std::vector<double>& values) {
  values.assign(spec.axes.size(), std::numeric_limits<double>::quiet_NaN());
}

/// SplitMix64: a well-mixed 64-bit hash, the same on every platform.
inline std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

}  // namespace tdcr::sweep_detail
