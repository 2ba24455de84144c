// tdcr: the command-line program. Solves a scene file with one of the models and prints the
// result as text or as JSON (the contract of tdcr::solution_to_json); `tdcr inverse` finds the
// tensions for a tip target (inverse_command.cpp).
//
// Exit status: 0 converged, 1 solved but not converged (the result is still printed, status
// "failed"), 2 bad input or usage, 3 internal error.
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <iostream>
#include <iterator>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "calibrate_command.hpp"
#include "cli_option.hpp"
#include "inverse_command.hpp"
#include "plot_command.hpp"
#include "simulate_command.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/core/scene_io.hpp"
#include "tdcr/models/model_registry.hpp"
#include "tdcr/models/model_selection.hpp"
#include "tdcr/models/static_model.hpp"
#include "tdcr/sweep/sweep_run.hpp"

#ifndef TDCR_VERSION
#define TDCR_VERSION "0.1.0"
#endif

namespace {

constexpr int kExitConverged = 0;
constexpr int kExitNotConverged = 1;
constexpr int kExitBadInput = 2;
constexpr int kExitInternal = 3;
constexpr long kMaxRepeat = 1000000;

/// The usage text; the model list comes from the registry.
std::string usage() {
  std::string models;
  for (const tdcr::ModelInfo& m : tdcr::model_registry()) {
    std::string name = m.name;
    name.resize(std::max<std::size_t>(name.size(), 8), ' ');
    models += "  " + name + m.description + "\n";
  }
  return "usage: tdcr solve SCENE.json [--model NAME] [--accuracy FRACTION] [--json] [--repeat N]\n"
         "                             [--integrator rk4|rk4_fixed|cvode] [--tip-tolerance M] [--continuation]\n"
         "                             [--jacobian]\n"
         + tdcr::cli::inverse_usage() + tdcr::cli::calibrate_usage() + tdcr::cli::simulate_usage() +
         "       tdcr sweep SWEEP.json -o OUT.csv [--threads N] [--shard i/N]   (tdcr sweep --help)\n"
         "       tdcr sweep-merge OUT.csv SHARD.csv...\n"
         "       tdcr plot SCENE.json [--model NAME[,NAME...]] -o FILE.png|svg   (tdcr plot --help)\n"
         "       tdcr plot SCENE.json --animate OUT.gif|mp4 [--trajectory TIP.png] [--duration T] [--dt H] [--fps F]\n"
         "       tdcr view SCENE.json [--port P] [--open]   interactive viewer in the browser (tdcr view --help)\n"
         "       tdcr --help | --version\n"
         "\n"
         "Solve the static shape of a tendon-driven continuum robot described by a scene file\n"
         "(see examples/ and docs/). SCENE.json may be '-' to read the scene from standard input.\n"
         "\n"
         "options of solve:\n"
         "  --model NAME          " + tdcr::model_names() + " or auto; overrides the scene's \"model\"\n"
         "  --accuracy FRACTION   with auto: requested tip position accuracy as a fraction of the\n"
         "                        robot length (default 0.01); auto picks the cheapest model\n"
         "                        expected to meet it and prints why\n"
         "  --json                print the result as JSON (model, status, reason, iterations,\n"
         "                        residual_norm, tip, disks, tendon_displacements, contacts with\n"
         "                        obstacles, timing, summary)\n"
         "  --repeat N            solve N times (N >= 1) from the same initial guess and report the\n"
         "                        median and minimum solve time\n"
         "  --integrator NAME     rk4, rk4_fixed or cvode; overrides the scene's solver.integrator\n"
         "  --tip-tolerance M     accuracy of the tip position (m); overrides solver.tip_tolerance\n"
         "  --continuation        if a direct solve fails, ramp actuation and loads (continuation)\n"
         "  --jacobian            also compute the tip Jacobian (d tip pose / d actuation) and the\n"
         "                        tip compliance (d tip pose / d tip wrench); --json prints them\n"
         "\n"
         "tdcr inverse: the non-negative tensions of least norm that put the tip at --target\n"
         "  (x,y,z in m, or x,y,z,rx,ry,rz with the orientation as a rotation vector in rad, base\n"
         "  frame), starting from the scene's tensions; prints the report line and the tensions,\n"
         "  or with --json the solution and an \"inverse\" object (status, target, tensions,\n"
         "  errors, iterations); exit status 1 if the target was not reached (closest pose printed)\n"
         "\n"
         "tdcr calibrate: fit the model's parameters (--fit youngs_modulus,shear_modulus,\n"
         "  segment_offset_scale,tendon_offset_scale,segment_length,disk_mass,tendon_stiffness,\n"
         "  friction_coefficient,base_offset,base_rotation; NAME[i] one of a group, NAME:LO:HI bounds)\n"
         "  to measured shapes (DATA.csv in the sweep CSV's columns); prints the fitted values,\n"
         "  standard errors, correlations and residuals, writes the calibrated scene with -o;\n"
         "  exit status 1 if the fit did not converge\n"
         "\n"
         "tdcr simulate: the robot in motion (CCsub, PRB, VC, VCref) from rest on the static answer of the\n"
         "  scene's first \"timeline\" entry, with its \"dynamics\" (docs/dynamics.md); one CSV row per\n"
         "  output step of --dt (default 1/60 s): t, tip_x, tip_y, tip_z, rot_x, rot_y, rot_z\n"
         "  (rotation vector, rad), status, iterations (CVODE steps of CCsub, PRB; Newton iterations of\n"
         "  VC, VCref), kinetic and potential energy, T_1..T_m (tensions, N; solved for tendons given\n"
         "  by displacement: VC, VCref); -o OUT.npz: NumPy arrays instead (with the disk positions);\n"
         "  a progress bar on a terminal (--quiet: none);\n"
         "  exit status 1 if a step failed (its time, residual and iterations on standard error)\n"
         "\n"
         "models:\n" + models +
         "  auto    the cheapest model expected to meet --accuracy\n"
         "\n"
         "exit status: 0 converged, 1 not converged (result printed with status \"failed\"),\n"
         "             2 bad input or usage, 3 internal error\n";
}

/// A usage error: wrong command line (exit 2).
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct SolveArgs {
  std::string scene_path;
  std::optional<std::string> model;
  std::optional<std::string> integrator;
  std::optional<double> tip_tolerance;
  bool json = false;
  bool continuation = false;
  bool jacobian = false;
  int repeat = 1;
  double accuracy = 0.01;
};

double parse_accuracy(const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !std::isfinite(v) || v <= 0.0 || v >= 1.0)
    throw UsageError("--accuracy: expected a fraction of the robot length in (0, 1) (got '" + text + "')");
  return v;
}

