// tdcr inverse SCENE.json --target x,y,z[,rx,ry,rz] [--model NAME] [--json]: the minimum-norm
// non-negative tensions that put the tip at a target (tdcr::inverse_solve).
#include "inverse_command.hpp"

#include "cli_option.hpp"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <iterator>
#include <memory>
#include <optional>
#include <sstream>

#include <nlohmann/json.hpp>

#include "tdcr/core/error.hpp"
#include "tdcr/core/scene_io.hpp"
#include "tdcr/models/inverse_solve.hpp"
#include "tdcr/models/model_selection.hpp"
#include "tdcr/models/static_model.hpp"

namespace tdcr::cli {

namespace {

struct InverseArgs {
  std::string scene_path;
  std::optional<std::string> model;
  InverseTarget target;
  bool have_target = false;
  bool json = false;
};

/// "x,y,z" (m) or "x,y,z,rx,ry,rz" (m, rotation vector in rad), base frame. Non-finite numbers
/// are passed on: InverseTarget::validate names the component.
InverseTarget parse_target(const std::string& text) {
  std::vector<double> v;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    char* end = nullptr;
    const double x = std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0')
      throw InputError("--target", text, "expected x,y,z (m) or x,y,z,rx,ry,rz (m, rad), numbers separated by commas");
    v.push_back(x);
  }
  if ((v.size() != 3 && v.size() != 6) || text.back() == ',')
    throw InputError("--target", text, "expected 3 numbers x,y,z (m) or 6 numbers x,y,z,rx,ry,rz (m, rad)");
  InverseTarget t;
  t.position = Vec3(v[0], v[1], v[2]);
  if (v.size() == 6) t.rotation = Vec3(v[3], v[4], v[5]);
  return t;
}

InverseArgs parse_args(const std::vector<std::string>& args) {
  InverseArgs out;
  bool have_scene = false;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const auto [name, inline_value] = tdcr_cli::split_option(args[i]);
    auto value = [&, name = name, inline_value = inline_value] {
      return tdcr_cli::option_value(args, i, name, inline_value);
    };
    if (name == "--target") {
      out.target = parse_target(value());
      out.have_target = true;
    } else if (name == "--model") {
      out.model = value();
    } else if (name == "--json" && !inline_value) {
      out.json = true;
    } else if (name.size() > 1 && name[0] == '-') {
      throw InputError("inverse", args[i], "unknown option (see tdcr --help)");
    } else if (have_scene) {
      throw InputError("inverse", args[i], "unexpected argument (one scene file per run)");
    } else {
      out.scene_path = args[i];
      have_scene = true;
    }
  }
  if (!have_scene) throw InputError("inverse", "", "missing scene file (see tdcr --help)");
  if (!out.have_target) throw InputError("--target", "", "missing: give the target as x,y,z or x,y,z,rx,ry,rz");
  return out;
}

Scene load(const std::string& path) {
  if (path != "-") return load_scene(path);
  const std::string text{std::istreambuf_iterator<char>(std::cin), std::istreambuf_iterator<char>()};
  return parse_scene(text, "<stdin>");
}

nlohmann::ordered_json vec(const Vec3& v) { return {v.x(), v.y(), v.z()}; }

void print_json(const InverseResult& r, const InverseTarget& target) {
  // The solve output's keys, `timing` included, as before: the inverse times no repeated solve.
  SolutionJsonOptions o;
  o.extra.push_back({"timing", R"({"repeat": 1, "median_us": 0.0, "min_us": 0.0})"});
  nlohmann::ordered_json j = nlohmann::ordered_json::parse(solution_to_json(r.solution, o));
  nlohmann::ordered_json t = {{"position", vec(target.position)}, {"rotation", nullptr}};
  if (target.rotation) t["rotation"] = vec(*target.rotation);
  j["inverse"] = {{"status", r.converged() ? "converged" : "failed"},
                  {"reason", to_string(r.status) + (r.message.empty() ? "" : ": " + r.message)},
                  {"target", t},
                  {"tensions", r.tensions},
                  {"position_error", r.position_error},
                  {"rotation_error", r.rotation_error},
                  {"iterations", r.iterations},
                  {"forward_solves", r.forward_solves},
                  {"minimum_norm", r.minimum_norm},
                  {"optimality", r.optimality},
                  {"tension_resolution", r.tension_resolution}};
  std::printf("%s\n", j.dump(2).c_str());
}

void print_text(const InverseResult& r) {
  std::printf("model:    %s\n", r.solution.model.c_str());
  std::printf("inverse:  %s\n", r.brief_report().c_str());
  std::printf("tensions (N):        [");
  for (std::size_t k = 0; k < r.tensions.size(); ++k) std::printf("%s%.10g", k ? ", " : "", r.tensions[k]);
  std::printf("]\n");
  if (!r.solution.disk_frames.empty()) {
    const Vec3 p = r.solution.tip().p;
    std::printf("tip position (m):    [%.10g, %.10g, %.10g]\n", p.x(), p.y(), p.z());
  }
}

}  // namespace

std::string inverse_usage() {
  return "       tdcr inverse SCENE.json --target x,y,z[,rx,ry,rz] [--model NAME] [--json]\n";
}

int run_inverse(const std::vector<std::string>& argv) {
  const InverseArgs args = parse_args(argv);
  Scene scene = load(args.scene_path);
  if (args.model) scene.model = *args.model;
  // The iteration varies tensions: it starts from the scene's tensions, or from zero tensions
  // when the scene gives displacements.
  if (scene.actuation.kind != Actuation::Kind::Tensions) {
    scene.actuation.kind = Actuation::Kind::Tensions;
    scene.actuation.values.assign(static_cast<std::size_t>(scene.robot.tendon_count()), 0.0);
  }
  args.target.validate();
  const SceneModel chosen = make_scene_model(scene);
  const std::unique_ptr<StaticModel>& model = chosen.model;
  auto ws = model->make_workspace();
  const InverseResult r = inverse_solve(*model, *ws, scene.input(), args.target, scene.solver);
  if (args.json)
    print_json(r, args.target);
  else
    print_text(r);
  std::fflush(stdout);
  return r.converged() ? 0 : 1;
}

}  // namespace tdcr::cli
