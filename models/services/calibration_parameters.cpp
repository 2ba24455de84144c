// Calibration parameters: the `--fit` list, the scalar parameters it names for a scene (start,
// bounds, scale), and how their values change the scene; the options' validation.
#include <cmath>
#include <cstdlib>
#include <limits>
#include <sstream>

#include "calibration_detail.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/core/lie.hpp"

namespace tdcr {

namespace {

using Kind = CalibrationParameterKind;
constexpr double kInf = std::numeric_limits<double>::infinity();

struct GroupInfo {
  const char* name;
  Kind kind;
  const char* unit;
  bool positive;  // a physical quantity > 0 (bounds must not be negative)
};

constexpr GroupInfo kGroups[] = {
    {"youngs_modulus", Kind::YoungsModulus, "Pa", true},
    {"shear_modulus", Kind::ShearModulus, "Pa", true},
    {"segment_offset_scale", Kind::SegmentOffsetScale, "", true},
    {"tendon_offset_scale", Kind::TendonOffsetScale, "", true},
    {"segment_length", Kind::SegmentLength, "m", true},
    {"disk_mass", Kind::DiskMass, "kg", true},
    {"tendon_stiffness", Kind::TendonStiffness, "N", true},
    {"friction_coefficient", Kind::FrictionCoefficient, "", true},
    {"base_offset", Kind::BaseOffset, "m", false},
    {"base_rotation", Kind::BaseRotation, "rad", false},
};

const GroupInfo& info(Kind k) {
  for (const GroupInfo& g : kGroups)
    if (g.kind == k) return g;
  return kGroups[0];
}

std::string known_names() {
  std::string s;
  for (const GroupInfo& g : kGroups) s += (s.empty() ? "" : ", ") + std::string(g.name);
  return s;
}

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t");
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(" \t") - a + 1);
}

std::optional<double> bound(const std::string& text, const std::string& entry) {
  const std::string t = trim(text);
  if (t.empty()) return std::nullopt;
  char* end = nullptr;
  const double v = std::strtod(t.c_str(), &end);
  if (*end != '\0' || !std::isfinite(v))
    throw InputError("--fit", entry, "a bound must be a finite number (name:LOWER:UPPER, either may be empty)");
  return v;
}

// The robot's tendons in global order as (segment, position in segment).
std::vector<std::pair<int, int>> tendon_slots(const Robot& robot) {
  std::vector<std::pair<int, int>> out;
  for (std::size_t i = 0; i < robot.segments.size(); ++i)
    for (std::size_t j = 0; j < robot.segments[i].tendons.size(); ++j)
      out.emplace_back(static_cast<int>(i), static_cast<int>(j));
  return out;
}

void scale_tendon(TendonSpec& t, double f) {
  t.x *= f;
  t.y *= f;
  for (auto& p : t.routing.positions) p[0] *= f, p[1] *= f;
}

}  // namespace

std::string to_string(CalibrationLoss loss) {
  switch (loss) {
    case CalibrationLoss::None: return "none";
    case CalibrationLoss::Huber: return "huber";
    case CalibrationLoss::Cauchy: return "cauchy";
  }
  return "?";
}

std::vector<CalibrationParameterSpec> parse_calibration_parameters(const std::string& list) {
  std::vector<CalibrationParameterSpec> out;
  std::stringstream in(list);
  std::string entry;
  std::vector<std::string> entries;
  while (std::getline(in, entry, ',')) entries.push_back(entry);
  if (list.empty() || list.back() == ',') entries.push_back("");
  for (const std::string& raw : entries) {
    const std::string e = trim(raw);
    if (e.empty()) throw InputError("--fit", list, "an empty entry: give parameter names separated by commas (" + known_names() + ")");
    std::vector<std::string> parts;
    std::stringstream ps(e);
    std::string part;
    while (std::getline(ps, part, ':')) parts.push_back(part);
    if (e.back() == ':') parts.push_back("");
    if (parts.size() != 1 && parts.size() != 3)
      throw InputError("--fit", e, "expected name or name:LOWER:UPPER");
    std::string name = trim(parts[0]);
    CalibrationParameterSpec spec;
    const auto br = name.find('[');
    if (br != std::string::npos) {
      const std::string idx = name.substr(br + 1);
      char* end = nullptr;
      const long k = std::strtol(idx.c_str(), &end, 10);
      if (idx.empty() || end == idx.c_str() || std::string(end) != "]" || k < 0 || k > 1000000)
        throw InputError("--fit", e, "an index must be a whole number >= 0 in brackets, e.g. segment_length[1]");
      spec.index = static_cast<int>(k);
      name = name.substr(0, br);
    }
    const GroupInfo* g = nullptr;
    for (const GroupInfo& gi : kGroups)
      if (name == gi.name) g = &gi;
    if (!g) throw InputError("--fit", e, "unknown parameter; known: " + known_names());
    if ((g->kind == Kind::YoungsModulus || g->kind == Kind::ShearModulus || g->kind == Kind::FrictionCoefficient) &&
        spec.index >= 0)
      throw InputError("--fit", e, std::string(g->name) + " is one number: it takes no index");
    if ((g->kind == Kind::BaseOffset || g->kind == Kind::BaseRotation) && spec.index > 2)
      throw InputError("--fit", e, "a base-frame component index is 0, 1 or 2");
    spec.name = g->name;
    spec.kind = g->kind;
    if (parts.size() == 3) {
      spec.lower = bound(parts[1], e);
      spec.upper = bound(parts[2], e);
      if (g->positive && ((spec.lower && *spec.lower < 0.0) || (spec.upper && *spec.upper <= 0.0)))
        throw InputError("--fit", e, std::string(g->name) + " is positive: its bounds must not be negative");
      if (spec.lower && spec.upper && !(*spec.lower < *spec.upper))
        throw InputError("--fit", e, "the lower bound must be below the upper bound");
    }
    for (const CalibrationParameterSpec& o : out)
      if (o.kind == spec.kind && (o.index < 0 || spec.index < 0 || o.index == spec.index))
        throw InputError("--fit", e, "given twice");
    out.push_back(spec);
  }
  return out;
}

