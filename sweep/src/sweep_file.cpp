// Sweep files: parsing, validation (before any solve) and the values of each sample.
#include "tdcr/sweep/sweep_file.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
// GCC 12 reports a false -Wmaybe-uninitialized inside <regex>'s compiler at -O2 with the
// sanitizers (std::function moved out of a temporary NFA state; GCC bug 105562).
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <regex>
#pragma GCC diagnostic pop
#else
#include <regex>
#endif
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "json_reader.hpp"  // core's strict JSON reading (sweep/CMakeLists.txt)
#include "tdcr/core/error.hpp"
#include "tdcr/core/scene_io.hpp"
#include "tdcr/models/model_registry.hpp"
#include "sweep_detail.hpp"

namespace tdcr {
namespace {

using json = nlohmann::json;
constexpr std::uint64_t kMaxSamples = std::uint64_t(1) << 40;
constexpr std::uint64_t kMaxAxisValues = 10000000;

std::string text_of(const json& v) { return v.dump(); }

void check_keys(const json& obj, const std::string& path, std::initializer_list<const char*> known) {
  for (auto it = obj.begin(); it != obj.end(); ++it) {
    if (std::none_of(known.begin(), known.end(), [&](const char* k) { return it.key() == k; })) {
      std::string list;
      for (const char* k : known) list += std::string(list.empty() ? "" : ", ") + k;
      throw InputError(path.empty() ? it.key() : path + "." + it.key(), "", "unknown key (known: " + list + ")");
    }
  }
}

double number(const json& v, const std::string& field) {
  if (!v.is_number() || !std::isfinite(v.get<double>()))
    throw InputError(field, text_of(v), "must be a finite number");
  return v.get<double>();
}

std::uint64_t whole(const json& v, const std::string& field, std::uint64_t lo, std::uint64_t hi) {
  if (!v.is_number_integer() || (v.is_number_integer() && !v.is_number_unsigned() && v.get<std::int64_t>() < 0) ||
      v.get<std::uint64_t>() < lo || v.get<std::uint64_t>() > hi)
    throw InputError(field, text_of(v), "must be a whole number from " + std::to_string(lo) + " to " + std::to_string(hi));
  return v.get<std::uint64_t>();
}

/// The input target of a field path, or Scene for anything else the scene file has.
void classify(SweepAxis& axis, const Scene& base, const std::string& where) {
  static const std::regex input_re(R"(^(actuation|loads)\.(tensions|displacements|tip_force|tip_moment|gravity)\[(\d+)\]$)");
  static const std::regex scene_re(R"(^(robot|effects|solver)(\.[A-Za-z_]+(\[\d+\])*)+$)");
  std::smatch m;
  if (std::regex_match(axis.field, m, input_re)) {
    const std::string group = m[1], name = m[2];
    const std::size_t k = sweep_detail::index_value(m[3]);
    axis.index = static_cast<int>(std::min<std::size_t>(k, 1 << 30));
    if (group == "actuation" && (name == "tensions" || name == "displacements")) {
      const bool tensions = name == "tensions";
      if (k >= base.actuation.values.size())
        throw InputError(axis.field, "", "does not exist: the base scene has " +
                                             std::to_string(base.actuation.values.size()) + " tendons");
      // Mixed input: each tendon is given by one of the two lists.
      if ((base.actuation.kind_of(k) == Actuation::Kind::Tensions) != tensions)
        throw InputError(axis.field, "", "does not exist: the base scene's actuation gives tendon " + std::to_string(k) +
                                             " by " + std::string(tensions ? "displacement" : "tension"));
      axis.target = tensions ? SweepAxis::Target::Tension : SweepAxis::Target::Displacement;
      return;
    }
    if (group == "loads" && (name == "tip_force" || name == "tip_moment" || name == "gravity")) {
      if (k > 2) throw InputError(axis.field, "", "does not exist: a load vector has components [0], [1], [2]");
      axis.target = name == "tip_force"    ? SweepAxis::Target::TipForce
                    : name == "tip_moment" ? SweepAxis::Target::TipMoment
                                           : SweepAxis::Target::Gravity;
      return;
    }
  }
  if (!std::regex_match(axis.field, scene_re))
    throw InputError(where, axis.field,
                     "not a sweepable field: give actuation.tensions[k], actuation.displacements[k], "
                     "loads.tip_force[i], loads.tip_moment[i], loads.gravity[i], or a numeric robot., "
                     "effects. or solver. field of the scene file");
  axis.target = SweepAxis::Target::Scene;
}

SweepAxis parse_axis(const json& a, const std::string& path, bool random, const Scene& base) {
  if (!a.is_object()) throw InputError(path, text_of(a), "must be an object");
  check_keys(a, path, {"field", "values", "from", "to", "count"});
  SweepAxis axis;
  if (!a.contains("field") || !a["field"].is_string())
    throw InputError(path + ".field", a.contains("field") ? text_of(a["field"]) : "", "must be a field path string");
  axis.field = a["field"].get<std::string>();
  classify(axis, base, path + ".field");
  const bool has_values = a.contains("values");
  const bool has_range = a.contains("from") || a.contains("to");
  if (has_values == has_range)
    throw InputError(path, axis.field, "give either \"values\" or \"from\" and \"to\"");
  if (has_values) {
    const json& v = a["values"];
    if (!v.is_array() || v.empty() || v.size() > kMaxAxisValues)
      throw InputError(path + ".values", text_of(v).substr(0, 80), "must be a non-empty list of numbers");
    for (std::size_t i = 0; i < v.size(); ++i)
      axis.values.push_back(number(v[i], path + ".values[" + std::to_string(i) + "]"));
    if (a.contains("count")) throw InputError(path + ".count", text_of(a["count"]), "applies to from/to only");
    return axis;
  }
  if (!a.contains("from") || !a.contains("to"))
    throw InputError(path, axis.field, "a range needs both \"from\" and \"to\"");
  axis.from = number(a["from"], path + ".from");
  axis.to = number(a["to"], path + ".to");
  if (!std::isfinite(axis.to - axis.from))  // e.g. -1e308 to 1e308: the samples would be inf or nan
    throw InputError(path + ".to", text_of(a["to"]),
                     "the range from " + text_of(a["from"]) + " is wider than a double holds");
  if (random) {
    if (a.contains("count"))
      throw InputError(path + ".count", text_of(a["count"]), "random sampling draws \"samples\" points; no count per axis");
    return axis;
  }
  if (!a.contains("count")) throw InputError(path + ".count", "", "a grid range needs a count");
  const std::uint64_t n = whole(a["count"], path + ".count", 1, kMaxAxisValues);
  for (std::uint64_t i = 0; i < n; ++i)
    axis.values.push_back(n == 1 ? axis.from : axis.from + (axis.to - axis.from) * double(i) / double(n - 1));
  return axis;
}

/// Each axis at its smallest and largest value (the others at the base scene), validated for
/// every model: an out-of-range axis is reported before any solve.
void check_extremes(const SweepSpec& spec) {
  std::vector<double> values;
  for (std::size_t a = 0; a < spec.axes.size(); ++a) {
    const SweepAxis& axis = spec.axes[a];
    double lo = axis.from, hi = axis.to;
    if (!axis.values.empty()) {
      lo = *std::min_element(axis.values.begin(), axis.values.end());
      hi = *std::max_element(axis.values.begin(), axis.values.end());
    }
    for (double v : {lo, hi}) {
      try {
        sweep_detail::base_values(spec, values);
        values[a] = v;
        Scene scene = spec.scene_with(values);
        const ModelInput input = spec.input_with(scene, values);
        scene.actuation = input.actuation;
        scene.loads = input.loads;
        for (ModelKind kind : spec.models) {
          scene.model = to_string(kind);
          validate_scene(scene);
        }
      } catch (const InputError& e) {
        // The scene's reason, reported for the axis and its value.
        std::string reason = e.what();
        const std::string got = " (got " + e.value() + ")";
        if (reason.rfind(e.field() + ": ", 0) == 0) reason.erase(0, e.field().size() + 2);
        if (!e.value().empty() && reason.size() >= got.size() && reason.compare(reason.size() - got.size(), got.size(), got) == 0)
          reason.resize(reason.size() - got.size());
        if (e.field() != axis.field) reason = "the scene is invalid at this value: " + e.field() + ": " + reason;
        throw InputError(axis.field, format_value(v), reason);
      }
    }
  }
}

std::uint64_t fnv1a(const std::string& s) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : s) h = (h ^ c) * 1099511628211ull;
  return h;
}

