// JSON output (json_writer.hpp).
#include "json_writer.hpp"

#include <algorithm>
#include <cmath>

namespace tdcr::detail {

namespace {

bool is_small(const ojson& j) {
  if (j.is_primitive()) return true;
  if (j.is_array())
    return std::all_of(j.begin(), j.end(),
                       [](const ojson& e) { return e.is_primitive() || (e.is_array() && is_small(e)); });
  return j.size() <= 4 && std::all_of(j.begin(), j.end(), [](const ojson& e) { return e.is_primitive(); });
}

void write_inline(const ojson& j, std::string& out) {
  if (j.is_primitive()) {
    out += j.dump();
    return;
  }
  const bool object = j.is_object();
  out += object ? "{" : "[";
  bool first = true;
  for (auto it = j.begin(); it != j.end(); ++it, first = false) {
    if (!first) out += ", ";
    if (object) out += ojson(it.key()).dump() + ": ";
    write_inline(*it, out);
  }
  out += object ? "}" : "]";
}

void write_pretty(const ojson& j, int level, std::string& out) {
  if (is_small(j) || j.empty()) {
    write_inline(j, out);
    return;
  }
  const bool object = j.is_object();
  const std::string pad(2 * static_cast<std::size_t>(level + 1), ' ');
  out += object ? "{\n" : "[\n";
  bool first = true;
  for (auto it = j.begin(); it != j.end(); ++it, first = false) {
    if (!first) out += ",\n";
    out += pad;
    if (object) out += ojson(it.key()).dump() + ": ";
    write_pretty(*it, level + 1, out);
  }
  out += "\n" + std::string(2 * static_cast<std::size_t>(level), ' ') + (object ? "}" : "]");
}

}  // namespace

std::string pretty(const ojson& j) {
  std::string out;
  write_pretty(j, 0, out);
  return out + "\n";
}

ojson number(double v) { return std::isfinite(v) ? ojson(v) : ojson(nullptr); }

ojson vec_json(const Vec3& v) { return ojson::array({number(v[0]), number(v[1]), number(v[2])}); }

ojson numbers_json(const std::vector<double>& v) {
  ojson a = ojson::array();
  for (double x : v) a.push_back(number(x));
  return a;
}

}  // namespace tdcr::detail
