// Scene files (JSON) in, solutions (JSON) out.
//
// Parsing is strict: every object has a table of known keys (an unknown key is an error that
// names its path and suggests the closest known key), every value is type checked at its JSON
// path, numbers must be finite, and duplicate keys are rejected. Semantic checks (positive
// lengths, tendon off the axis, tensions >= 0, list lengths) are Scene::validate()'s, which is
// called on the parsed scene; it reports the same JSON paths.
#include "tdcr/core/scene_io.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "tdcr/core/error.hpp"

namespace tdcr {

namespace {

using json = nlohmann::json;

// ---------------------------------------------------------------------------------------------
// Paths and messages

std::string key_path(const std::string& parent, const std::string& key) {
  return parent.empty() ? key : parent + "." + key;
}

std::string index_path(const std::string& parent, std::size_t i) {
  return parent + "[" + std::to_string(i) + "]";
}

/// Compact JSON text of a value for messages (non-finite numbers as "nan"/"inf", not "null"),
/// shortened if long.
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

std::string type_name(const json& j) {
  if (j.is_number_integer()) return "an integer";
  if (j.is_number_float()) return "a number";
  if (j.is_boolean()) return "a boolean";
  if (j.is_string()) return "a string";
  if (j.is_array()) return "an array";
  if (j.is_object()) return "an object";
  return "null";
}

[[noreturn]] void type_error(const std::string& path, const json& j, const std::string& expected) {
  throw InputError(path, text_of(j), "must be " + expected + ", not " + type_name(j));
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

using KeyTable = std::vector<const char*>;

std::string join_keys(const KeyTable& keys) {
  std::string s;
  for (const char* k : keys) s += (s.empty() ? "" : ", ") + std::string(k);
  return s;
}

// ---------------------------------------------------------------------------------------------
// Typed readers: each takes the value and its JSON path and throws InputError on a type error.

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

/// A fixed-length list of numbers.
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

/// A string naming one of `choices` (scene-file names paired with their values).
template <class T>
T read_choice(const json& j, const std::string& path, const std::vector<std::pair<const char*, T>>& choices) {
  std::string names;
  for (const auto& c : choices) names += (names.empty() ? "" : ", ") + std::string("\"") + c.first + "\"";
  if (!j.is_string()) type_error(path, j, "one of " + names);
  const std::string s = j.get<std::string>();
  for (const auto& c : choices)
    if (s == c.first) return c.second;
  throw InputError(path, text_of(j), "must be one of " + names);
}

// ---------------------------------------------------------------------------------------------
// Objects: a view of one JSON object at a path, with a table of its known keys.

class Object {
 public:
  /// Checks that `j` is an object whose keys all appear in `known`.
  Object(const json& j, std::string path, const KeyTable& known) : j_(j), path_(std::move(path)) {
    if (!j.is_object()) type_error(path_.empty() ? "scene" : path_, j, "an object");
    for (const auto& item : j.items()) check_known(item.key(), item.value(), known);
  }

  bool has(const char* key) const { return j_.contains(key); }
  const json& at(const char* key) const {
    if (!has(key)) throw InputError(path(key), "", "is required");
    return j_.at(key);
  }
  std::string path(const std::string& key) const { return key_path(path_, key); }
  const std::string& path() const { return path_; }

  // Optional values: `out` keeps its default when the key is absent.
  void get(const char* key, double& out) const {
    if (has(key)) out = read_number(j_.at(key), path(key));
  }
  void get(const char* key, int& out) const {
    if (has(key)) out = read_int(j_.at(key), path(key));
  }
  void get(const char* key, bool& out) const {
    if (has(key)) out = read_bool(j_.at(key), path(key));
  }
  void get(const char* key, Vec3& out) const {
    if (has(key)) out = read_vec3(j_.at(key), path(key));
  }
  void get(const char* key, std::optional<double>& out) const {
    if (has(key)) out = read_number(j_.at(key), path(key));
  }
  template <class T>
  void get(const char* key, T& out, const std::vector<std::pair<const char*, T>>& choices) const {
    if (has(key)) out = read_choice(j_.at(key), path(key), choices);
  }

  /// Rejects giving both keys of a pair that exclude each other.
  void exclusive(const char* a, const char* b, const std::string& reason) const {
    if (has(a) && has(b)) throw InputError(path(b), text_of(j_.at(b)), reason);
  }

 private:
  void check_known(const std::string& key, const json& value, const KeyTable& known) const {
    const char* best = nullptr;
    std::size_t best_d = std::numeric_limits<std::size_t>::max();
    for (const char* k : known) {
      if (key == k) return;
      const std::size_t d = edit_distance(key, k);
      if (d < best_d) best_d = d, best = k;
    }
    std::string reason = "unknown key";
    if (best && best_d <= std::max<std::size_t>(2, key.size() / 3))
      reason += "; did you mean \"" + std::string(best) + "\"?";
    reason += " (known keys here: " + join_keys(known) + ")";
    throw InputError(path(key), text_of(value), reason);
  }

  const json& j_;
  std::string path_;
};

// ---------------------------------------------------------------------------------------------
// Names of enumerations in scene files

const std::vector<std::pair<const char*, Actuation::DisplacementConvention>> kConventions = {
    {"at_base", Actuation::DisplacementConvention::AtBase},
    {"per_segment", Actuation::DisplacementConvention::PerSegment}};
const std::vector<std::pair<const char*, DiskNormalForce>> kDiskNormalForce = {
    {"removed", DiskNormalForce::Removed}, {"kept", DiskNormalForce::Kept}};
const std::vector<std::pair<const char*, TendonPath>> kTendonPath = {
    {"fully_constrained", TendonPath::FullyConstrained},
    {"partially_constrained", TendonPath::PartiallyConstrained}};
const std::vector<std::pair<const char*, IntegratorKind>> kIntegrators = {
    {"rk4", IntegratorKind::FixedStepRK4}, {"cvode", IntegratorKind::Cvode}};
const std::vector<std::pair<const char*, LinearSolverKind>> kLinearSolvers = {
    {"auto", LinearSolverKind::Automatic},
    {"dense", LinearSolverKind::Dense},
    {"klu", LinearSolverKind::SparseKLU}};
const std::vector<std::pair<const char*, std::string>> kModels = {
    {"cc", "cc"}, {"ccsub", "ccsub"}, {"prb", "prb"}, {"vc", "vc"}, {"vcref", "vcref"}, {"auto", "auto"}};

template <class T>
const char* name_of(T value, const std::vector<std::pair<const char*, T>>& choices) {
  for (const auto& c : choices)
    if (c.second == value) return c.first;
  return "?";
}

// ---------------------------------------------------------------------------------------------
// Scene sections

BackboneStiffness parse_stiffness(const json& j, const std::string& path) {
  const Object o(j, path, {"EI", "GJ", "EA", "GA"});
  BackboneStiffness k;
  k.EI = read_number(o.at("EI"), o.path("EI"));
  k.GJ = read_number(o.at("GJ"), o.path("GJ"));
  k.EA = read_number(o.at("EA"), o.path("EA"));
  k.GA = read_number(o.at("GA"), o.path("GA"));
  return k;
}

Backbone parse_backbone(const json& j, const std::string& path) {
  const Object o(j, path,
                 {"youngs_modulus", "poisson_ratio", "shear_modulus", "outer_radius", "inner_radius",
                  "density", "mass_per_length", "stiffness"});
  Backbone b;
  if (o.has("stiffness")) {
    const char* why = "the material and section are given by \"stiffness\"; give one or the other";
    for (const char* k : {"youngs_modulus", "poisson_ratio", "shear_modulus", "outer_radius", "inner_radius"})
      if (o.has(k)) throw InputError(o.path(k), text_of(o.at(k)), why);
    if (o.has("density"))
      throw InputError(o.path("density"), text_of(o.at("density")),
                       "with \"stiffness\" the section area is unknown; give \"mass_per_length\" instead");
    b.stiffness = parse_stiffness(o.at("stiffness"), o.path("stiffness"));
  }
  o.exclusive("poisson_ratio", "shear_modulus", "give either poisson_ratio or shear_modulus, not both");
  o.exclusive("density", "mass_per_length", "give either density or mass_per_length, not both");
  o.get("youngs_modulus", b.youngs_modulus);
  o.get("poisson_ratio", b.poisson_ratio);
  o.get("shear_modulus", b.shear_modulus);
  o.get("outer_radius", b.outer_radius);
  o.get("inner_radius", b.inner_radius);
  o.get("density", b.density);
  o.get("mass_per_length", b.mass_per_length);
  return b;
}

TendonSpec parse_tendon(const json& j, const std::string& path) {
  const Object o(j, path, {"x", "y"});
  return TendonSpec{read_number(o.at("x"), o.path("x")), read_number(o.at("y"), o.path("y"))};
}

Segment parse_segment(const json& j, const std::string& path) {
  const Object o(j, path, {"length", "disks", "tendons", "disk_mass"});
  Segment s;
  s.length = read_number(o.at("length"), o.path("length"));
  s.disks = read_int(o.at("disks"), o.path("disks"));
  const json& tendons = require_array(o.at("tendons"), o.path("tendons"));
  for (std::size_t k = 0; k < tendons.size(); ++k)
    s.tendons.push_back(parse_tendon(tendons[k], index_path(o.path("tendons"), k)));
  o.get("disk_mass", s.disk_mass);
  return s;
}

Robot parse_robot(const json& j, const std::string& path) {
  const Object o(j, path, {"backbone", "segments"});
  Robot r;
  if (o.has("backbone")) r.backbone = parse_backbone(o.at("backbone"), o.path("backbone"));
  const json& segments = require_array(o.at("segments"), o.path("segments"));
  if (segments.empty()) throw InputError(o.path("segments"), "[]", "must list at least one segment");
  for (std::size_t i = 0; i < segments.size(); ++i)
    r.segments.push_back(parse_segment(segments[i], index_path(o.path("segments"), i)));
  return r;
}

Actuation parse_actuation(const json& j, const std::string& path) {
  const Object o(j, path, {"tensions", "displacements", "displacement_convention"});
  Actuation a;
  o.exclusive("tensions", "displacements", "give either tensions or displacements, not both");
  if (o.has("tensions")) {
    if (o.has("displacement_convention"))
      throw InputError(o.path("displacement_convention"), text_of(o.at("displacement_convention")),
                       "applies to displacements only, not to tensions");
    a.kind = Actuation::Kind::Tensions;
    a.values = read_numbers(o.at("tensions"), o.path("tensions"));
  } else if (o.has("displacements")) {
    a.kind = Actuation::Kind::Displacements;
    a.values = read_numbers(o.at("displacements"), o.path("displacements"));
    o.get("displacement_convention", a.convention, kConventions);
  } else {
    throw InputError(path, text_of(j), "must give either \"tensions\" or \"displacements\"");
  }
  return a;
}

Loads parse_loads(const json& j, const std::string& path) {
  const Object o(j, path, {"tip_force", "tip_moment", "gravity"});
  Loads l;
  o.get("tip_force", l.tip_force);
  o.get("tip_moment", l.tip_moment);
  o.get("gravity", l.gravity);
  return l;
}

PrbParameters parse_prb(const json& j, const std::string& path) {
  const Object o(j, path, {"gamma", "k_theta"});
  PrbParameters p;
  if (o.has("gamma")) {
    const std::vector<double> g = read_numbers(o.at("gamma"), o.path("gamma"), 4);
    std::copy(g.begin(), g.end(), p.gamma);
  }
  if (o.has("k_theta")) {
    const std::vector<double> k = read_numbers(o.at("k_theta"), o.path("k_theta"), 3);
    std::copy(k.begin(), k.end(), p.k_theta);
  }
  return p;
}

Effects parse_effects(const json& j, const std::string& path) {
  const Object o(j, path, {"shear_extension", "disk_normal_force", "tendon_path", "prb"});
  Effects e;
  o.get("shear_extension", e.shear_extension);
  o.get("disk_normal_force", e.disk_normal_force, kDiskNormalForce);
  o.get("tendon_path", e.tendon_path, kTendonPath);
  if (o.has("prb")) e.prb = parse_prb(o.at("prb"), o.path("prb"));
  return e;
}

SolverOptions parse_solver(const json& j, const std::string& path) {
  const Object o(
      j, path,
      {"integrator", "rk4_steps", "rk4_max_step", "cvode_rtol", "cvode_atol", "function_tolerance", "step_tolerance",
       "max_iterations", "linear_solver", "continuation", "max_continuation_steps"});
  SolverOptions s;
  o.get("integrator", s.integrator, kIntegrators);
  o.get("rk4_steps", s.rk4_steps);
  o.get("rk4_max_step", s.rk4_max_step);
  o.get("cvode_rtol", s.cvode_rtol);
  o.get("cvode_atol", s.cvode_atol);
  o.get("function_tolerance", s.function_tolerance);
  o.get("step_tolerance", s.step_tolerance);
  o.get("max_iterations", s.max_iterations);
  o.get("linear_solver", s.linear_solver, kLinearSolvers);
  o.get("continuation", s.continuation);
  o.get("max_continuation_steps", s.max_continuation_steps);
  return s;
}

Scene parse_scene_object(const json& j) {
  // "description" is a free-text note for people reading the file; it is not part of Scene.
  const Object o(j, "", {"robot", "actuation", "loads", "effects", "model", "solver", "description"});
  Scene s;
  if (o.has("description") && !o.at("description").is_string())
    type_error("description", o.at("description"), "a string");
  s.robot = parse_robot(o.at("robot"), "robot");
  s.actuation = parse_actuation(o.at("actuation"), "actuation");
  if (o.has("loads")) s.loads = parse_loads(o.at("loads"), "loads");
  if (o.has("effects")) s.effects = parse_effects(o.at("effects"), "effects");
  o.get("model", s.model, kModels);
  if (o.has("solver")) s.solver = parse_solver(o.at("solver"), "solver");
  return s;
}

// ---------------------------------------------------------------------------------------------
// Raw JSON text: syntax errors, number overflow and duplicate keys, with the JSON path.

/// Follows the parser through the document so that a duplicate key or an overflowing number can
/// be reported at its JSON path (nlohmann itself keeps the last duplicate silently).
class PathTracker {
 public:
  bool operator()(int /*depth*/, json::parse_event_t event, json& parsed) {
    switch (event) {
      case json::parse_event_t::object_start:
      case json::parse_event_t::array_start:
        // A scene is at most 5 levels deep; a bound keeps pathological files from exhausting
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

json parse_json_text(const std::string& text, const std::string& source) {
  PathTracker tracker;
  try {
    return json::parse(text, std::ref(tracker));
  } catch (const json::parse_error& e) {
    throw InputError(source, "",
                     "malformed JSON at byte " + std::to_string(e.byte) + ": " + plain_message(e));
  } catch (const json::out_of_range& e) {
    // A number too large for a double (e.g. 1e999).
    std::string value;
    const std::string m = e.what();
    const auto a = m.find('\''), b = m.rfind('\'');
    if (a != std::string::npos && b > a) value = m.substr(a + 1, b - a - 1);
    const std::string path = tracker.pending_path();
    throw InputError(path.empty() ? source : path, value,
                     "must be a finite number (" + plain_message(e) + ")");
  }
}

// ---------------------------------------------------------------------------------------------
// Output: ordered JSON (keys in contract order), printed with small arrays and objects on one line.

using ojson = nlohmann::ordered_json;

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

/// Rotation as a list of rows: rotation[i][j] = R(i, j).
ojson rotation_json(const Mat3& R) {
  ojson rows = ojson::array();
  for (int i = 0; i < 3; ++i) rows.push_back(vec_json(R.row(i).transpose()));
  return rows;
}

ojson frame_json(const Frame& f) {
  return ojson{{"position", vec_json(f.p)}, {"rotation", rotation_json(f.R)}};
}

ojson summary_json(const SolverSummary& s) {
  return ojson{{"termination", to_string(s.termination)},
               {"message", s.message},
               {"solver_flag", s.solver_flag},
               {"iterations", s.iterations},
               {"residual_evaluations", s.residual_evaluations},
               {"jacobian_evaluations", s.jacobian_evaluations},
               {"residual_norm", number(s.residual_norm)},
               {"physical_residual", number(s.physical_residual)},
               {"unknowns", s.unknowns},
               {"continuation_steps", s.continuation_steps},
               {"linear_solver", s.linear_solver},
               {"integrator", s.integrator},
               {"solve_time_s", number(s.solve_time_s)}};
}

ojson backbone_json(const std::vector<BackboneSample>& samples) {
  ojson a = ojson::array();
  for (const auto& b : samples)
    a.push_back(ojson{{"s", number(b.s)},
                      {"position", vec_json(b.frame.p)},
                      {"rotation", rotation_json(b.frame.R)},
                      {"n", vec_json(b.n)},
                      {"m", vec_json(b.m)}});
  return a;
}

ojson backbone_to_json(const Backbone& b) {
  ojson j = ojson::object();
  if (b.stiffness) {
    j["stiffness"] = {
        {"EI", b.stiffness->EI}, {"GJ", b.stiffness->GJ}, {"EA", b.stiffness->EA}, {"GA", b.stiffness->GA}};
  } else {
    j["youngs_modulus"] = b.youngs_modulus;
    if (b.shear_modulus)
      j["shear_modulus"] = *b.shear_modulus;
    else
      j["poisson_ratio"] = b.poisson_ratio;
    j["outer_radius"] = b.outer_radius;
    j["inner_radius"] = b.inner_radius;
  }
  if (b.mass_per_length)
    j["mass_per_length"] = *b.mass_per_length;
  else if (!b.stiffness)
    j["density"] = b.density;
  return j;
}

ojson robot_to_json(const Robot& r) {
  ojson segments = ojson::array();
  for (const auto& s : r.segments) {
    ojson tendons = ojson::array();
    for (const auto& t : s.tendons) tendons.push_back({{"x", t.x}, {"y", t.y}});
    segments.push_back(
        {{"length", s.length}, {"disks", s.disks}, {"tendons", tendons}, {"disk_mass", s.disk_mass}});
  }
  return ojson{{"backbone", backbone_to_json(r.backbone)}, {"segments", segments}};
}

ojson actuation_to_json(const Actuation& a) {
  if (a.kind == Actuation::Kind::Tensions) return ojson{{"tensions", a.values}};
  return ojson{{"displacements", a.values}, {"displacement_convention", name_of(a.convention, kConventions)}};
}

ojson effects_to_json(const Effects& e) {
  return ojson{{"shear_extension", e.shear_extension},
               {"disk_normal_force", name_of(e.disk_normal_force, kDiskNormalForce)},
               {"tendon_path", name_of(e.tendon_path, kTendonPath)},
               {"prb",
                {{"gamma", std::vector<double>(e.prb.gamma, e.prb.gamma + 4)},
                 {"k_theta", std::vector<double>(e.prb.k_theta, e.prb.k_theta + 3)}}}};
}

ojson solver_to_json(const SolverOptions& s) {
  return ojson{{"integrator", name_of(s.integrator, kIntegrators)},
               {"rk4_steps", s.rk4_steps},
               {"rk4_max_step", s.rk4_max_step},
               {"cvode_rtol", s.cvode_rtol},
               {"cvode_atol", s.cvode_atol},
               {"function_tolerance", s.function_tolerance},
               {"step_tolerance", s.step_tolerance},
               {"max_iterations", s.max_iterations},
               {"linear_solver", name_of(s.linear_solver, kLinearSolvers)},
               {"continuation", s.continuation},
               {"max_continuation_steps", s.max_continuation_steps}};
}

std::vector<double> as_vector(const Vec3& v) { return {v[0], v[1], v[2]}; }

}  // namespace

Scene parse_scene(const std::string& json_text, const std::string& source) {
  const json j = parse_json_text(json_text, source);
  if (!j.is_object()) throw InputError(source, text_of(j), "a scene must be a JSON object");
  Scene scene = parse_scene_object(j);
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
  const ojson j{{"robot", robot_to_json(scene.robot)},
                {"actuation", actuation_to_json(scene.actuation)},
                {"loads",
                 {{"tip_force", as_vector(scene.loads.tip_force)},
                  {"tip_moment", as_vector(scene.loads.tip_moment)},
                  {"gravity", as_vector(scene.loads.gravity)}}},
                {"effects", effects_to_json(scene.effects)},
                {"model", scene.model},
                {"solver", solver_to_json(scene.solver)}};
  return pretty(j);
}

std::string solution_to_json(const Solution& solution, const SolutionJsonOptions& options) {
  const SolverSummary& s = solution.summary;
  std::string reason = to_string(s.termination);
  if (!s.message.empty()) reason += ": " + s.message;

  ojson tip = {{"position", nullptr}, {"rotation", nullptr}};
  if (!solution.disk_frames.empty()) tip = frame_json(solution.tip());

  ojson j = {
      {"model", solution.model},    {"status", s.converged() ? "converged" : "failed"}, {"reason", reason},
      {"iterations", s.iterations}, {"residual_norm", number(s.residual_norm)},         {"tip", tip}};
  if (options.include_disks) {
    ojson disks = ojson::array();
    for (const Frame& f : solution.disk_frames) disks.push_back(frame_json(f));
    j["disks"] = disks;
  }
  j["tendon_displacements"] = numbers_json(solution.tendon_displacements);
  j["tensions"] = numbers_json(solution.tensions);
  if (options.include_backbone) j["backbone"] = backbone_json(solution.backbone);
  j["timing"] = {{"repeat", options.repeat},
                 {"median_us", number(options.median_us)},
                 {"min_us", number(options.min_us)}};
  j["summary"] = summary_json(s);
  if (!solution.model_selection.empty()) j["model_selection"] = solution.model_selection;
  return pretty(j);
}

}  // namespace tdcr
