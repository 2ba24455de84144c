// The `environment` object of a scene file (docs/contact.md, docs/scene-file.md): obstacles and
// contact settings. Value checks are Environment::validate's; here a key of another obstacle type
// is refused, naming it.
#include <algorithm>
#include <functional>
#include <string>
#include <vector>

#include "scene_schema.hpp"

namespace tdcr::detail {

namespace {

constexpr const char* kContact = "CCsub, PRB, VC, VCref (contact)";

const Names<Obstacle::Type> kObstacleTypes = {{"plane", Obstacle::Type::Plane},
                                              {"sphere", Obstacle::Type::Sphere},
                                              {"cylinder", Obstacle::Type::Cylinder},
                                              {"capsule", Obstacle::Type::Capsule},
                                              {"lumen", Obstacle::Type::Lumen}};

const Schema<Obstacle>& obstacle_schema() {
  using O = Obstacle;
  using T = O::Type;
  const auto is = [](std::initializer_list<T> types) {
    const std::vector<T> list(types);
    return [list](const O& o) { return std::find(list.begin(), list.end(), o.type) != list.end(); };
  };
  // A list of points: two axis ends, or a lumen's centreline.
  const auto points = [](const char* key, const char* type, KeyDoc doc, std::size_t exactly,
                         std::function<std::vector<Vec3>(const O&)> get, std::function<void(O&, std::vector<Vec3>)> set,
                         std::function<bool(const O&)> present) {
    return Field<O>{{key, type, doc},
                    [exactly, set](const json& j, const std::string& p, O& o) {
                      require_array(j, p);
                      if (exactly && j.size() != exactly)
                        throw InputError(p, text_of(j), "must list exactly " + std::to_string(exactly) + " points");
                      std::vector<Vec3> v;
                      for (std::size_t i = 0; i < j.size(); ++i) v.push_back(read_vec3(j[i], index_path(p, i)));
                      set(o, std::move(v));
                    },
                    [get](const O& o) {
                      ojson a = ojson::array();
                      for (const Vec3& q : get(o)) a.push_back(vec_json(q));
                      return a;
                    },
                    std::move(present)};
  };
  static const Schema<O> s(
      {
          choice_field("type", &O::type, kObstacleTypes,
                       {"", nullptr,
                        "`\"plane\"`, `\"sphere\"`, `\"cylinder\"` (flat caps), `\"capsule\"` or `\"lumen\"` "
                        "(a tube the robot stays inside)",
                        kContact})
              .required(),
          vec3_field("point", &O::point, {"m", "required (plane)", "plane: a point on it", kContact}).when(is({T::Plane})),
          vec3_field("normal", &O::normal, {"", "required (plane)", "plane: nonzero, pointing to the free side", kContact})
              .when(is({T::Plane})),
          vec3_field("center", &O::center, {"m", "required (sphere)", "sphere: its centre", kContact}).when(is({T::Sphere})),
          number_field("radius", &O::radius,
                       {"m", "required (not plane)", "> 0; sphere, cylinder, capsule: radius; lumen: inner radius", kContact})
              .when(is({T::Sphere, T::Cylinder, T::Capsule, T::Lumen})),
          points("ends", "array of [3] numbers", {"m", "required (cylinder, capsule)", "cylinder, capsule: the two axis end points", kContact}, 2,
                 [](const O& o) { return std::vector<Vec3>{o.ends[0], o.ends[1]}; },
                 [](O& o, std::vector<Vec3> v) { o.ends[0] = v[0], o.ends[1] = v[1]; }, is({T::Cylinder, T::Capsule})),
          points("centreline", "array of [3] numbers",
                 {"m", "required (lumen)", "lumen: at least 2 points, the tube's axis (open at both ends)", kContact}, 0,
                 [](const O& o) { return o.centreline; }, [](O& o, std::vector<Vec3> v) { o.centreline = std::move(v); },
                 is({T::Lumen})),
      },
      {},
      [](const JsonObject& o, const O& v) {
        const auto need = [&](const char* key, std::initializer_list<T> types) {
          const bool applies = std::find(types.begin(), types.end(), v.type) != types.end();
          if (applies)
            o.at(key);  // throws "is required"
          else if (o.has(key))
            throw InputError(o.path(key), text_of(o.at(key)),
                             "does not apply to an obstacle of type " + text_of(o.at("type")));
        };
        need("point", {T::Plane});
        need("normal", {T::Plane});
        need("center", {T::Sphere});
        need("radius", {T::Sphere, T::Cylinder, T::Capsule, T::Lumen});
        need("ends", {T::Cylinder, T::Capsule});
        need("centreline", {T::Lumen});
      });
  return s;
}

const Schema<ContactSettings>& contact_schema() {
  static const Schema<ContactSettings> s({
      number_field("stiffness", &ContactSettings::stiffness,
                   {"N/m", "`0` (rigid)",
                    ">= 0; compliant contact: force = stiffness x penetration; 0: rigid (gap >= 0, force >= 0, "
                    "complementary)",
                    kContact}),
  });
  return s;
}

}  // namespace

const Schema<Environment>& environment_schema() {
  using E = Environment;
  static const Schema<E> s({
      objects_field("obstacles", &E::obstacles, obstacle_schema(), "i", nullptr,
                    {"", "none", "rigid primitives in the base frame; see [environment.obstacles](#scene_obstacles)",
                     kContact})
          .own_table(),
      object_field("contact", &E::contact, contact_schema(), {"", "rigid", "the key below", kContact}),
  });
  return s;
}

}  // namespace tdcr::detail
