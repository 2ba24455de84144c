// tdcr calibrate SCENE.json DATA.csv --model M --fit NAME[:LO:HI],... [-o OUT.json] [--json]
// [--loss huber|cauchy|none] [--loss-scale S] [--position-std M] [--rotation-std RAD]
// [--max-iterations N] [--cold] [--differences]: the model's parameters fitted to the measurements
// (tdcr::calibrate), the report printed, the calibrated scene written.
#include "calibrate_command.hpp"

#include "cli_option.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <optional>

#include <nlohmann/json.hpp>

#include "tdcr/core/error.hpp"
#include "tdcr/core/lie.hpp"
#include "tdcr/core/scene_io.hpp"
#include "tdcr/models/calibration.hpp"
#include "tdcr/models/static_model.hpp"

namespace tdcr::cli {

namespace {

struct CalibrateArgs {
  std::string scene_path, data_path;
  std::optional<std::string> model, output;
  std::string fit;
  bool json = false;
  CalibrationOptions options;
};

double number(const std::string& name, const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !std::isfinite(v)) throw InputError(name, text, "expected a finite number");
  return v;
}

int whole(const std::string& name, const std::string& text) {
  errno = 0;
  char* end = nullptr;
  const long v = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || errno == ERANGE || v < 1 || v > 100000)
    throw InputError(name, text, "expected a whole number from 1 to 100000");
  return static_cast<int>(v);
}

CalibrateArgs parse_args(const std::vector<std::string>& args) {
  CalibrateArgs out;
  std::vector<std::string> files;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const auto [name, inline_value] = tdcr_cli::split_option(args[i]);
    auto value = [&, name = name, inline_value = inline_value] {
      return tdcr_cli::option_value(args, i, name, inline_value);
    };
    if (name == "--model") out.model = value();
    else if (name == "--fit") out.fit = value();
    else if (name == "-o" || name == "--output") out.output = value();
    else if (name == "--json" && !inline_value) out.json = true;
    else if (name == "--cold" && !inline_value) out.options.warm_start = false;
    else if (name == "--differences" && !inline_value) out.options.jacobian = CalibrationJacobian::Differences;
    else if (name == "--loss") {
      const std::string v = value();
      if (v == "huber") out.options.loss = CalibrationLoss::Huber;
      else if (v == "cauchy") out.options.loss = CalibrationLoss::Cauchy;
      else if (v == "none") out.options.loss = CalibrationLoss::None;
      else throw InputError("--loss", v, "must be huber, cauchy or none");
    } else if (name == "--loss-scale") out.options.loss_scale = number(name, value());
    else if (name == "--position-std") out.options.position_std = number(name, value());
    else if (name == "--rotation-std") out.options.rotation_std = number(name, value());
    else if (name == "--max-iterations") out.options.max_iterations = whole(name, value());
    else if (name.size() > 1 && name[0] == '-') throw InputError("calibrate", args[i], "unknown option (see tdcr --help)");
    else files.push_back(args[i]);
  }
  if (files.size() < 2) throw InputError("calibrate", "", "give a scene file and a data file (see tdcr --help)");
  if (files.size() > 2) throw InputError("calibrate", files[2], "unexpected argument (one scene and one data file)");
  if (out.fit.empty()) throw InputError("--fit", "", "missing: name the parameters to fit, e.g. --fit youngs_modulus,segment_offset_scale");
  out.scene_path = files[0];
  out.data_path = files[1];
  return out;
}

nlohmann::ordered_json stats(const ResidualStatistics& s) {
  return {{"rms_position", s.rms_position}, {"max_position", s.max_position}, {"rms_rotation", s.rms_rotation},
          {"max_rotation", s.max_rotation}, {"rms_standardised", s.rms_standardised}};
}

nlohmann::ordered_json sample(const SampleResidual& r) {
  return {{"solved", r.solved}, {"tip_error", r.tip_error}, {"rotation_error", r.rotation_error},
          {"point_error", r.point_error}, {"standardised", r.standardised}};
}

