// Inverse solve (inverse_solve.hpp; method and limits in docs/user-guide.md, "Inverse solve").
//
// The problem: min |T|^2 / 2 over T >= 0 subject to e(T) = 0, e the (weighted) tip error. Phase 1
// finds a feasible T (bounded Levenberg-Marquardt on |e|^2); phase 2 is a feasible reduced-space
// SQP: at a point on the target with free (pulling) tendons F, the multipliers lambda solve
// T_F = J_F^T lambda in the least-squares sense, Z spans the null space of J_F (the tangent space
// of the target), g = Z^T T_F is the reduced gradient and B = Z^T (I - sum lambda_i d2 e_i) Z the
// reduced Hessian of the Lagrangian (its curvature term by differences of J along Z). The Newton
// step Z B^-1 g is followed by Gauss-Newton corrections back onto the target; the Lagrangian with
// the step's multipliers is the merit (insensitive, to first order, to the corrections' residual
// error). Tensions that reach zero are fixed there; a fixed tension whose multiplier
// mu_i = -J_i^T lambda is negative is freed. Phase 1 that ends at a local minimum of the distance
// (or stalls) starts again from other tensions; the answer is finally solved cold, along the
// loading path, and accepted only if that meets the target too. Every Jacobian is one by central
// differences of tight, warm-started forward solves (kDifferenceStep), so that the optimality
// conditions that end phase 2 are checked to about 1e-8 relative.
#include "tdcr/models/inverse_solve.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>

#include "services/inverse_solver.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/core/lie.hpp"

namespace tdcr {

namespace detail::inverse {

Solver::Solver(const StaticModel& model, ModelWorkspace& ws, const ModelInput& start, const InverseTarget& target,
               const SolverOptions& solver, const InverseOptions& options, InverseResult& result)
    : model_(model), ws_(ws), input_(start), target_(target), options_(options), r_(result) {
  // Warm-started solves reuse the workspace's last Newton Jacobian: at these tolerances their
  // answers still agree to 1e-13 m, and the differences of the Jacobian cost a few residuals.
  // The options made concrete for this robot (a 0 tolerance is tied to the robot's length),
  // and one RK4 mesh for every inner solve: their answers are differenced, and an
  // accuracy-driven solve may end on another mesh at a neighbouring input. The fixed mesh's
  // default (8 steps per disk interval, h <= 1 mm) is within 7e-10 m of CVODE on the paper
  // robot at n = 10.
  SolverOptions given = solver.resolved(model.robot().total_length());
  if (given.integrator == IntegratorKind::AccuracyDrivenRK4) given.integrator = IntegratorKind::FixedStepRK4;
  warm_ = given;
  warm_.function_tolerance = std::min(given.function_tolerance, kInnerFunctionTolerance);
  warm_.reuse_jacobian = true;
  warm_.extrapolate_warm_starts = false;
  warm_.stability = StabilityCheck::Never;
  warm_.differential_kinematics = false;
  // A trial point is warm-started next to an answer: if it fails directly, the step is too
  // long (rejected and shortened), not worth a load continuation.
  warm_.continuation = false;
  cold_ = warm_;
  cold_.continuation = solver.continuation;
  cold_.reuse_jacobian = false;
  tight_ = warm_;
  tight_.function_tolerance = std::min(given.function_tolerance, kDifferenceFunctionTolerance);
  tight_cold_ = cold_;
  tight_cold_.function_tolerance = tight_.function_tolerance;
  final_ = cold_;
  final_.stability = solver.stability;
  final_.differential_kinematics = solver.differential_kinematics;
  if (target.rotation) {
    R_target_ = lie::exp_so3(*target.rotation);
    rotation_weight_ = target.rotation_weight > 0.0 ? target.rotation_weight : model.robot().total_length();
  }
  // Tension scale: a tenth of the tension that bends the robot by a radian (EI / (r L)), or the
  // largest start tension.
  const Robot& robot = model.robot();
  double r = 0.0;
  for (const Segment& seg : robot.segments)
    for (const TendonSpec& t : seg.tendons) r = std::max(r, std::hypot(t.x, t.y));
  const double EI = robot.backbone.effective_stiffness().EI, L = robot.total_length();
  tension_scale_ = r > 0.0 && L > 0.0 && EI > 0.0 ? 0.1 * EI / (r * L) : 1.0;
  for (double t : start.actuation.values) input_start_max_ = std::max(input_start_max_, t);
  tension_scale_ = std::max(tension_scale_, input_start_max_);
}

void Solver::run() {
  Point cur;
  const std::vector<double>& t0 = input_.actuation.values;
  const VectorXd T0 = Eigen::Map<const VectorXd>(t0.data(), static_cast<Eigen::Index>(t0.size()));
  if (!evaluate(T0, nullptr, cur) || !jacobian(cur)) {
    finish(cur, InverseStatus::ForwardFailed,
           "the forward solve at the start tensions failed: " + cur.solution.summary.brief_report());
    return;
  }
  for (int round = 0;; ++round) {
    if (!reach(cur)) return;
    minimise_norm(cur);
    // The answer of tdcr::solve at these tensions: from the straight robot along the loading path.
    Point cold;
    const bool ok = evaluate(cur.T, nullptr, cold, Mode::Step, &final_);
    if (ok && cold.reached) {
      finish(cold, InverseStatus::Converged, std::move(message_));
      return;
    }
    if (!ok) {
      finish(cur, InverseStatus::ForwardFailed,
             "the target is met, but the forward solve from the straight robot at these tensions failed: " +
                 cold.solution.summary.brief_report());
      return;
    }
    if (round == kBranchRestarts) {
      char buf[200];
      std::snprintf(buf, sizeof buf,
                    "the target is met only on an equilibrium that the loading path from the straight robot does "
                    "not reach (there the tip is %.3g m off)",
                    cold.position_error);
      finish(cold, InverseStatus::Unreachable, buf);
      return;
    }
    cur = std::move(cold);  // the loading path's answer: go on from there
    if (!jacobian(cur)) {
      finish(cur, InverseStatus::ForwardFailed, "the Jacobian by differences of forward solves could not be formed");
      return;
    }
  }
}

void Solver::finish(Point& p, InverseStatus status, std::string message) {
  r_.status = status;
  r_.message = std::move(message);
  r_.tensions.assign(p.T.data(), p.T.data() + p.T.size());
  r_.position_error = p.position_error;
  r_.rotation_error = p.rotation_error;
  if (status != InverseStatus::Converged) {
    r_.minimum_norm = false;
    r_.optimality = 0.0;
    r_.tension_resolution = 0.0;
  }
  r_.solution = std::move(p.solution);
}

}  // namespace detail::inverse

namespace {

std::string component(const char* name, int i) { return std::string("target.") + name + "[" + std::to_string(i) + "]"; }

std::string matrix_text(const Mat3& R) {
  std::string s = "[";
  for (int i = 0; i < 3; ++i) {
    s += i ? ", [" : "[";
    for (int j = 0; j < 3; ++j) s += (j ? ", " : "") + format_value(R(i, j));
    s += "]";
  }
  return s + "]";
}

}  // namespace

void InverseTarget::validate() const {
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(position[i]))
      throw InputError(component("position", i), format_value(position[i]), "must be a finite number (m)");
    if (rotation && !std::isfinite((*rotation)[i]))
      throw InputError(component("rotation", i), format_value((*rotation)[i]), "must be a finite number (rad)");
  }
  if (!std::isfinite(rotation_weight) || rotation_weight < 0.0)
    throw InputError("target.rotation_weight", format_value(rotation_weight),
                     "must be a finite number >= 0 (m per rad; 0: the robot's length)");
}

