// Bindings of the scene description: robot, actuation, loads, effects, solver options, scenes and
// scene files. Enumerations are their scene-file strings ("rk4", "removed", ...), so a scene built
// field by field reads like its JSON file.
#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>
#include <pybind11/stl_bind.h>

#include "bindings.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/core/scene.hpp"
#include "tdcr/core/scene_io.hpp"
#include "tdcr/models/static_model.hpp"

namespace py = pybind11;
using namespace py::literals;

namespace tdcr_python {
namespace {

template <typename E>
using Names = std::vector<std::pair<const char*, E>>;

const Names<tdcr::Actuation::Kind> kActuationKind = {{"tensions", tdcr::Actuation::Kind::Tensions},
                                                     {"displacements", tdcr::Actuation::Kind::Displacements}};
const Names<tdcr::Actuation::DisplacementConvention> kConvention = {
    {"at_base", tdcr::Actuation::DisplacementConvention::AtBase},
    {"per_segment", tdcr::Actuation::DisplacementConvention::PerSegment}};
const Names<tdcr::DiskNormalForce> kDiskNormalForce = {{"removed", tdcr::DiskNormalForce::Removed},
                                                       {"kept", tdcr::DiskNormalForce::Kept}};
const Names<tdcr::TendonPath> kTendonPath = {{"fully_constrained", tdcr::TendonPath::FullyConstrained},
                                             {"partially_constrained", tdcr::TendonPath::PartiallyConstrained}};
const Names<tdcr::TendonRoutingSpec::Type> kRoutingType = {{"straight", tdcr::TendonRoutingSpec::Type::Straight},
                                                           {"helical", tdcr::TendonRoutingSpec::Type::Helical},
                                                           {"points", tdcr::TendonRoutingSpec::Type::Points}};
const Names<tdcr::TendonFriction::Motion> kMotion = {{"pulling", tdcr::TendonFriction::Motion::Pulling},
                                                     {"releasing", tdcr::TendonFriction::Motion::Releasing}};
const Names<tdcr::LinearSolverKind> kLinearSolver = {{"auto", tdcr::LinearSolverKind::Automatic},
                                                     {"dense", tdcr::LinearSolverKind::Dense},
                                                     {"klu", tdcr::LinearSolverKind::SparseKLU}};

template <typename E>
std::string name_of(const Names<E>& names, E e) {
  for (const auto& [n, v] : names)
    if (v == e) return n;
  return "?";
}

/// The enumerator named `text`; InputError naming `field` and listing the choices otherwise.
template <typename E>
E parse_name(const Names<E>& names, const std::string& text, const std::string& field) {
  std::string choices;
  for (const auto& [n, v] : names) {
    if (text == n) return v;
    choices += (choices.empty() ? "\"" : ", \"") + std::string(n) + "\"";
  }
  throw tdcr::InputError(field, "\"" + text + "\"", "must be one of " + choices);
}

/// A getter/setter pair exposing the enumerator member `member` of T as its scene-file string.
template <typename T, typename E>
void enum_property(py::class_<T>& c, const char* name, E T::*member, const Names<E>& names,
                   const std::string& field, const char* doc) {
  c.def_property(
      name, [member, &names](const T& t) { return name_of(names, t.*member); },
      [member, &names, field](T& t, const std::string& v) { t.*member = parse_name(names, v, field); }, doc);
}

/// A fixed-size array member as a list property (the setter checks the length).
template <std::size_t N>
void array_property(py::class_<tdcr::PrbParameters>& c, const char* name, double (tdcr::PrbParameters::*member)[N],
                    const std::string& field) {
  c.def_property(
      name,
      [member](const tdcr::PrbParameters& p) { return std::vector<double>(p.*member, p.*member + N); },
      [member, field](tdcr::PrbParameters& p, const std::vector<double>& v) {
        if (v.size() != N)
          throw tdcr::InputError(field, std::to_string(v.size()) + " values", "needs " + std::to_string(N) + " values");
        for (std::size_t i = 0; i < N; ++i) (p.*member)[i] = v[i];
      });
}

/// A read-only numpy copy of `v` (`a.values[0] = x` raises instead of changing a temporary).
py::array_t<double> readonly_array(const std::vector<double>& v) {
  py::array_t<double> a(static_cast<py::ssize_t>(v.size()), v.data());
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

/// Points routing: an (k, 2) array (or anything numpy reads as one, e.g. a list of pairs) as
/// hole positions; InputError naming `routing.positions` on another shape.
std::vector<std::array<double, 2>> positions_of(const py::object& obj) {
  const auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(obj);
  if (!a) throw tdcr::InputError("routing.positions", py::str(obj), "must be an (k, 2) array of numbers");
  if (a.size() == 0) return {};
  if (a.ndim() != 2 || a.shape(1) != 2)
    throw tdcr::InputError("routing.positions", "shape " + std::string(py::str(a.attr("shape"))),
                           "must have shape (k, 2): one (x, y) per disk after the base disk");
  std::vector<std::array<double, 2>> out(static_cast<std::size_t>(a.shape(0)));
  for (py::ssize_t i = 0; i < a.shape(0); ++i) out[static_cast<std::size_t>(i)] = {a.at(i, 0), a.at(i, 1)};
  return out;
}

py::array_t<double> positions_array(const std::vector<std::array<double, 2>>& p) {
  py::array_t<double> out({static_cast<py::ssize_t>(p.size()), py::ssize_t{2}});
  auto a = out.mutable_unchecked<2>();
  for (std::size_t k = 0; k < p.size(); ++k) a(k, 0) = p[k][0], a(k, 1) = p[k][1];
  return out;
}

/// Actuation::kinds from names, normalised as the scene parser does: a mixed list sets `kind`
/// to displacements; a list of one kind is that kind (and no list).
void set_kinds(tdcr::Actuation& a, const std::vector<std::string>& names) {
  a.kinds.clear();
  for (std::size_t k = 0; k < names.size(); ++k)
    a.kinds.push_back(parse_name(kActuationKind, names[k], "actuation.kinds[" + std::to_string(k) + "]"));
  if (a.kinds.empty()) return;
  const bool one_kind = std::all_of(a.kinds.begin(), a.kinds.end(), [&](auto x) { return x == a.kinds[0]; });
  a.kind = one_kind ? a.kinds[0] : tdcr::Actuation::Kind::Displacements;
  if (one_kind) a.kinds.clear();
}

/// `parent.key` (just `key` at the root), `parent[i]`: the scene file's field paths.
std::string key_path(const std::string& parent, const std::string& key) { return parent.empty() ? key : parent + "." + key; }
std::string index_path(const std::string& parent, std::size_t i) { return parent + "[" + std::to_string(i) + "]"; }

/// repr() of a value for a message, shortened if long.
std::string short_repr(const py::handle& v) {
  std::string r = py::repr(v);
  return r.size() > 80 ? r.substr(0, 77) + "..." : r;
}

/// `v` (a value of a scene dict at `path`) as plain JSON values for json.dumps: numpy scalars
/// become Python numbers and numpy arrays lists (np.float64(2.0), np.array([1.0, 0, 0])); a NaN or
/// an infinity, a key that is not a string, or a value JSON cannot hold is an InputError naming
/// its path, as a scene file's would be (json.dumps would write NaN, which is no JSON number, or
/// refuse numpy values as "not JSON serializable").
py::object plain_json(const py::handle& v, const std::string& path) {
  if (v.is_none() || py::isinstance<py::bool_>(v) || py::isinstance<py::str>(v) || py::isinstance<py::int_>(v))
    return py::reinterpret_borrow<py::object>(v);
  if (py::isinstance<py::float_>(v)) {  // np.float64 too (a float subclass)
    const double x = v.cast<double>();
    if (!std::isfinite(x)) throw tdcr::InputError(path, tdcr::format_value(x), "must be a finite number");
    return py::float_(x);
  }
  if (py::isinstance<py::dict>(v)) {
    py::dict out;
    for (const auto& [key, value] : py::reinterpret_borrow<py::dict>(v)) {
      if (!py::isinstance<py::str>(key))
        throw tdcr::InputError(key_path(path, short_repr(key)), short_repr(key),
                               "a key must be a string (as in a scene file)");
      const std::string k = key.cast<std::string>();
      out[key] = plain_json(value, key_path(path, k));
    }
    return std::move(out);
  }
  if (py::isinstance<py::list>(v) || py::isinstance<py::tuple>(v)) {
    py::list out;
    std::size_t i = 0;
    for (const py::handle& item : v) out.append(plain_json(item, index_path(path, i++)));
    return std::move(out);
  }
  // numpy (imported with the module): an array as nested lists, a scalar (np.float32, np.int64,
  // np.bool_) as its Python value.
  const py::module_ np = py::module_::import("numpy");
  if (py::isinstance(v, np.attr("ndarray"))) return plain_json(v.attr("tolist")(), path);
  if (py::isinstance(v, np.attr("generic"))) return plain_json(v.attr("item")(), path);
  throw tdcr::InputError(path, short_repr(v),
                         "must be a number, a string, a boolean, None, a list or a dict (a JSON value), not " +
                             std::string(py::str(v.get_type().attr("__name__"))));
}

/// A scene dict as scene file text (the values checked and converted by plain_json).
std::string scene_dict_text(const py::object& d) {
  if (!py::isinstance<py::dict>(d))
    throw tdcr::InputError("scene", short_repr(d),
                           "Scene.from_dict needs a dict with the scene file's keys, not " +
                               std::string(py::str(d.get_type().attr("__name__"))));
  return py::str(py::module_::import("json").attr("dumps")(plain_json(d, ""), "allow_nan"_a = false));
}

void bind_robot(py::module_& m) {
  py::class_<tdcr::BackboneStiffness>(m, "BackboneStiffness", "Direct cross-section stiffnesses")
      .def(py::init<>())
      .def(py::init([](double EI, double GJ, double EA, double GA) { return tdcr::BackboneStiffness{EI, GJ, EA, GA}; }),
           "EI"_a, "GJ"_a, "EA"_a, "GA"_a)
      .def_readwrite("EI", &tdcr::BackboneStiffness::EI, "bending stiffness (N m^2)")
      .def_readwrite("GJ", &tdcr::BackboneStiffness::GJ, "torsional stiffness (N m^2)")
      .def_readwrite("EA", &tdcr::BackboneStiffness::EA, "axial stiffness (N)")
      .def_readwrite("GA", &tdcr::BackboneStiffness::GA, "shear stiffness (N)");

  py::class_<tdcr::Backbone>(m, "Backbone", "Backbone material and cross section (SI units)")
      .def(py::init<>())
      .def_readwrite("youngs_modulus", &tdcr::Backbone::youngs_modulus, "E (Pa)")
      .def_readwrite("poisson_ratio", &tdcr::Backbone::poisson_ratio, "nu")
      .def_readwrite("shear_modulus", &tdcr::Backbone::shear_modulus, "G (Pa) or None")
      .def_readwrite("outer_radius", &tdcr::Backbone::outer_radius, "r_o (m)")
      .def_readwrite("inner_radius", &tdcr::Backbone::inner_radius, "r_i (m)")
      .def_readwrite("stiffness", &tdcr::Backbone::stiffness, "BackboneStiffness or None (assign a whole object)")
      .def_readwrite("density", &tdcr::Backbone::density, "kg/m^3 (gravity only)")
      .def_readwrite("mass_per_length", &tdcr::Backbone::mass_per_length, "kg/m or None")
      .def("effective_stiffness", &tdcr::Backbone::effective_stiffness)
      .def("linear_mass", &tdcr::Backbone::linear_mass);

  py::class_<tdcr::TendonRoutingSpec> routing(m, "TendonRoutingSpec",
                                              "How a tendon runs from the base to its end disk (scene key `routing`)");
  routing
      .def(py::init([](const std::string& type, double turns, const py::object& positions) {
             tdcr::TendonRoutingSpec r;
             r.type = parse_name(kRoutingType, type, "routing.type");
             r.turns = turns;
             if (!positions.is_none()) r.positions = positions_of(positions);
             return r;
           }),
           "type"_a = "straight", "turns"_a = 0.0, "positions"_a = py::none())
      .def_readwrite("turns", &tdcr::TendonRoutingSpec::turns, "helical: turns from the base to the end disk")
      .def_property(
          "positions", [](const tdcr::TendonRoutingSpec& r) { return positions_array(r.positions); },
          [](tdcr::TendonRoutingSpec& r, const py::object& p) { r.positions = positions_of(p); },
          "points: (k, 2) hole positions (m) in disks 1..end disk (assign an array or a list of pairs)")
      .def("__repr__", [](const tdcr::TendonRoutingSpec& r) {
        std::string s = "TendonRoutingSpec(type=\"" + name_of(kRoutingType, r.type) + "\"";
        if (r.type == tdcr::TendonRoutingSpec::Type::Helical) s += ", turns=" + tdcr::format_value(r.turns);
        if (r.type == tdcr::TendonRoutingSpec::Type::Points) s += ", positions=<" + std::to_string(r.positions.size()) + " points>";
        return s + ")";
      });
  enum_property(routing, "type", &tdcr::TendonRoutingSpec::type, kRoutingType, "routing.type",
                "'straight', 'helical' or 'points'");

  py::class_<tdcr::TendonSpec>(m, "TendonSpec",
                               "A tendon hole at (x, y) in the disk frame at the base (m), its axial stiffness "
                               "EA (N, None: inextensible) and its routing")
      .def(py::init([](double x, double y, std::optional<double> stiffness,
                       const std::optional<tdcr::TendonRoutingSpec>& routing) {
             tdcr::TendonSpec t{x, y};
             t.stiffness = stiffness;
             if (routing) t.routing = *routing;
             return t;
           }),
           "x"_a = 0.0, "y"_a = 0.0, py::kw_only(), "stiffness"_a = py::none(), "routing"_a = py::none())
      .def_readwrite("x", &tdcr::TendonSpec::x)
      .def_readwrite("y", &tdcr::TendonSpec::y)
      .def_readwrite("stiffness", &tdcr::TendonSpec::stiffness, "axial stiffness EA (N) or None (inextensible)")
      .def_readwrite("routing", &tdcr::TendonSpec::routing, "TendonRoutingSpec (straight unless given)")
      .def("__repr__", [](const tdcr::TendonSpec& t) {
        std::string s = "TendonSpec(x=" + tdcr::format_value(t.x) + ", y=" + tdcr::format_value(t.y);
        if (t.stiffness) s += ", stiffness=" + tdcr::format_value(*t.stiffness);
        if (t.routing.type != tdcr::TendonRoutingSpec::Type::Straight)
          s += ", routing=" + std::string(py::repr(py::cast(t.routing)));
        return s + ")";
      });
  py::bind_vector<std::vector<tdcr::TendonSpec>>(m, "TendonList");
  py::implicitly_convertible<py::list, std::vector<tdcr::TendonSpec>>();

  py::class_<tdcr::Segment>(m, "Segment", "A segment: length (m), disks, the tendons ending at its last disk")
      .def(py::init([](double length, int disks, std::vector<tdcr::TendonSpec> tendons, double disk_mass) {
             return tdcr::Segment{length, disks, std::move(tendons), disk_mass};
           }),
           "length"_a = 0.05, "disks"_a = 10, "tendons"_a = std::vector<tdcr::TendonSpec>{}, "disk_mass"_a = 0.0)
      .def_readwrite("length", &tdcr::Segment::length)
      .def_readwrite("disks", &tdcr::Segment::disks)
      .def_readwrite("tendons", &tdcr::Segment::tendons)
      .def_readwrite("disk_mass", &tdcr::Segment::disk_mass);
  py::bind_vector<std::vector<tdcr::Segment>>(m, "SegmentList");
  py::implicitly_convertible<py::list, std::vector<tdcr::Segment>>();

  py::class_<tdcr::Robot>(m, "Robot", "A backbone and its segments, base to tip")
      .def(py::init([](const tdcr::Backbone& backbone, std::vector<tdcr::Segment> segments) {
             return tdcr::Robot{backbone, std::move(segments)};
           }),
           "backbone"_a = tdcr::Backbone(), "segments"_a = std::vector<tdcr::Segment>{})
      .def_readwrite("backbone", &tdcr::Robot::backbone)
      .def_readwrite("segments", &tdcr::Robot::segments)
      .def("validate", &tdcr::Robot::validate, "raise InputError on an unusable value")
      .def("total_length", &tdcr::Robot::total_length)
      .def("total_disks", &tdcr::Robot::total_disks)
      .def("tendon_count", &tdcr::Robot::tendon_count);
}

void bind_input(py::module_& m) {
  py::class_<tdcr::Actuation> act(m, "Actuation", "Tendon tensions (N) or displacements (m), one per tendon");
  act.def(py::init([](std::vector<double> values, const std::string& kind, const std::string& convention,
                       const std::vector<std::string>& kinds) {
            tdcr::Actuation a;
            a.values = std::move(values);
            a.kind = parse_name(kActuationKind, kind, "actuation");
            a.convention = parse_name(kConvention, convention, "actuation.displacement_convention");
            set_kinds(a, kinds);
            return a;
          }),
          "values"_a = std::vector<double>{}, "kind"_a = "tensions", "convention"_a = "at_base",
          "kinds"_a = std::vector<std::string>{})
      .def_property(
          "values", [](const tdcr::Actuation& a) { return readonly_array(a.values); },
          [](tdcr::Actuation& a, const std::vector<double>& v) { a.values = v; },
          "one value per tendon, N or m (assign a whole list)")
      .def_property(
          "kinds",
          [](const tdcr::Actuation& a) {
            std::vector<std::string> k;
            for (tdcr::Actuation::Kind x : a.kinds) k.push_back(name_of(kActuationKind, x));
            return k;
          },
          &set_kinds,
          "mixed input: 'tensions' or 'displacements' per tendon; [] when every value is `kind` (a list of one "
          "kind is stored as that kind)")
      .def_property_readonly("mixed", &tdcr::Actuation::mixed, "some tendons by tension, others by displacement");
  enum_property(act, "kind", &tdcr::Actuation::kind, kActuationKind, "actuation", "'tensions' or 'displacements'");
  enum_property(act, "convention", &tdcr::Actuation::convention, kConvention, "actuation.displacement_convention",
                "'at_base' or 'per_segment'");

  py::class_<tdcr::Loads>(m, "Loads", "Tip force (N), tip moment (N m), gravity (m/s^2), base frame")
      .def(py::init([](const tdcr::Vec3& f, const tdcr::Vec3& mo, const tdcr::Vec3& g) { return tdcr::Loads{f, mo, g}; }),
           "tip_force"_a = tdcr::Vec3::Zero(), "tip_moment"_a = tdcr::Vec3::Zero(), "gravity"_a = tdcr::Vec3::Zero())
      .def_readwrite("tip_force", &tdcr::Loads::tip_force)
      .def_readwrite("tip_moment", &tdcr::Loads::tip_moment)
      .def_readwrite("gravity", &tdcr::Loads::gravity);

  py::class_<tdcr::ModelInput>(m, "ModelInput", "The per-call input of a model: actuation and loads")
      .def(py::init([](const tdcr::Actuation& a, const tdcr::Loads& l) { return tdcr::ModelInput{a, l, tdcr::Environment{}}; }),
           "actuation"_a = tdcr::Actuation(), "loads"_a = tdcr::Loads())
      .def_readwrite("actuation", &tdcr::ModelInput::actuation)
      .def_readwrite("loads", &tdcr::ModelInput::loads)
      .def("validate", &tdcr::ModelInput::validate, "robot"_a);
}

void bind_effects(py::module_& m) {
  py::class_<tdcr::PrbParameters> prb(m, "PrbParameters", "PRB link length and spring factors (paper Table 1)");
  prb.def(py::init<>());
  array_property<4>(prb, "gamma", &tdcr::PrbParameters::gamma, "effects.prb.gamma");
  array_property<3>(prb, "k_theta", &tdcr::PrbParameters::k_theta, "effects.prb.k_theta");

  py::class_<tdcr::TendonFriction> fr(m, "TendonFriction",
                                     "Capstan friction at the disk holes and the direction of tendon motion");
  fr.def(py::init([](double coefficient, const std::vector<double>& coefficients, const std::string& motion) {
           tdcr::TendonFriction f;
           f.coefficient = coefficient;
           f.coefficients = coefficients;
           f.motion = parse_name(kMotion, motion, "effects.tendon_friction.motion");
           return f;
         }),
         "coefficient"_a = 0.0, "coefficients"_a = std::vector<double>{}, "motion"_a = "pulling")
      .def_readwrite("coefficient", &tdcr::TendonFriction::coefficient, "mu of every tendon (>= 0; 0: off)")
      .def_property(
          "coefficients", [](const tdcr::TendonFriction& f) { return readonly_array(f.coefficients); },
          [](tdcr::TendonFriction& f, const std::vector<double>& v) { f.coefficients = v; },
          "one mu per tendon (global order) overriding `coefficient`, or empty (assign a whole list)")
      .def_property_readonly("on", &tdcr::TendonFriction::on, "some tendon has a nonzero coefficient");
  enum_property(fr, "motion", &tdcr::TendonFriction::motion, kMotion, "effects.tendon_friction.motion",
                "'pulling' (tension drops away from the base) or 'releasing' (it rises)");

  py::class_<tdcr::Effects> eff(m, "Effects", "What a model simulates (defaults: the paper's code)");
  eff.def(py::init<>())
      .def_readwrite("shear_extension", &tdcr::Effects::shear_extension)
      .def_readwrite("kink_forces", &tdcr::Effects::kink_forces)
      .def_readwrite("prb", &tdcr::Effects::prb)
      .def_readwrite("tendon_friction", &tdcr::Effects::tendon_friction, "TendonFriction (off by default)")
      .def("validate", py::overload_cast<>(&tdcr::Effects::validate, py::const_))
      .def("validate", py::overload_cast<const tdcr::Robot&>(&tdcr::Effects::validate, py::const_), py::arg("robot"));
  enum_property(eff, "disk_normal_force", &tdcr::Effects::disk_normal_force, kDiskNormalForce,
                "effects.disk_normal_force", "'removed' (Eq. 58) or 'kept'");
  enum_property(eff, "tendon_path", &tdcr::Effects::tendon_path, kTendonPath, "effects.tendon_path",
                "'fully_constrained' or 'partially_constrained' (CC)");

  py::class_<tdcr::SolverOptions> opt(m, "SolverOptions", "Numerical settings of a solve");
  opt.def(py::init<>())
      .def_readwrite("function_tolerance", &tdcr::SolverOptions::function_tolerance)
      .def_readwrite("step_tolerance", &tdcr::SolverOptions::step_tolerance)
      .def_readwrite("max_iterations", &tdcr::SolverOptions::max_iterations)
      .def_readwrite("rk4_steps", &tdcr::SolverOptions::rk4_steps)
      .def_readwrite("rk4_max_step", &tdcr::SolverOptions::rk4_max_step)
      .def_readwrite("tip_tolerance", &tdcr::SolverOptions::tip_tolerance)
      .def_readwrite("cvode_rtol", &tdcr::SolverOptions::cvode_rtol)
      .def_readwrite("cvode_atol", &tdcr::SolverOptions::cvode_atol)
      .def_readwrite("continuation", &tdcr::SolverOptions::continuation)
      .def_readwrite("max_continuation_steps", &tdcr::SolverOptions::max_continuation_steps)
      .def_readwrite("coarse_loading_path", &tdcr::SolverOptions::coarse_loading_path)
      .def_property(
          "stability",
          [](const tdcr::SolverOptions& o) -> py::object {
            if (o.stability == tdcr::StabilityCheck::Automatic) return py::str("auto");
            return py::bool_(o.stability == tdcr::StabilityCheck::Always);
          },
          [](tdcr::SolverOptions& o, const py::object& v) {
            if (py::isinstance<py::bool_>(v))
              o.stability = v.cast<bool>() ? tdcr::StabilityCheck::Always : tdcr::StabilityCheck::Never;
            else if (py::isinstance<py::str>(v) && v.cast<std::string>() == "auto")
              o.stability = tdcr::StabilityCheck::Automatic;
            else
              throw tdcr::InputError("solver.stability", py::str(py::repr(v)).cast<std::string>(),
                                     "must be 'auto', True or False");
          },
          "'auto' (default: answers reached by a loading path and scenes with external loads), True (every "
          "answer) or False (none)")
      .def_readwrite("differential_kinematics", &tdcr::SolverOptions::differential_kinematics)
      .def_readwrite("reuse_jacobian", &tdcr::SolverOptions::reuse_jacobian)
      .def_readwrite("extrapolate_warm_starts", &tdcr::SolverOptions::extrapolate_warm_starts)
      .def("validate", &tdcr::SolverOptions::validate);
  // Integrator names are core's (tdcr::parse_integrator_kind), as in scene files and the CLI.
  opt.def_property(
      "integrator", [](const tdcr::SolverOptions& o) { return tdcr::to_string(o.integrator); },
      [](tdcr::SolverOptions& o, const std::string& v) {
        o.integrator = tdcr::parse_integrator_kind(v, "solver.integrator");
      },
      "'rk4', 'rk4_fixed' or 'cvode'");
  enum_property(opt, "linear_solver", &tdcr::SolverOptions::linear_solver, kLinearSolver, "solver.linear_solver",
                "'auto', 'dense' or 'klu'");
}

void bind_scene_class(py::module_& m) {
  py::class_<tdcr::Scene>(m, "Scene", "Robot, actuation, loads, effects, model name and solver options")
      .def(py::init<>())
      .def_readwrite("robot", &tdcr::Scene::robot)
      .def_readwrite("actuation", &tdcr::Scene::actuation)
      .def_readwrite("loads", &tdcr::Scene::loads)
      .def_readwrite("effects", &tdcr::Scene::effects)
      .def_readwrite("model", &tdcr::Scene::model)
      .def_readwrite("solver", &tdcr::Scene::solver)
      .def("input", &tdcr::Scene::input, "the ModelInput (actuation and loads)")
      .def("validate", &tdcr::validate_scene, "raise InputError naming the field and value of any unusable entry")
      .def("to_json", &tdcr::scene_to_json, "the scene file text")
      .def("to_dict", [](const tdcr::Scene& s) { return json_loads(tdcr::scene_to_json(s)); })
      .def("copy", [](const tdcr::Scene& s) { return s; })
      .def("__copy__", [](const tdcr::Scene& s) { return s; })
      .def("__deepcopy__", [](const tdcr::Scene& s, py::dict) { return s; })
      .def_static("from_file", &tdcr::load_scene, "path"_a, "read a scene file (InputError on bad input)")
      .def_static("from_json", &tdcr::parse_scene, "text"_a, "source"_a = "<string>")
      .def_static(
          "from_dict", [](const py::object& d) { return tdcr::parse_scene(scene_dict_text(d), "<dict>"); }, "data"_a,
          "parse a dict with the scene file's keys (the same checks and messages as a file); numpy numbers and "
          "arrays are taken as numbers and lists, NaN and infinity are refused naming their field");

  m.def("load_scene", &tdcr::load_scene, "path"_a);
  m.def("parse_scene", &tdcr::parse_scene, "text"_a, "source"_a = "<string>");
  m.def("scene_to_json", &tdcr::scene_to_json, "scene"_a);
}

}  // namespace

void bind_scene(py::module_& m) {
  bind_robot(m);
  bind_input(m);
  bind_effects(m);
  bind_scene_class(m);
}

}  // namespace tdcr_python