void print_json(const CalibrationResult& r, const std::optional<std::string>& output) {
  nlohmann::ordered_json j;
  j["model"] = r.scene.model;
  j["status"] = r.converged() ? "converged" : "failed";
  j["reason"] = r.summary.termination + (r.summary.message.empty() ? "" : ": " + r.summary.message);
  j["iterations"] = r.summary.iterations;
  j["forward_solves"] = r.summary.forward_solves;
  j["linearised_answers"] = r.summary.linearised_answers;
  j["time_s"] = r.summary.time_s;
  nlohmann::ordered_json ps = nlohmann::ordered_json::array();
  for (const FittedParameter& p : r.parameters)
    ps.push_back({{"name", p.name}, {"unit", p.unit}, {"initial", p.initial}, {"value", p.value},
                  {"std_error", std::isfinite(p.std_error) ? nlohmann::ordered_json(p.std_error) : nlohmann::ordered_json()},
                  {"lower", std::isfinite(p.lower) ? nlohmann::ordered_json(p.lower) : nlohmann::ordered_json()},
                  {"upper", std::isfinite(p.upper) ? nlohmann::ordered_json(p.upper) : nlohmann::ordered_json()},
                  {"identifiable", p.identifiable}, {"at_bound", p.at_bound}});
  j["parameters"] = ps;
  nlohmann::ordered_json corr = nlohmann::ordered_json::array();
  for (Eigen::Index a = 0; a < r.correlation.rows(); ++a) {
    nlohmann::ordered_json row = nlohmann::ordered_json::array();
    for (Eigen::Index b = 0; b < r.correlation.cols(); ++b)
      row.push_back(std::isfinite(r.correlation(a, b)) ? nlohmann::ordered_json(r.correlation(a, b)) : nlohmann::ordered_json());
    corr.push_back(row);
  }
  j["correlation"] = corr;
  j["singular_values"] = std::vector<double>(r.singular_values.data(), r.singular_values.data() + r.singular_values.size());
  j["non_identifiable"] = r.non_identifiable;
  j["warning"] = r.warning;
  const Vec3 w = lie::log_so3(r.base.R);
  j["base"] = {{"position", {r.base.p.x(), r.base.p.y(), r.base.p.z()}}, {"rotation", {w.x(), w.y(), w.z()}}};
  j["before"] = stats(r.summary.before);
  j["after"] = stats(r.summary.after);
  nlohmann::ordered_json samples = nlohmann::ordered_json::array();
  for (std::size_t i = 0; i < r.residuals_after.size(); ++i)
    samples.push_back({{"line", r.residuals_after[i].line}, {"before", sample(r.residuals_before[i])},
                       {"after", sample(r.residuals_after[i])}});
  j["samples"] = samples;
  j["scene_file"] = output ? nlohmann::ordered_json(*output) : nlohmann::ordered_json();
  std::printf("%s\n", j.dump(2).c_str());
}

void print_text(const CalibrationResult& r, const std::optional<std::string>& output) {
  std::printf("model:        %s\n", r.scene.model.c_str());
  std::printf("calibration:  %s\n", r.summary.brief_report().c_str());
  std::printf("%-28s %-14s %-14s %-12s %s\n", "parameter", "initial", "fitted", "std error", "unit");
  for (const FittedParameter& p : r.parameters)
    std::printf("%-28s %-14.8g %-14.8g %-12.3g %s%s\n", p.name.c_str(), p.initial, p.value, p.std_error,
                p.unit.c_str(), p.at_bound ? "  (at bound)" : "");
  if (r.parameters.size() > 1) {
    std::printf("correlation:\n");
    for (Eigen::Index a = 0; a < r.correlation.rows(); ++a) {
      std::printf("  %-26s", r.parameters[static_cast<std::size_t>(a)].name.c_str());
      for (Eigen::Index b = 0; b < r.correlation.cols(); ++b) std::printf(" %7.3f", r.correlation(a, b));
      std::printf("\n");
    }
  }
  if (!r.warning.empty()) std::printf("warning: %s\n", r.warning.c_str());
  const Vec3 w = lie::log_so3(r.base.R);
  if (!r.base.p.isZero(0.0) || !w.isZero(0.0))
    std::printf("base frame:   position [%.6g, %.6g, %.6g] m, rotation vector [%.6g, %.6g, %.6g] rad (not part of the scene file)\n",
                r.base.p.x(), r.base.p.y(), r.base.p.z(), w.x(), w.y(), w.z());
  std::printf("position error (m):  RMS %.4g -> %.4g, max %.4g -> %.4g\n", r.summary.before.rms_position,
              r.summary.after.rms_position, r.summary.before.max_position, r.summary.after.max_position);
  if (r.summary.before.rms_rotation > 0.0)
    std::printf("rotation error (rad): RMS %.4g -> %.4g, max %.4g -> %.4g\n", r.summary.before.rms_rotation,
                r.summary.after.rms_rotation, r.summary.before.max_rotation, r.summary.after.max_rotation);
  std::printf("per sample (line: tip error before -> after, m):\n");
  for (std::size_t i = 0; i < r.residuals_after.size(); ++i)
    std::printf("  %d: %.4g -> %.4g%s\n", r.residuals_after[i].line, r.residuals_before[i].tip_error,
                r.residuals_after[i].tip_error, r.residuals_after[i].solved ? "" : " (not solved)");
  if (output) std::printf("calibrated scene: %s\n", output->c_str());
}

}  // namespace

std::string calibrate_usage() {
  return "       tdcr calibrate SCENE.json DATA.csv --model NAME --fit NAME[:LO:HI],... [-o OUT.json] [--json]\n"
         "                      [--loss huber|cauchy|none] [--loss-scale S] [--position-std M] [--rotation-std RAD]\n"
         "                      [--max-iterations N] [--cold] [--differences]   (docs/calibration.md)\n";
}

int run_calibrate(const std::vector<std::string>& argv) {
  CalibrateArgs args = parse_args(argv);
  Scene scene = load_scene(args.scene_path);
  if (args.model) scene.model = *args.model;
  args.options.model = parse_model_kind(scene.model);
  args.options.parameters = parse_calibration_parameters(args.fit);
  args.options.validate();
  validate_scene(scene);
  const CalibrationData data = read_calibration_data(args.data_path, scene);
  const CalibrationResult r = calibrate(scene, data, args.options);
  if (args.output) {
    std::ofstream out(*args.output);
    if (!out || !(out << scene_to_json(r.scene) << "\n")) throw InputError("-o", *args.output, "cannot write the output file");
  }
  if (args.json)
    print_json(r, args.output);
  else
    print_text(r, args.output);
  std::fflush(stdout);
  return r.converged() ? 0 : 1;
}

}  // namespace tdcr::cli
