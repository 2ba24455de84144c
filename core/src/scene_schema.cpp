// The scene-file field table: every key of a scene file, once, with how it is read and written
// and its row of the reference (docs/scene-file.md, checked by test_scene_io). Value checks
// (ranges, list lengths) are the structs' validate() functions; the constraint texts here
// describe them. One bound is the scene file's own: the disks of a robot (kMaxDisks), so that a
// file cannot ask for a robot no model solves in memory. Model names are the models layer's
// (tdcr::validate_scene); core only checks that `model` is a string. The `solver` object has a
// file of its own (scene_solver_schema.cpp).
#include "scene_schema.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace tdcr::detail {

namespace {

const Names<Actuation::DisplacementConvention> kConventions = {
    {"at_base", Actuation::DisplacementConvention::AtBase},
    {"per_segment", Actuation::DisplacementConvention::PerSegment}};
const Names<DiskNormalForce> kDiskNormalForce = {{"removed", DiskNormalForce::Removed},
                                                 {"kept", DiskNormalForce::Kept}};
const Names<TendonPath> kTendonPath = {{"fully_constrained", TendonPath::FullyConstrained},
                                       {"partially_constrained", TendonPath::PartiallyConstrained}};
const Names<TendonFriction::Motion> kMotion = {{"pulling", TendonFriction::Motion::Pulling},
                                              {"releasing", TendonFriction::Motion::Releasing}};
const Names<TendonRoutingSpec::Type> kRoutingTypes = {{"straight", TendonRoutingSpec::Type::Straight},
                                                      {"helical", TendonRoutingSpec::Type::Helical},
                                                      {"points", TendonRoutingSpec::Type::Points}};

// Who honours a key (the reference's last column).
constexpr const char* kAll = "all";
constexpr const char* kStatic = "CCsub, PRB, VC, VCref";
constexpr const char* kGravity = "CCsub, PRB, VC, VCref (gravity)";
constexpr const char* kContact = "CCsub, PRB, VC, VCref (contact)";

const Schema<BackboneStiffness>& stiffness_schema() {
  using S = BackboneStiffness;
  static const Schema<S> s({
      number_field("EI", &S::EI, {"N m^2", nullptr, "> 0", kAll}).required(),
      number_field("GJ", &S::GJ, {"N m^2", nullptr, "> 0", kStatic}).required(),
      number_field("EA", &S::EA, {"N", nullptr, "> 0", "every model (see `shear_extension`)"}).required(),
      number_field("GA", &S::GA, {"N", nullptr, "> 0", "VC, VCref (see `shear_extension`)"}).required(),
  });
  return s;
}

const Schema<Backbone>& backbone_schema() {
  using B = Backbone;
  const auto material = [](const B& b) { return !b.stiffness; };
  constexpr const char* kGivenByStiffness =
      "the material and section are given by \"stiffness\"; give one or the other";
  static const Schema<B> s(
      {
          number_field("youngs_modulus", &B::youngs_modulus, {"Pa", nullptr, "> 0; not with `stiffness`", kAll})
              .when(material),
          number_field("poisson_ratio", &B::poisson_ratio,
                       {"", nullptr, "in (-1, 0.5); not with `shear_modulus` or `stiffness`",
                        "CCsub, PRB, VC, VCref (through G)"})
              .when([](const B& b) { return !b.stiffness && !b.shear_modulus; }),
          optional_number_field("shear_modulus", &B::shear_modulus,
                                {"Pa", "E / (2 (1 + nu))", "> 0; not with `poisson_ratio` or `stiffness`", kStatic})
              .when([](const B& b) { return !b.stiffness && b.shear_modulus; }),
          number_field("outer_radius", &B::outer_radius, {"m", nullptr, "> 0; not with `stiffness`", kAll})
              .when(material),
          number_field("inner_radius", &B::inner_radius,
                       {"m", "`0` (solid)", "0 <= value < `outer_radius`; not with `stiffness`", kAll})
              .when(material),
          number_field("density", &B::density,
                       {"kg/m^3", nullptr, ">= 0; not with `mass_per_length` or `stiffness`", kGravity})
              .when([](const B& b) { return !b.stiffness && !b.mass_per_length; }),
          optional_number_field("mass_per_length", &B::mass_per_length,
                                {"kg/m", "density times area", ">= 0; not with `density`", kGravity}),
          optional_object_field("stiffness", &B::stiffness, stiffness_schema(),
                                {"", "from the material",
                                 "all four keys below; excludes the material and radii keys and `density`", kAll}),
      },
      {
          {"stiffness", "youngs_modulus", kGivenByStiffness},
          {"stiffness", "poisson_ratio", kGivenByStiffness},
          {"stiffness", "shear_modulus", kGivenByStiffness},
          {"stiffness", "outer_radius", kGivenByStiffness},
          {"stiffness", "inner_radius", kGivenByStiffness},
          {"stiffness", "density",
           "with \"stiffness\" the section area is unknown; give \"mass_per_length\" instead"},
          {"poisson_ratio", "shear_modulus", "give either poisson_ratio or shear_modulus, not both"},
          {"density", "mass_per_length", "give either density or mass_per_length, not both"},
      });
  return s;
}

const Schema<TendonRoutingSpec>& routing_schema() {
  using R = TendonRoutingSpec;
  constexpr const char* kRouted = "CCsub, PRB, VC, VCref (CC: straight only)";
  const auto is = [](R::Type t) { return [t](const R& r) { return r.type == t; }; };
  // A list of (x, y) pairs.
  Field<R> positions{{"positions", "array of [2] numbers",
                      {"m", nullptr,
                       "one (x, y) per disk the tendon passes after the base disk (the base hole is the "
                       "tendon's `x`, `y`), each finite and at least 1e-9 m from the axis; only with "
                       "`\"points\"`",
                       kRouted}},
                     [](const json& j, const std::string& p, R& r) {
                       require_array(j, p);
                       r.positions.clear();
                       for (std::size_t i = 0; i < j.size(); ++i) {
                         const std::vector<double> q = read_numbers(j[i], index_path(p, i), 2);
                         r.positions.push_back({q[0], q[1]});
                       }
                     },
                     [](const R& r) {
                       ojson a = ojson::array();
                       for (const auto& q : r.positions) a.push_back(numbers_json({q[0], q[1]}));
                       return a;
                     },
                     is(R::Type::Points)};
  static const Schema<R> s(
      {
          choice_field("type", &R::type, kRoutingTypes,
                       {"", nullptr,
                        "`\"straight\"` (parallel to the backbone), `\"helical\"` (radius kept, angle "
                        "advancing linearly from the base to the end disk) or `\"points\"` (a hole position "
                        "per disk)",
                        kRouted})
              .required(),
          number_field("turns", &R::turns,
                       {"turns", nullptr, "finite (the sign sets the direction); required with `\"helical\"`, only there",
                        kRouted})
              .when(is(R::Type::Helical)),
          std::move(positions),
      },
      {},
      [](const JsonObject& o, const R& r) {
        const auto only = [&](const char* key, R::Type t, const char* name) {
          if (r.type == t)
            o.at(key);  // throws "is required"
          else if (o.has(key))
            throw InputError(o.path(key), text_of(o.at(key)), std::string("applies to \"") + name + "\" routing only");
        };
        only("turns", R::Type::Helical, "helical");
        only("positions", R::Type::Points, "points");
      });
  return s;
}

const Schema<TendonSpec>& tendon_schema() {
  static const Schema<TendonSpec> s({
      number_field("x", &TendonSpec::x, {"m", nullptr, "finite", kAll}).required(),
      number_field("y", &TendonSpec::y, {"m", nullptr, "finite; (x, y) at least 1e-9 m from the axis", kAll})
          .required(),
      optional_number_field("stiffness", &TendonSpec::stiffness,
                            {"N", "absent: inextensible",
                             "> 0; axial stiffness EA: with displacement input T = EA / L_free max(0, stretch), "
                             "L_free the tendon's length from the base to its end disk in the straight robot",
                             "CCsub, PRB, VC, VCref (displacement input)"}),
      object_field("routing", &TendonSpec::routing, routing_schema(),
                   {"", "`{\"type\": \"straight\"}`", "the keys below", "CCsub, PRB, VC, VCref (CC: straight only)"})
          .when([](const TendonSpec& t) { return t.routing.type != TendonRoutingSpec::Type::Straight; }),
  });
  return s;
}

// Most disks of a scene file's robot, all segments together: the VCref scaling benchmark's
// largest robot (bench_vcref: the paper robot at 100000 disks per segment, 22.8 s and 4.2 GB with
// the default options, docs/benchmarks.md) with room to spare. More is not a robot but a memory
// sink: VCref takes about 24 KB per disk, and at 1e8 disks in one segment every model ended in
// std::bad_alloc (`tdcr solve` on examples/paper_robot_vc.json with "disks" changed, 2026-11-26).
// (A loading path through many disks is costly well below this bound: 4 segments of 100 disks
// under examples/paper_robot_tip_force.json's tip force take 3-18 s with CCsub, PRB and VCref.)
constexpr int kMaxDisks = 250000;

const Schema<Segment>& segment_schema() {
  using S = Segment;
  static const std::string disks = ">= 1; at most " + std::to_string(kMaxDisks) + " in all segments together";
  static const Schema<S> s({
      number_field("length", &S::length, {"m", nullptr, "> 0", kAll}).required(),
      integer_field("disks", &S::disks, {"", nullptr, disks.c_str(), kAll}).required(),
      objects_field("tendons", &S::tendons, tendon_schema(), "k", nullptr,
                    {"", nullptr, "may be empty (a passive segment)", kAll})
          .required(),
      number_field("disk_mass", &S::disk_mass, {"kg", nullptr, ">= 0", kGravity}),
      number_field("disk_radius", &S::disk_radius,
                   {"m", nullptr, ">= 0; the disks' contact surface (0: only the backbone touches obstacles)",
                    kContact}),
  });
  return s;
}

const Schema<Robot>& robot_schema() {
  static const Schema<Robot> s(
      {
          object_field("backbone", &Robot::backbone, backbone_schema(),
                       {"", "the paper's rod", "see [robot.backbone](#scene_backbone)", kAll})
              .own_table(),
          objects_field("segments", &Robot::segments, segment_schema(), "i", "segment",
                        {"", nullptr, "at least one; see [robot.segments](#scene_segments)", kAll})
              .required()
              .own_table(),
      },
      {},
      // The disk bound (kMaxDisks), reported at the segment that crosses it.
      [](const JsonObject& o, const Robot& r) {
        long long total = 0;
        for (std::size_t i = 0; i < r.segments.size(); ++i) {
          const int n = r.segments[i].disks;
          total += std::max(n, 0);  // below 1: Robot::validate's to report
          if (total > kMaxDisks)
            throw InputError(index_path(o.path("segments"), i) + ".disks", std::to_string(n),
                             "a robot has at most " + std::to_string(kMaxDisks) +
                                 " disks in all segments together (this segment brings it to " +
                                 std::to_string(total) + ")");
        }
      });
  return s;
}

// An actuation list whose entries may be null (mixed input: the other list gives that tendon);
// null is read as NaN.
std::vector<double> read_values(const json& j, const std::string& p) {
  require_array(j, p);
  std::vector<double> v;
  for (std::size_t i = 0; i < j.size(); ++i)
    v.push_back(j[i].is_null() ? std::numeric_limits<double>::quiet_NaN() : read_number(j[i], index_path(p, i)));
  return v;
}

// The values of `kind` (null where a tendon is given the other way).
ojson values_json(const Actuation& a, Actuation::Kind kind) {
  std::vector<double> v = a.values;
  for (std::size_t k = 0; k < v.size(); ++k)
    if (a.kind_of(k) != kind) v[k] = std::numeric_limits<double>::quiet_NaN();
  return numbers_json(v);
}

// Mixed input: `displacements` read after `tensions` (held in a.values, NaN where null); each
// tendon must be given by exactly one of the lists.
void merge_displacements(const json& j, const std::string& p, const std::vector<double>& d, Actuation& a) {
  using K = Actuation::Kind;
  if (d.size() != a.values.size())
    throw InputError(p, text_of(j), "with \"tensions\" too, must list one entry per tendon as \"tensions\" does (" +
                                        std::to_string(a.values.size()) + ")");
  a.kinds.assign(d.size(), K::Tensions);
  bool any_tension = false, any_displacement = false;
  for (std::size_t k = 0; k < d.size(); ++k) {
    const bool t = std::isfinite(a.values[k]), x = std::isfinite(d[k]);
    if (t == x)
      throw InputError(p, text_of(j),
                       "tendon " + std::to_string(k) + (t ? " is given both" : " is given neither") +
                           " a tension and a displacement (mixed input: null in one list, a number in the other)");
    if (x) a.values[k] = d[k], a.kinds[k] = K::Displacements;
    any_tension = any_tension || t;
    any_displacement = any_displacement || x;
  }
  a.kind = any_displacement ? K::Displacements : K::Tensions;
  if (!(any_tension && any_displacement)) a.kinds.clear();  // one kind after all
}

const Schema<Actuation>& actuation_schema() {
  using A = Actuation;
  using K = A::Kind;
  // Both lists fill Actuation::values; with both (mixed input) each tendon is a number in one
  // list and null in the other. `tensions` is read first.
  static const Schema<A> s(
      {
          {{"tensions", "array of numbers",
            {"N", "", "one per tendon; each finite and >= 0, or null where `displacements` gives the tendon", kAll}},
           [](const json& j, const std::string& p, A& a) {
             a.kind = K::Tensions;
             a.values = read_values(j, p);
           },
           [](const A& a) { return values_json(a, K::Tensions); },
           [](const A& a) { return a.kind == K::Tensions || a.mixed(); }},
          {{"displacements", "array of numbers",
            {"m", "",
             "one per tendon, positive when pulled; each finite, or null where `tensions` gives the tendon "
             "(mixed input). A tendon cannot push: commanded below its path's pull it goes slack (T = 0). "
             "Solved with the tensions of these tendons as unknowns (docs/models.md, \"Displacement input\")",
             "CC (kinematic; every tendon by displacement); CCsub, PRB, VC, VCref (also mixed)"}},
           [](const json& j, const std::string& p, A& a) {
             const std::vector<double> d = read_values(j, p);
             if (!a.values.empty()) return merge_displacements(j, p, d, a);
             for (std::size_t k = 0; k < d.size(); ++k)
               if (!std::isfinite(d[k]))
                 throw InputError(index_path(p, k), "null", "must be a number (null only with \"tensions\" too)");
             a.kind = K::Displacements;
             a.values = d;
           },
           [](const A& a) { return values_json(a, K::Displacements); },
           [](const A& a) { return a.kind == K::Displacements; }},
          choice_field("displacement_convention", &A::convention, kConventions,
                       {"", "`\"at_base\"`", "`\"at_base\"` or `\"per_segment\"`; only with `displacements`",
                        "CC (input); all (reported displacements)"})
              .when([](const A& a) { return a.kind == K::Displacements; }),
      },
      {},
      [](const JsonObject& o, const A& a) {
        if (!o.has("tensions") && !o.has("displacements"))
          throw InputError(o.path(), text_of(o.value()), "must give either \"tensions\" or \"displacements\"");
        if (o.has("displacement_convention") && !o.has("displacements"))
          throw InputError(o.path("displacement_convention"), text_of(o.at("displacement_convention")),
                           "applies to displacements only, not to tensions");
        if (o.has("displacements")) return;
        for (std::size_t k = 0; k < a.values.size(); ++k)
          if (!std::isfinite(a.values[k]))
            throw InputError(index_path(o.path("tensions"), k), "null",
                             "must be a number (null only with \"displacements\" too)");
      });
  return s;
}

const Schema<Loads>& loads_schema() {
  static const Schema<Loads> s({
      vec3_field("tip_force", &Loads::tip_force, {"N", nullptr, "finite", kStatic}),
      vec3_field("tip_moment", &Loads::tip_moment, {"N m", nullptr, "finite", kStatic}),
      vec3_field("gravity", &Loads::gravity, {"m/s^2", nullptr, "finite", kStatic}),
  });
  return s;
}

const Schema<PrbParameters>& prb_schema() {
  using P = PrbParameters;
  static const Schema<P> s({
      numbers_field("gamma", &P::gamma, {"", "Table 1 / 0.999", "link length factors gamma_0..3, each > 0", "PRB"}),
      numbers_field("k_theta", &P::k_theta,
                    {"", nullptr, "spring factors K_Theta_1..3 (k_q = K_Theta_q EI / l, Eq. 49), each > 0", "PRB"}),
  });
  return s;
}

constexpr const char* kFriction = "CCsub, PRB, VC, VCref (CC refuses mu > 0)";

const Schema<TendonFriction>& friction_schema() {
  using F = TendonFriction;
  static const Schema<F> s({
      number_field("coefficient", &F::coefficient,
                   {"", "`0` (off)", "friction coefficient mu of every tendon; finite, >= 0", kFriction}),
      Field<F>{{"coefficients", "array of numbers",
                {"", "none", "one mu per tendon (global order), each finite and >= 0; overrides `coefficient`",
                 kFriction}},
               [](const json& j, const std::string& p, F& f) { f.coefficients = read_numbers(j, p); },
               [](const F& f) { return numbers_json(f.coefficients); },
               [](const F& f) { return !f.coefficients.empty(); }},
      choice_field("motion", &F::motion, kMotion,
                   {"", "`\"pulling\"`",
                    "`\"pulling\"`: tendons slide towards the actuator, tension drops away from the base by "
                    "exp(-mu theta); `\"releasing\"`: it rises by exp(+mu theta)",
                    kFriction}),
  });
  return s;
}

const Schema<Effects>& effects_schema() {
  using E = Effects;
  static const Schema<E> s({
      boolean_field("shear_extension", &E::shear_extension,
                    {"", nullptr,
                     "`true`: Cosserat rod with shear and extension; `false`: inextensible, unshearable "
                     "(Kirchhoff) rod",
                     "VC, VCref; CC with tension input (axial strain - sum T / EA per segment); CCsub and "
                     "PRB: each subsegment shortened by the tensions of the tendons through it over EA (its "
                     "bend and twist unchanged). `false` reproduces the paper's CCsub and PRB."}),
      choice_field("disk_normal_force", &E::disk_normal_force, kDiskNormalForce,
                   {"", nullptr,
                    "`\"kept\"`: a frictionless hole, one tension on both sides of a disk the tendon passes "
                    "through, the disk takes the full force of Eq. 32-33 (the force balance of the tendon in "
                    "the hole, docs/models.md; VCref then converges to VC as the disks grow, helical routing "
                    "included); `\"removed\"`: the paper's Eq. 58, the component along the disk normal "
                    "dropped (robot and tendons then miss that force, and VCref levels off away from VC under "
                    "loads and on helical robots; the paper's case study)",
                    "CCsub, PRB, VCref (VC and CC have no discrete disk forces)"}),
      boolean_field("kink_forces", &E::kink_forces,
                    {"", nullptr,
                     "`true`: a tensioned tendon passing a disk where the strains jump (segment ends "
                     "under a tip wrench, disk weights) pulls with its kink force T (t+ - t-); `false`: "
                     "the paper code's formulation, which omits it (global balance then fails where "
                     "torsion or shear jumps)",
                     "VC"}),
      choice_field("tendon_path", &E::tendon_path, kTendonPath,
                   {"", nullptr,
                    "`\"fully_constrained\"`: tendons parallel to the backbone (Eq. 14-18); "
                    "`\"partially_constrained\"`: straight chords between disks (Eq. 20-23)",
                    "CC (displacement input and reported displacements)"}),
      object_field("prb", &E::prb, prb_schema(), {"", "Table 1", "the two keys below", "PRB"}),
      object_field("tendon_friction", &E::tendon_friction, friction_schema(),
                   {"", "off",
                    "capstan friction at the disk holes (VC: along the tendon path); the keys below (docs/models.md)",
                    kFriction})
          .when([](const E& e) {
            const TendonFriction& f = e.tendon_friction;
            return f.coefficient != 0.0 || !f.coefficients.empty() || f.motion != TendonFriction::Motion::Pulling;
          }),
  });
  return s;
}


// --- Robots that move: `dynamics` and `timeline` (tdcr/models/dynamics.hpp). ---
const Names<TimeScheme> kTimeSchemes = {{"bdf_alpha", TimeScheme::BdfAlpha},
                                        {"implicit_midpoint", TimeScheme::ImplicitMidpoint}};
constexpr const char* kDynamics = "`tdcr simulate` (CCsub, PRB; VC, VCref when their dynamics exist)";

const Schema<DynamicsSettings>& dynamics_schema() {
  using D = DynamicsSettings;
  static const Schema<D> s({
      number_field("bending_damping_time", &D::bending_damping_time,
                   {"s", nullptr, "Kelvin-Voigt retardation time of bending and torsion, >= 0 (0: undamped)", kDynamics}),
      number_field("shear_damping_time", &D::shear_damping_time,
                   {"s", nullptr, "the same for shear and extension, >= 0", "VC, VCref (CCsub's and PRB's axial compression follows the tensions at once: it has no mass "
                   "or damping of its own)"}),
      number_field("air_drag", &D::air_drag,
                   {"N s^2/m^3", nullptr, "quadratic drag per length, f = -air_drag norm(v) v; >= 0", kDynamics}),
      choice_field("scheme", &D::scheme, kTimeSchemes,
                   {"", nullptr, "`\"bdf_alpha\"` or `\"implicit_midpoint\"`", "VC, VCref (CCsub, PRB: CVODE BDF)"}),
      number_field("alpha", &D::alpha, {"", nullptr, "BDF-alpha parameter in [-0.5, 0]", "VC, VCref"}),
  });
  return s;
}

const std::vector<const char*> kTimelineKeys = {"t", "actuation", "loads"};

// `timeline`: read after `actuation` and `loads`; an entry without one of them keeps the
// previous entry's (the first: the scene's).
Field<Scene> timeline_field() {
  Field<Scene> f{{"timeline", "array",
                  {"", "none (static scene)",
                   "entries `{\"t\": s, \"actuation\": {...}, \"loads\": {...}}` with t strictly increasing; "
                   "inputs linear between entries, an entry without `actuation` or `loads` keeps the previous "
                   "one's; the simulation starts at rest on the static answer of the first entry",
                   kDynamics}},
                 [](const json& j, const std::string& p, Scene& sc) {
                   require_array(j, p);
                   sc.timeline.entries.clear();
                   ModelInput prev = sc.input();
                   for (std::size_t i = 0; i < j.size(); ++i) {
                     const JsonObject o(j[i], index_path(p, i), kTimelineKeys);
                     TimelineEntry e;
                     e.t = read_number(o.at("t"), o.path("t"));
                     e.input = prev;
                     if (o.has("actuation")) e.input.actuation = actuation_schema().read(o.at("actuation"), o.path("actuation"));
                     if (o.has("loads")) e.input.loads = loads_schema().read(o.at("loads"), o.path("loads"));
                     prev = e.input;
                     sc.timeline.entries.push_back(e);
                   }
                 },
                 [](const Scene& sc) {
                   ojson a = ojson::array();
                   for (const TimelineEntry& e : sc.timeline.entries) {
                     ojson o = ojson::object();
                     o["t"] = number(e.t);
                     o["actuation"] = actuation_schema().write(e.input.actuation);
                     o["loads"] = loads_schema().write(e.input.loads);
                     a.push_back(o);
                   }
                   return a;
                 },
                 [](const Scene& sc) { return !sc.timeline.entries.empty(); }};
  return f;
}
// --- end of the dynamics keys.
}  // namespace