// A number for --tip-tolerance; its range is SolverOptions::validate()'s (solver.tip_tolerance).
double parse_tip_tolerance(const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !std::isfinite(v))
    throw UsageError("--tip-tolerance: expected a number of metres (got '" + text + "')");
  return v;
}

int parse_repeat(const std::string& text) {
  errno = 0;
  char* end = nullptr;
  const long n = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || errno == ERANGE || n < 1 || n > kMaxRepeat)
    throw UsageError("--repeat: expected a whole number from 1 to " + std::to_string(kMaxRepeat) + " (got '" +
                     text + "')");
  return static_cast<int>(n);
}

SolveArgs parse_solve_args(const std::vector<std::string>& args) {
  SolveArgs out;
  bool have_scene = false;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const auto [name, inline_value] = tdcr_cli::split_option(args[i]);
    auto value = [&, name = name, inline_value = inline_value]() -> std::string {
      if (inline_value) return *inline_value;
      if (i + 1 >= args.size()) throw UsageError(name + ": missing argument");
      return args[++i];
    };
    auto no_value = [&, name = name, inline_value = inline_value]() {
      if (inline_value) throw UsageError(name + " takes no argument (got '" + *inline_value + "')");
    };
    if (name == "--model") {
      out.model = value();
    } else if (name == "--accuracy") {
      out.accuracy = parse_accuracy(value());
    } else if (name == "--integrator") {
      out.integrator = value();
    } else if (name == "--tip-tolerance") {
      out.tip_tolerance = parse_tip_tolerance(value());
    } else if (name == "--repeat") {
      out.repeat = parse_repeat(value());
    } else if (name == "--json") {
      no_value();
      out.json = true;
    } else if (name == "--continuation") {
      no_value();
      out.continuation = true;
    } else if (name == "--jacobian") {
      no_value();
      out.jacobian = true;
    } else if (name.size() > 1 && name[0] == '-') {
      throw UsageError("unknown option '" + args[i] + "'");
    } else if (have_scene) {
      throw UsageError("unexpected argument '" + args[i] + "' (one scene file per run)");
    } else {
      out.scene_path = args[i];
      have_scene = true;
    }
  }
  if (!have_scene) throw UsageError("solve: missing scene file");
  return out;
}

