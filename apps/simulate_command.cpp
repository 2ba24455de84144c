// tdcr simulate SCENE.json --duration T [--dt H] [--model M] [-o OUT.csv]: the scene's robot
// from rest on the static answer of its timeline's first entry, moving under the timeline
// (tdcr::simulate); one CSV row per output step.
#include "simulate_command.hpp"

#include "cli_option.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <optional>

#include "tdcr/core/error.hpp"
#include "tdcr/core/lie.hpp"
#include "tdcr/core/scene_io.hpp"
#include "tdcr/models/dynamics.hpp"
#include "tdcr/models/static_model.hpp"

namespace tdcr::cli {

namespace {

double number(const std::string& name, const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !std::isfinite(v)) throw InputError(name, text, "expected a finite number");
  return v;
}

void write_csv(std::ostream& out, const SimulationResult& r, std::size_t tendons) {
  out << "t,tip_x,tip_y,tip_z,rot_x,rot_y,rot_z,status,iterations,kinetic_energy,potential_energy";
  for (std::size_t k = 0; k < tendons; ++k) out << ",T_" << k + 1;
  out << "\n";
  char line[512];
  for (const SimulationStep& s : r.steps) {
    const Vec3 w = lie::log_so3(s.tip.R);
    std::snprintf(line, sizeof line, "%.10g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%s,%d,%.9g,%.9g", s.t, s.tip.p.x(),
                  s.tip.p.y(), s.tip.p.z(), w.x(), w.y(), w.z(), to_string(s.status).c_str(), s.iterations,
                  s.kinetic_energy, s.potential_energy);
    out << line;
    for (std::size_t k = 0; k < tendons; ++k) {
      std::snprintf(line, sizeof line, ",%.12g", k < s.tensions.size() ? s.tensions[k] : NAN);
      out << line;
    }
    out << "\n";
  }
}

}  // namespace

std::string simulate_usage() {
  return "       tdcr simulate SCENE.json --duration T [--dt H] [--model NAME] [-o OUT.csv]\n";
}

int run_simulate(const std::vector<std::string>& args) {
  std::vector<std::string> files;
  SimulationOptions options;
  bool have_duration = false;
  std::optional<std::string> model_name, output;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const auto [name, inline_value] = tdcr_cli::split_option(args[i]);
    auto value = [&, name = name, inline_value = inline_value] {
      return tdcr_cli::option_value(args, i, name, inline_value);
    };
    if (name == "--duration") options.duration = number(name, value()), have_duration = true;
    else if (name == "--dt") options.dt = number(name, value());
    else if (name == "--model") model_name = value();
    else if (name == "-o" || name == "--output") output = value();
    else if (name.size() > 1 && name[0] == '-') throw InputError("simulate", args[i], "unknown option (see tdcr --help)");
    else files.push_back(args[i]);
  }
  if (files.size() != 1) throw InputError("simulate", files.empty() ? "" : files[1], "give one scene file (see tdcr --help)");
  if (!have_duration) throw InputError("--duration", "", "missing: how long to simulate (s)");
  try {
    options.validate();
  } catch (const InputError& e) {
    throw InputError("--" + e.field(), e.value(), "must be a finite time > 0 (s), at most 1e7 steps");
  }
  if (output && output->size() >= 4 && output->compare(output->size() - 4, 4, ".npz") == 0)
    throw InputError("-o", *output, "only CSV output so far (.npz is not supported yet)");
  Scene scene = load_scene(files[0]);
  if (model_name) scene.model = *model_name;
  validate_scene(scene);
  if (scene.model == "auto") throw InputError("model", "auto", "simulate needs a named model (ccsub, prb, vc or vcref)");
  if (!scene.dynamics) throw InputError("dynamics", "", "missing: a scene to simulate gives a \"dynamics\" object");
  Timeline timeline = scene.timeline;
  if (timeline.entries.empty()) timeline.entries.push_back(TimelineEntry{0.0, scene.input()});  // constant input
  const auto model = make_model(parse_model_kind(scene.model), scene);
  const SimulationResult r = simulate(*model, *scene.dynamics, timeline, options, scene.solver);
  if (output) {
    std::ofstream f(*output);
    if (!f) throw InputError("-o", *output, "cannot be written");
    write_csv(f, r, model->robot().tendon_count());
  } else {
    write_csv(std::cout, r, model->robot().tendon_count());
  }
  if (!r.completed) {
    std::fprintf(stderr, "simulation stopped: %s\n", r.message.c_str());
    return 1;
  }
  return 0;
}

}  // namespace tdcr::cli
