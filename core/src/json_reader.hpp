// Strict reading of JSON documents (private to tdcr's libraries, not installed: tdcr_core reads
// scene files with it, tdcr_sweep sweep files): every error is a tdcr::InputError that names the
// JSON path of the offending value (`robot.segments[0].disks`) and the value itself.
//
// parse_json_text rejects malformed text, duplicate keys, number overflow and absurd nesting;
// the typed readers check one value each; JsonObject checks an object's keys against its known
// keys and suggests the closest one for a misspelt key.
#pragma once

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "tdcr/core/error.hpp"
#include "tdcr/core/types.hpp"

namespace tdcr::detail {

using json = nlohmann::json;

/// `parent.key` (just `key` at the root).
std::string key_path(const std::string& parent, const std::string& key);
/// `parent[i]`.
std::string index_path(const std::string& parent, std::size_t i);

/// Compact JSON text of a value for messages (non-finite numbers as "nan"/"inf"), shortened if long.
std::string text_of(const json& j);

/// Throws InputError(path, value, "must be <expected>, not <type of j>").
[[noreturn]] void type_error(const std::string& path, const json& j, const std::string& expected);

/// Parses JSON text; syntax errors name `source` and the byte position, duplicate keys and
/// overflowing numbers name their JSON path.
json parse_json_text(const std::string& text, const std::string& source);

// Typed readers: each takes the value and its JSON path.
double read_number(const json& j, const std::string& path);  ///< A finite number.
int read_int(const json& j, const std::string& path);        ///< An integer that fits an int.
bool read_bool(const json& j, const std::string& path);      ///< true or false.
std::string read_string(const json& j, const std::string& path);
const json& require_array(const json& j, const std::string& path);
std::vector<double> read_numbers(const json& j, const std::string& path);  ///< Any length.
std::vector<double> read_numbers(const json& j, const std::string& path, std::size_t n);  ///< Exactly n.
Vec3 read_vec3(const json& j, const std::string& path);

/// The names of an enumeration in JSON files, paired with its values.
template <class E>
using Names = std::vector<std::pair<const char*, E>>;

/// `"a", "b", "c"`: the names for messages.
std::string quoted_names(const std::vector<const char*>& names);

/// A string naming one of `names`.
template <class E>
E read_choice(const json& j, const std::string& path, const Names<E>& names) {
  std::vector<const char*> list;
  for (const auto& n : names) list.push_back(n.first);
  if (!j.is_string()) type_error(path, j, "one of " + quoted_names(list));
  const std::string s = j.get<std::string>();
  for (const auto& n : names)
    if (s == n.first) return n.second;
  throw InputError(path, text_of(j), "must be one of " + quoted_names(list));
}

/// The name of `value` in `names`.
template <class E>
const char* name_of(E value, const Names<E>& names) {
  for (const auto& n : names)
    if (n.second == value) return n.first;
  return "?";
}

/// One JSON object at a path, checked against its known keys.
class JsonObject {
 public:
  /// Throws unless `j` is an object whose keys all appear in `known` (an unknown key is reported
  /// with the closest known key and the list of known keys).
  JsonObject(const json& j, std::string path, const std::vector<const char*>& known);

  bool has(const char* key) const { return j_.contains(key); }
  /// The value of a key; InputError "is required" if absent.
  const json& at(const char* key) const;
  /// The path of a key of this object.
  std::string path(const std::string& key) const { return key_path(path_, key); }
  const std::string& path() const { return path_; }
  const json& value() const { return j_; }

 private:
  const json& j_;
  std::string path_;
};

}  // namespace tdcr::detail