tdcr::Scene load(const std::string& path) {
  if (path != "-") return tdcr::load_scene(path);
  const std::string text{std::istreambuf_iterator<char>(std::cin), std::istreambuf_iterator<char>()};
  return tdcr::parse_scene(text, "<stdin>");
}

void apply_overrides(const SolveArgs& args, tdcr::Scene& scene) {
  if (args.model) scene.model = *args.model;
  if (args.integrator) scene.solver.integrator = tdcr::parse_integrator_kind(*args.integrator, "--integrator");
  if (args.tip_tolerance) {
    scene.solver.tip_tolerance = *args.tip_tolerance;
    try {
      scene.solver.validate();
    } catch (const tdcr::InputError& e) {
      throw UsageError(std::string("--tip-tolerance: ") + e.what());
    }
  }
  if (args.continuation) scene.solver.continuation = true;
  if (args.jacobian) scene.solver.differential_kinematics = true;
}

struct Timed {
  tdcr::Solution solution;
  double median_us = 0.0;
  double min_us = 0.0;
};

/// Solves `repeat` times from the same initial guess (no warm start), reusing one workspace.
Timed solve_timed(const tdcr::StaticModel& model, const tdcr::Scene& scene, int repeat) {
  const tdcr::ModelInput input = scene.input();
  auto workspace = model.make_workspace();
  std::vector<double> us;
  us.reserve(static_cast<std::size_t>(repeat));
  Timed out;
  for (int r = 0; r < repeat; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    out.solution = tdcr::solve(model, *workspace, input, scene.solver);
    const auto t1 = std::chrono::steady_clock::now();
    us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
  }
  std::sort(us.begin(), us.end());
  const std::size_t n = us.size();
  out.median_us = n % 2 ? us[n / 2] : 0.5 * (us[n / 2 - 1] + us[n / 2]);
  out.min_us = us.front();
  return out;
}

/// The `timing` member of the JSON output: the solves of --repeat, which only the CLI runs.
std::string timing_json(const Timed& t, int repeat) {
  return nlohmann::ordered_json{{"repeat", repeat}, {"median_us", t.median_us}, {"min_us", t.min_us}}.dump();
}

void print_human(const Timed& t, int repeat) {
  const tdcr::Solution& s = t.solution;
  std::printf("model:  %s\n", s.model.c_str());
  if (!s.model_selection.empty()) std::printf("        %s\n", s.model_selection.c_str());
  std::printf("status: %s\n", s.summary.brief_report().c_str());
  if (s.disk_frames.empty()) {
    std::printf("tip:    not available\n");
  } else {
    const tdcr::Vec3 p = s.tip().p * 1e3;
    const double c = std::clamp(s.tip().R(2, 2), -1.0, 1.0);
    std::printf("tip position (mm):                   [%.6g, %.6g, %.6g]\n", p[0], p[1], p[2]);
    std::printf("tip angle from base z axis (deg):    %.6g\n", std::acos(c) * 180.0 / M_PI);
  }
  if (!s.tendon_slack.empty()) {
    std::printf("tensions (N), displacement input:    [");
    for (std::size_t k = 0; k < s.tensions.size(); ++k)
      std::printf("%s%.6g%s", k ? ", " : "", s.tensions[k], s.tendon_slack[k] ? " (slack)" : "");
    std::printf("]\n");
  }
  for (const tdcr::Contact& c : s.contacts)
    std::printf("contact: obstacle %d, %s at disk %d (s = %.4g mm), force %.6g N along [%.4g, %.4g, %.4g], "
                "point (mm) [%.6g, %.6g, %.6g], gap %.3g m\n",
                c.obstacle, c.disk ? "rim of disk" : "backbone", c.disk_index, c.s * 1e3, c.force, c.normal.x(),
                c.normal.y(), c.normal.z(), c.point.x() * 1e3, c.point.y() * 1e3, c.point.z() * 1e3, c.gap);
  std::printf("solve time (us):                     median %.1f, min %.1f over %d run%s\n", t.median_us,
              t.min_us, repeat, repeat == 1 ? "" : "s");
}

