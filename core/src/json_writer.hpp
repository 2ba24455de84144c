// JSON output (private to tdcr_core): ordered objects (keys in contract order) printed with small
// arrays and objects on one line; non-finite numbers as null, so the text is always valid JSON.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tdcr/core/types.hpp"

namespace tdcr::detail {

using ojson = nlohmann::ordered_json;

/// Two-space indented text, small arrays and objects inline, ending with a newline.
std::string pretty(const ojson& j);

/// A number, or null if not finite.
ojson number(double v);
/// [x, y, z], non-finite entries as null.
ojson vec_json(const Vec3& v);
/// An array of numbers, non-finite entries as null.
ojson numbers_json(const std::vector<double>& v);

}  // namespace tdcr::detail