void CalibrationOptions::validate() const {
  auto positive = [](const char* name, double v) {
    if (!std::isfinite(v) || !(v > 0.0))
      throw InputError(std::string("calibration.") + name, format_value(v), "must be a positive finite number");
  };
  if (parameters.empty()) throw InputError("calibration.parameters", "", "no parameter to fit (give --fit NAME,...)");
  positive("loss_scale", loss_scale);
  positive("position_std", position_std);
  positive("rotation_std", rotation_std);
  positive("function_tolerance", function_tolerance);
  positive("parameter_tolerance", parameter_tolerance);
  positive("gradient_tolerance", gradient_tolerance);
  positive("difference_step", difference_step);
  positive("rank_tolerance", rank_tolerance);
  positive("max_relative_std", max_relative_std);
  if (difference_step >= 0.1) throw InputError("calibration.difference_step", format_value(difference_step), "must be below 0.1");
  if (rank_tolerance >= 1.0) throw InputError("calibration.rank_tolerance", format_value(rank_tolerance), "must be below 1");
  if (max_iterations < 1) throw InputError("calibration.max_iterations", std::to_string(max_iterations), "must be at least 1");
  if (!(solve_function_tolerance >= SolverOptions::kMinFunctionTolerance &&
        solve_function_tolerance <= SolverOptions::kMaxFunctionTolerance))
    throw InputError("calibration.solve_function_tolerance", format_value(solve_function_tolerance),
                     "must be within [" + format_value(SolverOptions::kMinFunctionTolerance) + ", " +
                         format_value(SolverOptions::kMaxFunctionTolerance) + "]");
}

