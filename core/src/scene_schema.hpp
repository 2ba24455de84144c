// The scene-file field table (private to tdcr_core): one Field per key, holding how it is read,
// how it is written and what the reference (docs/scene-file.md) says about it. parse_scene,
// scene_to_json and scene_key_reference all walk the same table (scene_schema.cpp, its `solver`
// object in scene_solver_schema.cpp), so a key is spelled once.
#pragma once

#include <algorithm>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "json_reader.hpp"
#include "json_writer.hpp"
#include "tdcr/core/scene.hpp"

namespace tdcr::detail {

/// What the reference says about a key (one row of a table in docs/scene-file.md).
struct KeyDoc {
  const char* unit = "";
  /// Shown as the default; nullptr: the default-constructed struct's value as scene_to_json
  /// writes it ("required" for a required key).
  const char* default_text = nullptr;
  const char* constraints = "";
  const char* honoured_by = "";
};

class SchemaBase;

/// A key as the reference sees it.
struct FieldInfo {
  const char* key = "";
  std::string type;                    ///< "number", "[3] numbers", "object", ...
  KeyDoc doc;
  bool required = false;
  const SchemaBase* child = nullptr;   ///< Schema of an object value or of array elements.
  const char* index = nullptr;         ///< Array of objects: the index letter of the reference ("i").
  bool own_table = false;              ///< The child's keys have their own table in the reference.
};

/// An object's keys, independent of the struct they fill (for the reference).
class SchemaBase {
 public:
  virtual ~SchemaBase() = default;
  virtual std::size_t size() const = 0;
  virtual const FieldInfo& info(std::size_t i) const = 0;
  /// The default column of key i (see KeyDoc::default_text).
  virtual std::string default_text(std::size_t i) const = 0;
};

/// One key of an object that fills a T.
template <class T>
struct Field {
  FieldInfo info;
  std::function<void(const json&, const std::string& path, T&)> read;
  std::function<ojson(const T&)> write;   ///< Empty: never written (a note for the reader).
  std::function<bool(const T&)> present;  ///< Whether scene_to_json writes it; empty: always.

  Field&& when(std::function<bool(const T&)> p) && {
    present = std::move(p);
    return std::move(*this);
  }
  Field&& required() && {
    info.required = true;
    return std::move(*this);
  }
  Field&& own_table() && {
    info.own_table = true;
    return std::move(*this);
  }
  bool written(const T& v) const { return write && (!present || present(v)); }
};

/// Two keys of an object that exclude each other; the second is reported.
struct Conflict {
  const char* first;
  const char* second;
  const char* reason;
};

/// The keys of an object that fills a T, the pairs of keys that exclude each other, and an
/// optional check of the whole object (after its keys are read).
template <class T>
class Schema final : public SchemaBase {
 public:
  using Check = std::function<void(const JsonObject&, const T&)>;
  explicit Schema(std::vector<Field<T>> fields, std::vector<Conflict> conflicts = {}, Check check = {})
      : fields_(std::move(fields)), conflicts_(std::move(conflicts)), check_(std::move(check)) {
    for (const auto& f : fields_) keys_.push_back(f.info.key);
  }

  T read(const json& j, const std::string& path) const {
    const JsonObject o(j, path, keys_);
    for (const Conflict& c : conflicts_)
      if (o.has(c.first) && o.has(c.second)) throw InputError(o.path(c.second), text_of(o.at(c.second)), c.reason);
    T v;
    for (const auto& f : fields_) {
      if (o.has(f.info.key))
        f.read(o.at(f.info.key), o.path(f.info.key), v);
      else if (f.info.required)
        o.at(f.info.key);  // throws "is required"
    }
    if (check_) check_(o, v);
    return v;
  }

  ojson write(const T& v) const {
    ojson j = ojson::object();
    for (const auto& f : fields_)
      if (f.written(v)) j[f.info.key] = f.write(v);
    return j;
  }

  std::size_t size() const override { return fields_.size(); }
  const FieldInfo& info(std::size_t i) const override { return fields_[i].info; }
  std::string default_text(std::size_t i) const override;