std::string read_file(const std::string& path, const std::string& field) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(field, path, "cannot read the file (does it exist?)");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

SweepSpec parse_sweep(const std::string& json_text, const std::string& source, const std::string& base_dir) {
  // As strict as a scene file: a syntax error names the byte, a duplicate key or a number that
  // overflows a double (1e999) names its path in the sweep file (axes[0].to, scene.robot...).
  json doc = detail::parse_json_text(json_text, source);
  if (!doc.is_object()) throw InputError(source, "", "a sweep file is a JSON object");
  check_keys(doc, "", {"description", "scene", "models", "axes", "sampling", "samples", "seed", "order"});
  SweepSpec spec;
  spec.source = source;

  if (!doc.contains("scene")) throw InputError("scene", "", "missing: a scene file path or an inline scene object");
  json scene_json;
  if (doc["scene"].is_string()) {
    std::string path = doc["scene"].get<std::string>();
    if (!path.empty() && path[0] != '/') path = base_dir + "/" + path;
    const std::string text = read_file(path, "scene");
    spec.base = parse_scene(text, path);
    scene_json = json::parse(text);
  } else if (doc["scene"].is_object()) {
    scene_json = doc["scene"];
    spec.base = parse_scene(scene_json.dump(), source + ": scene");
  } else {
    throw InputError("scene", text_of(doc["scene"]).substr(0, 80), "must be a file path or a scene object");
  }
  scene_json.erase("description");
  spec.base_scene_json = scene_json.dump();

  if (!doc.contains("models") || !doc["models"].is_array() || doc["models"].empty())
    throw InputError("models", doc.contains("models") ? text_of(doc["models"]) : "", "must be a non-empty list of model names");
  for (std::size_t i = 0; i < doc["models"].size(); ++i) {
    const json& m = doc["models"][i];
    const std::string field = "models[" + std::to_string(i) + "]";
    if (!m.is_string()) throw InputError(field, text_of(m), "must be a model name");
    ModelKind kind;
    try {
      kind = parse_model_kind(m.get<std::string>());
    } catch (const InputError& e) {
      throw InputError(field, m.get<std::string>(), "unknown model (known: " + model_names() + ")");
    }
    if (std::find(spec.models.begin(), spec.models.end(), kind) != spec.models.end())
      throw InputError(field, m.get<std::string>(), "listed twice");
    spec.models.push_back(kind);
  }

  std::string sampling = "grid";
  if (doc.contains("sampling") && doc["sampling"].is_string()) sampling = doc["sampling"].get<std::string>();
  if (doc.contains("sampling") && (!doc["sampling"].is_string() || (sampling != "grid" && sampling != "random")))
    throw InputError("sampling", text_of(doc["sampling"]), "must be \"grid\" or \"random\"");
  spec.random = sampling == "random";
  if (spec.random) {
    if (!doc.contains("samples")) throw InputError("samples", "", "random sampling needs a number of samples");
    if (!doc.contains("seed")) throw InputError("seed", "", "random sampling needs a seed (reproducible samples)");
    spec.random_samples = whole(doc["samples"], "samples", 1, kMaxSamples);
    spec.seed = whole(doc["seed"], "seed", 0, std::numeric_limits<std::uint64_t>::max());
  } else {
    for (const char* k : {"samples", "seed"})
      if (doc.contains(k)) throw InputError(k, text_of(doc[k]), "applies to \"sampling\": \"random\" only");
  }

  if (doc.contains("order")) {
    if (!doc["order"].is_string() || (doc["order"] != "warm_start" && doc["order"] != "sample"))
      throw InputError("order", text_of(doc["order"]), "must be \"warm_start\" or \"sample\"");
    spec.warm_order = doc["order"] == "warm_start";
  }

  if (!doc.contains("axes") || !doc["axes"].is_array() || doc["axes"].empty())
    throw InputError("axes", doc.contains("axes") ? text_of(doc["axes"]).substr(0, 80) : "", "must be a non-empty list of axes");
  std::set<std::string> fields;
  long double product = 1.0;
  for (std::size_t i = 0; i < doc["axes"].size(); ++i) {
    const std::string path = "axes[" + std::to_string(i) + "]";
    spec.axes.push_back(parse_axis(doc["axes"][i], path, spec.random, spec.base));
    if (!fields.insert(spec.axes.back().field).second)
      throw InputError(path + ".field", spec.axes.back().field, "swept twice");
    product *= static_cast<long double>(std::max<std::size_t>(spec.axes.back().values.size(), 1));
  }
  if (!spec.random && product > static_cast<long double>(kMaxSamples))
    throw InputError("axes", "", "the grid has more than 2^40 samples");
  check_extremes(spec);

  json canonical = doc;
  canonical.erase("description");
  canonical["scene"] = scene_json;
  spec.hash = fnv1a(canonical.dump());
  return spec;
}

SweepSpec load_sweep(const std::string& path) {
  const std::string text = read_file(path, "sweep file");
  const auto slash = path.find_last_of('/');
  return parse_sweep(text, path, slash == std::string::npos ? "." : path.substr(0, slash));
}

}  // namespace tdcr
