// Strict JSON reading with path-tracked errors (json_reader.hpp).
#include "json_reader.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <set>

namespace tdcr::detail {

std::string key_path(const std::string& parent, const std::string& key) {
  return parent.empty() ? key : parent + "." + key;
}

std::string index_path(const std::string& parent, std::size_t i) {
  return parent + "[" + std::to_string(i) + "]";
}

std::string text_of(const json& j) {
  if (j.is_number_float()) {
    const double v = j.get<double>();
    if (!std::isfinite(v)) return format_value(v);
  }
  constexpr std::size_t kMaxLength = 120;
  std::string text = j.dump(-1, ' ', false, json::error_handler_t::replace);
  if (text.size() > kMaxLength) text = text.substr(0, kMaxLength - 3) + "...";
  return text;
}

namespace {

std::string type_name(const json& j) {
  if (j.is_number_integer()) return "an integer";
  if (j.is_number_float()) return "a number";
  if (j.is_boolean()) return "a boolean";
  if (j.is_string()) return "a string";
  if (j.is_array()) return "an array";
  if (j.is_object()) return "an object";
  return "null";
}

std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t subst = prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1);
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, subst});
    }
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

/// Follows the parser through the document so that a duplicate key or an overflowing number can
/// be reported at its JSON path (nlohmann itself keeps the last duplicate silently).
class PathTracker {
 public:
  bool operator()(int /*depth*/, json::parse_event_t event, json& parsed) {
    switch (event) {
      case json::parse_event_t::object_start:
      case json::parse_event_t::array_start:
        // A scene is at most 6 levels deep; a bound keeps pathological files from exhausting
        // the stack in recursive code (dump, destruction).
        if (frames_.size() >= kMaxDepth)
          throw InputError(pending_path(), "",
                           "nested too deeply (more than " + std::to_string(kMaxDepth) + " levels)");
        begin_value();
        frames_.push_back(Frame{event == json::parse_event_t::object_start, {}, {}, -1});
        break;
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        frames_.pop_back();
        break;
      case json::parse_event_t::key: {
        Frame& f = frames_.back();
        f.key = parsed.get<std::string>();
        if (!f.keys.insert(f.key).second)
          throw InputError(path(frames_.size()), "\"" + f.key + "\"", "duplicate key");
        break;
      }
      case json::parse_event_t::value:
        begin_value();
        break;
    }
    return true;
  }

  /// Path of the value the parser is reading now.
  std::string pending_path() const {
    if (frames_.empty()) return "";
    std::string p = path(frames_.size() - 1);
    const Frame& f = frames_.back();
    return f.is_object ? key_path(p, f.key) : index_path(p, static_cast<std::size_t>(f.index + 1));
  }

 private:
  static constexpr std::size_t kMaxDepth = 64;

  struct Frame {
    bool is_object;
    std::set<std::string> keys;
    std::string key;  // current key (objects)
    int index;        // index of the current element (arrays)
  };

  void begin_value() {
    if (!frames_.empty() && !frames_.back().is_object) ++frames_.back().index;
  }

  /// Path made of the first n frames.
  std::string path(std::size_t n) const {
    std::string p;
    for (std::size_t i = 0; i < n; ++i)
      p = frames_[i].is_object ? key_path(p, frames_[i].key)
                               : index_path(p, static_cast<std::size_t>(frames_[i].index));
    return p;
  }

  std::vector<Frame> frames_;
};

/// nlohmann's message without its "[json.exception.xxx.nnn] " prefix.
std::string plain_message(const std::exception& e) {
  std::string m = e.what();
  const auto close = m.find("] ");
  return m.rfind("[json.exception", 0) == 0 && close != std::string::npos ? m.substr(close + 2) : m;
}

}  // namespace

void type_error(const std::string& path, const json& j, const std::string& expected) {
  throw InputError(path, text_of(j), "must be " + expected + ", not " + type_name(j));
}