const Schema<Scene>& scene_schema() {
  static const Schema<Scene> s({
      note_field<Scene>("description", {"", "none", "any text; ignored", "(for the reader)"}),
      object_field("robot", &Scene::robot, robot_schema(), {"", nullptr, "see [robot](#scene_robot)", kAll})
          .required()
          .own_table(),
      object_field("actuation", &Scene::actuation, actuation_schema(),
                   {"", nullptr, "see [actuation](#scene_actuation)", kAll})
          .required()
          .own_table(),
      object_field("loads", &Scene::loads, loads_schema(), {"", "no loads", "see [loads](#scene_loads)", kStatic})
          .own_table(),
      object_field("effects", &Scene::effects, effects_schema(),
                   {"", "the paper code's", "see [effects](#scene_effects)", "see the table"})
          .own_table(),
      object_field("environment", &Scene::environment, environment_schema(),
                   {"", "no obstacles", "see [environment](#scene_environment)", kContact})
          .when([](const Scene& sc) { return !sc.environment.obstacles.empty() || sc.environment.contact.stiffness != 0.0; })
          .own_table(),
      string_field("model", &Scene::model,
                   {"", nullptr,
                    "a model name of the registry (`tdcr::model_names()`) or `\"auto\"`; checked by "
                    "`tdcr::validate_scene`",
                    ""}),
      object_field("solver", &Scene::solver, solver_schema(),
                   {"", "the defaults below", "see [solver](#scene_solver)", "see the table"})
          .own_table(),
      optional_object_field("dynamics", &Scene::dynamics, dynamics_schema(),
                            {"", "none (static scene)", "see [dynamics](#scene_dynamics)", kDynamics})
          .own_table(),
      timeline_field(),
  });
  return s;
}

}  // namespace tdcr::detail
