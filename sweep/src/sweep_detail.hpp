// Private helpers of the sweep library.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "tdcr/sweep/sweep_file.hpp"

namespace tdcr::sweep_detail {

/// "Leave this axis at the base scene's value" (sample values are always finite).
inline void base_values(const SweepSpec& spec, std::vector<double>& values) {
  values.assign(spec.axes.size(), std::numeric_limits<double>::quiet_NaN());
}

/// The index of a field path (`[12]`: "12"), saturating at SIZE_MAX so that a number of any
/// length is an index that does not exist rather than std::stoul's std::out_of_range.
inline std::size_t index_value(const std::string& digits) {
  std::size_t k = 0;
  for (const char c : digits) {
    const std::size_t d = static_cast<std::size_t>(c - '0');
    if (k > (std::numeric_limits<std::size_t>::max() - d) / 10) return std::numeric_limits<std::size_t>::max();
    k = 10 * k + d;
  }
  return k;
}

/// SplitMix64: a well-mixed 64-bit hash, the same on every platform.
inline std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

}  // namespace tdcr::sweep_detail