json parse_json_text(const std::string& text, const std::string& source) {
  PathTracker tracker;
  try {
    return json::parse(text, std::ref(tracker));
  } catch (const json::parse_error& e) {
    throw InputError(source, "",
                     "malformed JSON at byte " + std::to_string(e.byte) + ": " + plain_message(e));
  } catch (const json::out_of_range& e) {
    // A number too large for a double (e.g. 1e999, or an integer of 400 digits), named by its
    // path and its text (shortened: the text can be as long as the file).
    constexpr std::size_t kMaxValueLength = 40;
    std::string value;
    const std::string m = e.what();
    const auto a = m.find('\''), b = m.rfind('\'');
    if (a != std::string::npos && b > a) value = m.substr(a + 1, b - a - 1);
    if (value.size() > kMaxValueLength) value = value.substr(0, kMaxValueLength - 3) + "...";
    const std::string path = tracker.pending_path();
    throw InputError(path.empty() ? source : path, value,
                     "must be a finite number (number overflow: it does not fit a double)");
  }
}

double read_number(const json& j, const std::string& path) {
  // nlohmann keeps booleans apart from numbers, so true/false are rejected here too.
  if (!j.is_number()) type_error(path, j, "a number");
  const double v = j.get<double>();
  if (!std::isfinite(v)) throw InputError(path, text_of(j), "must be a finite number");
  return v;
}

int read_int(const json& j, const std::string& path) {
  if (!j.is_number_integer()) type_error(path, j, "an integer");
  if (j.is_number_unsigned()) {
    if (j.get<std::uint64_t>() > static_cast<std::uint64_t>(std::numeric_limits<int>::max()))
      throw InputError(path, text_of(j), "is out of range");
  } else {
    const auto v = j.get<std::int64_t>();
    if (v < std::numeric_limits<int>::min() || v > std::numeric_limits<int>::max())
      throw InputError(path, text_of(j), "is out of range");
  }
  return j.get<int>();
}

bool read_bool(const json& j, const std::string& path) {
  if (!j.is_boolean()) type_error(path, j, "true or false");
  return j.get<bool>();
}

std::string read_string(const json& j, const std::string& path) {
  if (!j.is_string()) type_error(path, j, "a string");
  return j.get<std::string>();
}

const json& require_array(const json& j, const std::string& path) {
  if (!j.is_array()) type_error(path, j, "an array");
  return j;
}

std::vector<double> read_numbers(const json& j, const std::string& path) {
  require_array(j, path);
  std::vector<double> v;
  v.reserve(j.size());
  for (std::size_t i = 0; i < j.size(); ++i) v.push_back(read_number(j[i], index_path(path, i)));
  return v;
}

std::vector<double> read_numbers(const json& j, const std::string& path, std::size_t n) {
  require_array(j, path);
  if (j.size() != n)
    throw InputError(path, text_of(j), "must list exactly " + std::to_string(n) + " numbers");
  return read_numbers(j, path);
}

Vec3 read_vec3(const json& j, const std::string& path) {
  const std::vector<double> v = read_numbers(j, path, 3);
  return Vec3(v[0], v[1], v[2]);
}

std::string quoted_names(const std::vector<const char*>& names) {
  std::string s;
  for (const char* n : names) s += (s.empty() ? "\"" : ", \"") + std::string(n) + "\"";
  return s;
}

JsonObject::JsonObject(const json& j, std::string path, const std::vector<const char*>& known)
    : j_(j), path_(std::move(path)) {
  if (!j.is_object()) type_error(path_.empty() ? "scene" : path_, j, "an object");
  for (const auto& item : j.items()) {
    const std::string& key = item.key();
    const char* best = nullptr;
    std::size_t best_d = std::numeric_limits<std::size_t>::max();
    bool found = false;
    for (const char* k : known) {
      if (key == k) {
        found = true;
        break;
      }
      const std::size_t d = edit_distance(key, k);
      if (d < best_d) best_d = d, best = k;
    }
    if (found) continue;
    std::string reason = "unknown key";
    if (best && best_d <= std::max<std::size_t>(2, key.size() / 3))
      reason += "; did you mean \"" + std::string(best) + "\"?";
    std::string list;
    for (const char* k : known) list += (list.empty() ? "" : ", ") + std::string(k);
    throw InputError(this->path(key), text_of(item.value()), reason + " (known keys here: " + list + ")");
  }
}

const json& JsonObject::at(const char* key) const {
  if (!has(key)) throw InputError(path(key), "", "is required");
  return j_.at(key);
}

}  // namespace tdcr::detail
