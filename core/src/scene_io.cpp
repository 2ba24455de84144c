// Scene files (JSON) in and out, and the scene-file key reference: all three walk the one field
// table of scene_schema.cpp.
//
// Parsing is strict: every object has a table of known keys (an unknown key is an error that
// names its path and suggests the closest known key), every value is type checked at its JSON
// path, numbers must be finite, and duplicate keys are rejected (json_reader.cpp). Semantic
// checks (positive lengths, tendon off the axis, tensions >= 0, list lengths) are
// Scene::validate()'s, which is called on the parsed scene; it reports the same JSON paths.
#include "tdcr/core/scene_io.hpp"

#include <filesystem>
#include <fstream>
#include <sstream>

#include "scene_schema.hpp"

namespace tdcr {

Scene parse_scene(const std::string& json_text, const std::string& source) {
  const detail::json j = detail::parse_json_text(json_text, source);
  if (!j.is_object()) throw InputError(source, detail::text_of(j), "a scene must be a JSON object");
  Scene scene = detail::scene_schema().read(j, "");
  scene.validate();
  return scene;
}

Scene load_scene(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw InputError(path, "", "cannot be opened as a scene file: it is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "", "cannot be opened (missing or unreadable scene file)");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw InputError(path, "", "cannot be read");
  return parse_scene(text.str(), path);
}

std::string scene_to_json(const Scene& scene) {
  // Non-finite values (only possible in an unvalidated Scene) are written as null, which
  // parse_scene rejects with the field's path: never invalid JSON.
  return detail::pretty(detail::scene_schema().write(scene));
}

// --- The reference ---------------------------------------------------------------------------

namespace detail {

std::string reference_text(const ojson& j) {
  if (j.is_number_float()) {
    std::string s = format_value(j.get<double>());  // shortest round trip: 2.11e+11, 1e-08
    const auto e = s.find('e');
    if (e != std::string::npos) {
      std::string exponent = s.substr(e + 1);
      const bool negative = exponent[0] == '-';
      if (exponent[0] == '+' || negative) exponent.erase(0, 1);
      exponent.erase(0, std::min(exponent.find_first_not_of('0'), exponent.size() - 1));
      s = s.substr(0, e + 1) + (negative ? "-" : "") + exponent;
    }
    return s;
  }
  if (j.is_array()) {
    std::string s = "[";
    for (std::size_t i = 0; i < j.size(); ++i) s += (i ? ", " : "") + reference_text(j[i]);
    return s + "]";
  }
  return j.dump();
}

namespace {

/// Adds the rows of `schema`'s keys under `prefix` to `out`, and those of nested objects except
/// the ones with their own table, which are added to `tables` as new tables.
void add_rows(const SchemaBase& schema, const std::string& prefix, std::string& out,
              std::vector<SceneKeyTable>& tables);

void add_table(const SchemaBase& schema, const std::string& object, std::vector<SceneKeyTable>& tables) {
  const std::size_t at = tables.size();
  tables.push_back({object, "| key | type | unit | default | constraints | honoured by |\n"
                            "| --- | --- | --- | --- | --- | --- |\n"});
  std::string rows;
  add_rows(schema, object, rows, tables);
  tables[at].markdown += rows;
}

void add_rows(const SchemaBase& schema, const std::string& prefix, std::string& out,
              std::vector<SceneKeyTable>& tables) {
  for (std::size_t i = 0; i < schema.size(); ++i) {
    const FieldInfo& f = schema.info(i);
    const std::string path = key_path(prefix, f.key);
    out += "| `" + path + "` | " + f.type + " | " + f.doc.unit + " | " + schema.default_text(i) + " | " +
           f.doc.constraints + " | " + f.doc.honoured_by + " |\n";
    if (!f.child) continue;
    const std::string child = f.index ? path + "[" + f.index + "]" : path;
    if (f.own_table)
      add_table(*f.child, child, tables);
    else
      add_rows(*f.child, child, out, tables);
  }
}

}  // namespace
}  // namespace detail

std::vector<SceneKeyTable> scene_key_reference() {
  std::vector<SceneKeyTable> tables;
  detail::add_table(detail::scene_schema(), "", tables);
  return tables;
}

}  // namespace tdcr