namespace calibration_detail {

bool is_base_parameter(Kind kind) { return kind == Kind::BaseOffset || kind == Kind::BaseRotation; }

std::vector<Parameter> resolve_parameters(const Scene& scene, const std::vector<CalibrationParameterSpec>& specs) {
  const Robot& robot = scene.robot;
  const auto slots = tendon_slots(robot);
  const int segments = static_cast<int>(robot.segments.size());
  const int tendons = static_cast<int>(slots.size());
  std::vector<Parameter> out;
  for (const CalibrationParameterSpec& spec : specs) {
    const GroupInfo& g = info(spec.kind);
    int count = 1;
    std::string what;
    switch (spec.kind) {
      case Kind::SegmentOffsetScale:
      case Kind::SegmentLength:
      case Kind::DiskMass: count = segments, what = "segments"; break;
      case Kind::TendonOffsetScale:
      case Kind::TendonStiffness: count = tendons, what = "tendons"; break;
      case Kind::BaseOffset:
      case Kind::BaseRotation: count = 3, what = "components"; break;
      default: break;
    }
    if (spec.index >= count)
      throw InputError("--fit", spec.name + "[" + std::to_string(spec.index) + "]",
                       "does not exist: the scene's robot has " + std::to_string(count) + " " + what);
    for (int k = 0; k < count; ++k) {
      if (spec.index >= 0 && k != spec.index) continue;
      Parameter p;
      p.kind = spec.kind;
      p.index = k;
      p.unit = g.unit;
      const bool indexed = count > 1 || spec.kind == Kind::BaseOffset || spec.kind == Kind::BaseRotation;
      p.name = spec.name + (indexed ? "[" + std::to_string(k) + "]" : "");
      p.lower = g.positive ? 0.0 : -kInf;
      p.upper = kInf;
      switch (spec.kind) {
        case Kind::YoungsModulus:
          if (robot.backbone.stiffness)
            throw InputError("--fit", spec.name, "the scene gives robot.backbone.stiffness directly: youngs_modulus has no effect");
          p.initial = robot.backbone.youngs_modulus;
          break;
        case Kind::ShearModulus:
          if (robot.backbone.stiffness)
            throw InputError("--fit", spec.name, "the scene gives robot.backbone.stiffness directly: shear_modulus has no effect");
          p.initial = robot.backbone.shear_modulus.value_or(robot.backbone.youngs_modulus /
                                                              (2.0 * (1.0 + robot.backbone.poisson_ratio)));
          break;
        case Kind::SegmentOffsetScale:
        case Kind::TendonOffsetScale: p.initial = 1.0; break;
        case Kind::SegmentLength: p.initial = robot.segments[static_cast<std::size_t>(k)].length; break;
        case Kind::DiskMass: p.initial = robot.segments[static_cast<std::size_t>(k)].disk_mass, p.scale = 1e-3; break;
        case Kind::TendonStiffness: {
          const auto [i, j] = slots[static_cast<std::size_t>(k)];
          const auto& t = robot.segments[static_cast<std::size_t>(i)].tendons[static_cast<std::size_t>(j)];
          if (!t.stiffness)
            throw InputError("robot.segments[" + std::to_string(i) + "].tendons[" + std::to_string(j) + "].stiffness", "",
                             "not set (the tendon is inextensible): give a starting value in the scene to fit tendon_stiffness");
          p.initial = *t.stiffness;
          break;
        }
        case Kind::FrictionCoefficient:
          if (!scene.effects.tendon_friction.coefficients.empty())
            throw InputError("--fit", spec.name,
                             "the scene gives effects.tendon_friction.coefficients per tendon: fit one coefficient by "
                             "giving effects.tendon_friction.coefficient instead");
          p.initial = scene.effects.tendon_friction.coefficient;
          p.scale = 0.1;
          break;
        case Kind::BaseOffset: p.initial = 0.0, p.scale = 1e-2 * robot.total_length(); break;
        case Kind::BaseRotation: p.initial = 0.0, p.scale = 1e-2; break;
      }
      if (p.initial != 0.0) p.scale = std::abs(p.initial);
      if (spec.lower) p.lower = *spec.lower;
      if (spec.upper) p.upper = *spec.upper;
      if (p.initial < p.lower || p.initial > p.upper)
        throw InputError("--fit", p.name + " = " + format_value(p.initial),
                         "the starting value lies outside the bounds [" + format_value(p.lower) + ", " + format_value(p.upper) + "]");
      out.push_back(p);
    }
  }
  return out;
}

Scene apply_parameters(const Scene& scene, const std::vector<Parameter>& params, const Eigen::VectorXd& values) {
  Scene s = scene;
  const auto slots = tendon_slots(s.robot);
  for (std::size_t q = 0; q < params.size(); ++q) {
    const Parameter& p = params[q];
    const double v = values[static_cast<Eigen::Index>(q)];
    const auto k = static_cast<std::size_t>(p.index);
    switch (p.kind) {
      case Kind::YoungsModulus: s.robot.backbone.youngs_modulus = v; break;
      case Kind::ShearModulus: s.robot.backbone.shear_modulus = v; break;
      case Kind::SegmentOffsetScale:
        for (TendonSpec& t : s.robot.segments[k].tendons) scale_tendon(t, v);
        break;
      case Kind::TendonOffsetScale: {
        const auto [i, j] = slots[k];
        scale_tendon(s.robot.segments[static_cast<std::size_t>(i)].tendons[static_cast<std::size_t>(j)], v);
        break;
      }
      case Kind::SegmentLength: s.robot.segments[k].length = v; break;
      case Kind::DiskMass: s.robot.segments[k].disk_mass = v; break;
      case Kind::TendonStiffness: {
        const auto [i, j] = slots[k];
        s.robot.segments[static_cast<std::size_t>(i)].tendons[static_cast<std::size_t>(j)].stiffness = v;
        break;
      }
      case Kind::FrictionCoefficient: s.effects.tendon_friction.coefficient = v; break;
      case Kind::BaseOffset:
      case Kind::BaseRotation: break;
    }
  }
  return s;
}

Frame base_frame(const std::vector<Parameter>& params, const Eigen::VectorXd& values) {
  Vec3 t = Vec3::Zero(), w = Vec3::Zero();
  for (std::size_t q = 0; q < params.size(); ++q) {
    if (params[q].kind == Kind::BaseOffset) t[params[q].index] = values[static_cast<Eigen::Index>(q)];
    if (params[q].kind == Kind::BaseRotation) w[params[q].index] = values[static_cast<Eigen::Index>(q)];
  }
  return Frame{lie::exp_so3(w), t};
}

}  // namespace calibration_detail

}  // namespace tdcr
