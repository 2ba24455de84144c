// The CLI's JSON contract for a solution (solution_to_json, scene_io.hpp; docs/scene-file.md).
#include <cinttypes>
#include <cstdio>
#include <stdexcept>

#include "json_writer.hpp"
#include "tdcr/core/scene_io.hpp"

namespace tdcr {

namespace {

using detail::number;
using detail::numbers_json;
using detail::ojson;
using detail::vec_json;

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
               {"tip_error_estimate", number(s.tip_error_estimate)},
               {"rk4_refinements", s.rk4_refinements},
               {"rk4_halvings", s.rk4_halvings},
               {"tip_error_estimate_age", s.tip_error_estimate_age},
               {"function_tolerance", s.function_tolerance},
               {"tip_tolerance", s.tip_tolerance},
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

/// A matrix as a list of rows.
ojson matrix_json(const Eigen::MatrixXd& M) {
  ojson rows = ojson::array();
  for (Eigen::Index i = 0; i < M.rows(); ++i) {
    ojson row = ojson::array();
    for (Eigen::Index k = 0; k < M.cols(); ++k) row.push_back(number(M(i, k)));
    rows.push_back(row);
  }
  return rows;
}

// Every key solution_to_json writes itself: a caller's extra member may not take one.
constexpr const char* kContractKeys[] = {
    "model", "model_fingerprint", "status", "reason", "iterations", "residual_norm", "tip", "disks",
    "tendon_displacements", "tensions", "tendon_end_tensions", "tendon_slack", "backbone", "stability",
    "path_events", "geometry_warnings", "contacts", "tip_jacobian", "tip_compliance", "summary", "model_selection"};

/// Adds the caller's member to j (SolutionJsonOptions::extra), its text parsed so that it is
/// printed like the contract's own values.
void add_extra(const JsonMember& m, ojson& j) {
  for (const char* k : kContractKeys)
    if (m.key == k)
      throw std::invalid_argument("solution_to_json: extra member \"" + m.key + "\" is a key of the contract");
  if (j.contains(m.key)) throw std::invalid_argument("solution_to_json: extra member \"" + m.key + "\" given twice");
  try {
    j[m.key] = ojson::parse(m.json);
  } catch (const ojson::parse_error& e) {
    throw std::invalid_argument("solution_to_json: extra member \"" + m.key + "\" is not JSON: " + e.what());
  }
}

/// 16 lower-case hex digits: JSON numbers cannot carry 64 bits exactly.
std::string hex64(std::uint64_t v) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016" PRIx64, v);
  return buf;
}

}  // namespace

std::string solution_to_json(const Solution& solution, const SolutionJsonOptions& options) {
  const SolverSummary& s = solution.summary;
  std::string reason = to_string(s.termination);
  if (!s.message.empty()) reason += ": " + s.message;

  ojson tip = {{"position", nullptr}, {"rotation", nullptr}};
  if (!solution.disk_frames.empty()) tip = frame_json(solution.tip());

  ojson j = ojson::object();
  j["model"] = solution.model;
  j["model_fingerprint"] = hex64(solution.model_fingerprint);
  j["status"] = s.converged() ? "converged" : "failed";
  j["reason"] = reason;
  j["iterations"] = s.iterations;
  j["residual_norm"] = number(s.residual_norm);
  j["tip"] = tip;
  if (options.include_disks) {
    ojson disks = ojson::array();
    for (const Frame& f : solution.disk_frames) disks.push_back(frame_json(f));
    j["disks"] = disks;
  }
  j["tendon_displacements"] = numbers_json(solution.tendon_displacements);
  j["tensions"] = numbers_json(solution.tensions);
  if (!solution.tendon_end_tensions.empty()) j["tendon_end_tensions"] = numbers_json(solution.tendon_end_tensions);
  if (!solution.tendon_slack.empty()) {
    ojson slack = ojson::array();
    for (bool b : solution.tendon_slack) slack.push_back(b);
    j["tendon_slack"] = slack;
  }
  if (options.include_backbone) j["backbone"] = backbone_json(solution.backbone);
  for (const JsonMember& m : options.extra) add_extra(m, j);
  j["stability"] = {{"status", to_string(solution.stability.status)},
                    {"margin", number(solution.stability.margin)},
                    {"method", solution.stability.method}};
  ojson events = ojson::array();
  for (const PathEvent& e : solution.path_events)
    events.push_back(ojson{{"type", to_string(e.type)},
                           {"load_fraction", number(e.load_fraction)},
                           {"tip_jump", number(e.tip_jump)},
                           {"note", e.note}});
  j["path_events"] = events;
  ojson warnings = ojson::array();
  for (const GeometryWarning& w : solution.geometry_warnings)
    warnings.push_back(ojson{{"what", w.what}, {"tendon", w.tendon}, {"disk", w.disk}, {"value", number(w.value)}});
  j["geometry_warnings"] = warnings;
  if (!solution.contacts.empty()) {  // free-space answers keep their JSON as it was
    ojson contacts = ojson::array();
    for (const Contact& c : solution.contacts)
      contacts.push_back(ojson{{"s", number(c.s)},
                               {"point", numbers_json({c.point.x(), c.point.y(), c.point.z()})},
                               {"normal", numbers_json({c.normal.x(), c.normal.y(), c.normal.z()})},
                               {"force", number(c.force)},
                               {"gap", number(c.gap)},
                               {"body", c.disk ? "disk" : "backbone"},
                               {"disk", c.disk_index},
                               {"obstacle", c.obstacle}});
    j["contacts"] = contacts;
  }
  if (solution.tip_jacobian.size() > 0) j["tip_jacobian"] = matrix_json(solution.tip_jacobian);
  if (solution.tip_compliance.size() > 0) j["tip_compliance"] = matrix_json(solution.tip_compliance);
  j["summary"] = summary_json(s);
  if (!solution.model_selection.empty()) j["model_selection"] = solution.model_selection;
  return detail::pretty(j);
}

}  // namespace tdcr