Vec3 InverseTarget::rotation_from_matrix(const Mat3& R) {
  if (!R.allFinite()) throw InputError("target.rotation", matrix_text(R), "must be a rotation matrix of finite numbers");
  const double err = lie::orthonormality_error(R);
  if (!(err <= kRotationMatrixTolerance))
    throw InputError("target.rotation", matrix_text(R),
                     "must be a rotation matrix: |R^T R - I| = " + format_value(err) + " exceeds " +
                         format_value(kRotationMatrixTolerance));
  if (R.determinant() <= 0.0)
    throw InputError("target.rotation", matrix_text(R),
                     "must be a rotation matrix: det R = " + format_value(R.determinant()) + " (a reflection), not +1");
  return lie::log_so3(R);
}

void InverseOptions::validate() const {
  if (max_iterations < 1)
    throw InputError("inverse.max_iterations", std::to_string(max_iterations), "must be at least 1");
  const std::pair<const char*, double> tolerances[] = {{"inverse.position_tolerance", position_tolerance},
                                                       {"inverse.rotation_tolerance", rotation_tolerance},
                                                       {"inverse.tension_tolerance", tension_tolerance}};
  for (const auto& [name, v] : tolerances)
    if (!std::isfinite(v) || v <= 0.0) throw InputError(name, format_value(v), "must be a positive finite number");
}

std::string to_string(InverseStatus s) {
  switch (s) {
    case InverseStatus::Converged: return "converged";
    case InverseStatus::Unreachable: return "unreachable";
    case InverseStatus::MaxIterations: return "max_iterations";
    case InverseStatus::ForwardFailed: return "forward_failed";
  }
  return "unknown";
}

std::string InverseResult::brief_report() const {
  double norm = 0.0;
  for (double t : tensions) norm += t * t;
  char buf[320];
  if (converged())
    std::snprintf(buf, sizeof buf,
                  "%s: |dp| = %.3g m, |drot| = %.3g rad, %d iterations, %d forward solves, |T| = %.6g N, "
                  "minimum norm %s (Newton step %.2g N)",
                  to_string(status).c_str(), position_error, rotation_error, iterations, forward_solves,
                  std::sqrt(norm), minimum_norm ? "verified" : "not verified", optimality);
  else
    std::snprintf(buf, sizeof buf, "%s: |dp| = %.3g m, |drot| = %.3g rad, %d iterations, %d forward solves, |T| = %.6g N",
                  to_string(status).c_str(), position_error, rotation_error, iterations, forward_solves,
                  std::sqrt(norm));
  return message.empty() ? std::string(buf) : std::string(buf) + " (" + message + ")";
}

InverseResult inverse_solve(const StaticModel& model, ModelWorkspace& workspace, const ModelInput& start,
                            const InverseTarget& target, const SolverOptions& solver, const InverseOptions& options) {
  target.validate();
  options.validate();
  if (start.actuation.kind != Actuation::Kind::Tensions)
    throw InputError("actuation", "displacements", "the inverse solve varies the tensions: start from tension input");
  InverseResult r;
  detail::inverse::Solver(model, workspace, start, target, solver, options, r).run();
  return r;
}

}  // namespace tdcr