int run_solve(const std::vector<std::string>& argv) {
  const SolveArgs args = parse_solve_args(argv);
  tdcr::Scene scene = load(args.scene_path);
  apply_overrides(args, scene);
  const tdcr::SceneModel chosen = tdcr::make_scene_model(scene, args.accuracy);
  scene.model = chosen.model->name();
  Timed t = solve_timed(*chosen.model, scene, args.repeat);
  t.solution.model_selection = chosen.selection();
  if (args.json) {
    tdcr::SolutionJsonOptions o;
    o.extra.push_back({"timing", timing_json(t, args.repeat)});
    std::printf("%s\n", tdcr::solution_to_json(t.solution, o).c_str());
  } else {
    print_human(t, args.repeat);
  }
  std::fflush(stdout);
  return t.solution.converged() ? kExitConverged : kExitNotConverged;
}

int run(const std::vector<std::string>& args) {
  if (args.empty()) throw UsageError("missing command");
  const std::string& cmd = args[0];
  if (cmd == "--help" || cmd == "-h" || cmd == "help") {
    std::printf("%s", usage().c_str());
    return 0;
  }
  if (cmd == "--version") {
    std::printf("tdcr %s\n", TDCR_VERSION);
    return 0;
  }
  if (cmd == "solve") {
    const std::vector<std::string> rest(args.begin() + 1, args.end());
    if (std::find(rest.begin(), rest.end(), "--help") != rest.end()) {
      std::printf("%s", usage().c_str());
      return 0;
    }
    return run_solve(rest);
  }
  if (cmd == "inverse") {
    const std::vector<std::string> rest(args.begin() + 1, args.end());
    if (std::find(rest.begin(), rest.end(), "--help") != rest.end()) {
      std::printf("%s", usage().c_str());
      return 0;
    }
    return tdcr::cli::run_inverse(rest);
  }
  if (cmd == "calibrate") {
    const std::vector<std::string> rest(args.begin() + 1, args.end());
    if (std::find(rest.begin(), rest.end(), "--help") != rest.end()) {
      std::printf("%s", usage().c_str());
      return 0;
    }
    return tdcr::cli::run_calibrate(rest);
  }
  if (cmd == "simulate") {
    const std::vector<std::string> rest(args.begin() + 1, args.end());
    if (std::find(rest.begin(), rest.end(), "--help") != rest.end()) {
      std::printf("%s", usage().c_str());
      return 0;
    }
    return tdcr::cli::run_simulate(rest);
  }
  if (cmd == "sweep") return tdcr::sweep_command({args.begin() + 1, args.end()});
  if (cmd == "sweep-merge") return tdcr::sweep_merge_command({args.begin() + 1, args.end()});
  if (cmd == "plot") return tdcr_cli::run_plot(std::vector<std::string>(args.begin() + 1, args.end()));
  if (cmd == "view") return tdcr_cli::run_view(std::vector<std::string>(args.begin() + 1, args.end()));
  if (!cmd.empty() && cmd[0] == '-') throw UsageError("unknown option '" + cmd + "'");
  throw UsageError("unknown command '" + cmd + "'");
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(std::vector<std::string>(argv + 1, argv + argc));
  } catch (const UsageError& e) {
    std::fprintf(stderr, "error: %s\n(see tdcr --help)\n", e.what());
    return kExitBadInput;
  } catch (const tdcr::InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "internal error: %s\n", e.what());
    return kExitInternal;
  } catch (...) {
    std::fprintf(stderr, "internal error: unknown exception\n");
    return kExitInternal;
  }
}