 private:
  std::vector<Field<T>> fields_;
  std::vector<const char*> keys_;
  std::vector<Conflict> conflicts_;
  Check check_;
};

/// A JSON value as the reference writes it: `2.11e11`, `[0, 0, 0]`, `"rk4"`, `true`.
std::string reference_text(const ojson& j);

template <class T>
std::string Schema<T>::default_text(std::size_t i) const {
  const Field<T>& f = fields_[i];
  if (f.info.required) return "required";
  if (f.info.doc.default_text) return f.info.doc.default_text;
  const auto p = std::make_unique<const T>();  // on the heap: GCC 12 warns falsely (maybe-uninitialized) on a local
  const T& v = *p;
  return f.written(v) ? "`" + reference_text(f.write(v)) + "`" : "";
}

// --- Field builders: one per kind of value ---------------------------------------------------

/// A member read by `read(value, path)` and written as its JSON value (non-finite numbers as null).
template <class T, class V, class Read>
Field<T> member_field(const char* key, const char* type, V T::*m, Read read, KeyDoc doc) {
  return {{key, type, doc},
          [m, read](const json& j, const std::string& p, T& v) { v.*m = read(j, p); },
          [m](const T& v) { return ojson(v.*m); },
          {}};
}

template <class T>
Field<T> number_field(const char* key, double T::*m, KeyDoc doc) {
  return member_field(key, "number", m, read_number, doc);
}

template <class T>
Field<T> integer_field(const char* key, int T::*m, KeyDoc doc) {
  return member_field(key, "integer", m, read_int, doc);
}

template <class T>
Field<T> boolean_field(const char* key, bool T::*m, KeyDoc doc) {
  return member_field(key, "boolean", m, read_bool, doc);
}

template <class T>
Field<T> string_field(const char* key, std::string T::*m, KeyDoc doc) {
  return member_field(key, "string", m, read_string, doc);
}

/// An optional number: written only when set.
template <class T>
Field<T> optional_number_field(const char* key, std::optional<double> T::*m, KeyDoc doc) {
  return {{key, "number", doc},
          [m](const json& j, const std::string& p, T& v) { v.*m = read_number(j, p); },
          [m](const T& v) { return number((v.*m).value_or(0.0)); },
          [m](const T& v) { return (v.*m).has_value(); }};
}

/// Free text for the reader of the file: type checked, then dropped (never written).
template <class T>
Field<T> note_field(const char* key, KeyDoc doc) {
  return {{key, "string", doc}, [](const json& j, const std::string& p, T&) { read_string(j, p); }, {}, {}};
}

template <class T>
Field<T> vec3_field(const char* key, Vec3 T::*m, KeyDoc doc) {
  return {{key, "[3] numbers", doc},
          [m](const json& j, const std::string& p, T& v) { v.*m = read_vec3(j, p); },
          [m](const T& v) { return vec_json(v.*m); },
          {}};
}

/// A fixed-length C array of numbers.
template <class T, std::size_t N>
Field<T> numbers_field(const char* key, double (T::*m)[N], KeyDoc doc) {
  return {{key, "[" + std::to_string(N) + "] numbers", doc},
          [m](const json& j, const std::string& p, T& v) {
            const std::vector<double> x = read_numbers(j, p, N);
            std::copy(x.begin(), x.end(), v.*m);
          },
          [m](const T& v) { return numbers_json(std::vector<double>(v.*m, v.*m + N)); },
          {}};
}

/// A name from `names` for an enumeration member.
template <class T, class E>
Field<T> choice_field(const char* key, E T::*m, const Names<E>& names, KeyDoc doc) {
  return {{key, "string", doc},
          [m, &names](const json& j, const std::string& p, T& v) { v.*m = read_choice(j, p, names); },
          [m, &names](const T& v) { return ojson(name_of(v.*m, names)); },
          {}};
}

/// A nested object.
template <class T, class C>
Field<T> object_field(const char* key, C T::*m, const Schema<C>& schema, KeyDoc doc) {
  Field<T> f{{key, "object", doc},
             [m, &schema](const json& j, const std::string& p, T& v) { v.*m = schema.read(j, p); },
             [m, &schema](const T& v) { return schema.write(v.*m); },
             {}};
  f.info.child = &schema;
  return f;
}

/// A nested object that may be absent (written only when set).
template <class T, class C>
Field<T> optional_object_field(const char* key, std::optional<C> T::*m, const Schema<C>& schema, KeyDoc doc) {
  Field<T> f{{key, "object", doc},
             [m, &schema](const json& j, const std::string& p, T& v) { v.*m = schema.read(j, p); },
             [m, &schema](const T& v) { return schema.write((v.*m).value_or(C{})); },
             [m](const T& v) { return (v.*m).has_value(); }};
  f.info.child = &schema;
  return f;
}

/// An array of objects, indexed `index` in the reference; `at_least_one` names an element when
/// the array must not be empty (nullptr: may be empty).
template <class T, class C>
Field<T> objects_field(const char* key, std::vector<C> T::*m, const Schema<C>& schema, const char* index,
                       const char* at_least_one, KeyDoc doc) {
  Field<T> f{{key, "array", doc},
             [m, &schema, at_least_one](const json& j, const std::string& p, T& v) {
               require_array(j, p);
               if (j.empty() && at_least_one)
                 throw InputError(p, "[]", std::string("must list at least one ") + at_least_one);
               (v.*m).clear();
               for (std::size_t i = 0; i < j.size(); ++i) (v.*m).push_back(schema.read(j[i], index_path(p, i)));
             },
             [m, &schema](const T& v) {
               ojson a = ojson::array();
               for (const C& c : v.*m) a.push_back(schema.write(c));
               return a;
             },
             {}};
  f.info.child = &schema;
  f.info.index = index;
  return f;
}

/// The scene's table (scene_schema.cpp).
const Schema<Scene>& scene_schema();
/// The `environment` object's table (scene_environment_schema.cpp).
const Schema<Environment>& environment_schema();

/// The table of the scene's `solver` object, SolverOptions (scene_solver_schema.cpp).
const Schema<SolverOptions>& solver_schema();

}  // namespace tdcr::detail
