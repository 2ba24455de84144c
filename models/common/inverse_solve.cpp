// Inverse solve (inverse_solve.hpp; method and limits in docs/user-guide.md, "Inverse solve").
#include "tdcr/models/inverse_solve.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>

#include <Eigen/LU>
#include <Eigen/QR>
#include <Eigen/SVD>

#include "tdcr/core/error.hpp"
#include "tdcr/core/lie.hpp"

namespace tdcr {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// Lawson-Hanson non-negative least squares: argmin |A y - b| over y >= 0. Every A used here
// holds a scaled identity block (full column rank), so the answer is unique.
VectorXd nnls(const MatrixXd& A, const VectorXd& b) {
  const int n = static_cast<int>(A.cols());
  VectorXd y = VectorXd::Zero(n), z(n);
  std::vector<bool> passive(static_cast<std::size_t>(n), false);
  const double tol = 10.0 * std::numeric_limits<double>::epsilon() * n * A.cwiseAbs().maxCoeff() *
                     std::max(b.norm(), std::numeric_limits<double>::min());
  VectorXd w = A.transpose() * (b - A * y);
  for (int outer = 0; outer < 3 * n; ++outer) {
    int j = -1;
    double best = tol;
    for (int i = 0; i < n; ++i)
      if (!passive[static_cast<std::size_t>(i)] && w[i] > best) best = w[(j = i)];
    if (j < 0) break;
    passive[static_cast<std::size_t>(j)] = true;
    for (int inner = 0; inner < 3 * n; ++inner) {
      std::vector<int> P;
      for (int i = 0; i < n; ++i)
        if (passive[static_cast<std::size_t>(i)]) P.push_back(i);
      MatrixXd AP(A.rows(), static_cast<Eigen::Index>(P.size()));
      for (std::size_t k = 0; k < P.size(); ++k) AP.col(static_cast<Eigen::Index>(k)) = A.col(P[k]);
      const VectorXd zP = AP.colPivHouseholderQr().solve(b);
      z.setZero();
      for (std::size_t k = 0; k < P.size(); ++k) z[P[k]] = zP[static_cast<Eigen::Index>(k)];
      double alpha = 1.0;
      for (int i : P)
        if (z[i] <= 0.0) alpha = std::min(alpha, y[i] / (y[i] - z[i]));
      if (alpha >= 1.0) {
        y = z;
        break;
      }
      y += alpha * (z - y);
      const double zero = 1e-14 * y.cwiseAbs().maxCoeff();  // rounding of the blocking variable
      for (int i : P)
        if (y[i] <= zero) {
          passive[static_cast<std::size_t>(i)] = false;
          y[i] = 0.0;
        }
    }
    w = A.transpose() * (b - A * y);
  }
  return y.cwiseMax(0.0);
}

// The damped step from T: argmin |J (y - T) + e|^2 + lambda |y - T|^2 over y >= 0.
VectorXd damped_step(const MatrixXd& J, const VectorXd& e, const VectorXd& T, double lambda) {
  const Eigen::Index k = J.rows(), m = J.cols();
  MatrixXd A(k + m, m);
  VectorXd b(k + m);
  const double s = std::sqrt(lambda);
  A << J, s * MatrixXd::Identity(m, m);
  b << J * T - e, s * T;
  return nnls(A, b);
}

// The minimum-norm step from T: the y >= 0 of least norm on the linearised target set
// J (y - T) + e = 0, restricted to the range of J (singular values above 1e-9 of the largest;
// directions J cannot see are left free for the norm). The set is written with the orthonormal
// rows V_r^T of J = U S V^T, V_r^T y = S_r^-1 U_r^T (J T - e), and weighted by 1e6 against |y|:
// A stays well conditioned and the set is met to 1e-12 relative.
VectorXd min_norm_step(const MatrixXd& J, const VectorXd& e, const VectorXd& T) {
  const Eigen::JacobiSVD<MatrixXd> svd(J, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const VectorXd& sv = svd.singularValues();
  const Eigen::Index m = J.cols();
  Eigen::Index r = 0;
  while (r < sv.size() && sv[r] > 1e-9 * sv[0]) ++r;
  const double rho = 1e6;
  MatrixXd A(r + m, m);
  VectorXd b(r + m);
  A << rho * svd.matrixV().leftCols(r).transpose(), MatrixXd::Identity(m, m);
  b << rho * (svd.matrixU().leftCols(r).transpose() * (J * T - e)).cwiseQuotient(sv.head(r)), VectorXd::Zero(m);
  return nnls(A, b);
}

// One forward solve and the target error it gives.
struct Point {
  Solution solution;
  VectorXd T;            // tensions
  VectorXd e;            // weighted error: position (m), then rotation weight x rotation vector
  MatrixXd J;            // d e / d T
  double position_error = 0.0;
  double rotation_error = 0.0;
  bool reached = false;  // within both tolerances
  double merit() const { return e.norm(); }
};

class Iteration {
 public:
  Iteration(const StaticModel& model, ModelWorkspace& ws, const ModelInput& start, const InverseTarget& target,
            const SolverOptions& solver, const InverseOptions& options)
      : model_(model), ws_(ws), input_(start), target_(target), solver_(solver), options_(options) {
    solver_.differential_kinematics = true;
    // A trial point is warm-started next to an answer: if it fails directly, the step is too
    // long (rejected and shortened), not worth a load continuation.
    trial_solver_ = solver_;
    trial_solver_.continuation = false;
    difference_solver_ = trial_solver_;
    difference_solver_.differential_kinematics = false;
    if (target.rotation) {
      R_target_ = lie::exp_so3(*target.rotation);
      rotation_weight_ = target.rotation_weight > 0.0 ? target.rotation_weight : model.robot().total_length();
    }
  }

  // Forward solve at T warm-started from `warm`; false if it failed (no Jacobian either).
  bool evaluate(const VectorXd& T, const Solution* warm, Point& out) {
    input_.actuation.values.assign(T.data(), T.data() + T.size());
    out.T = T;
    out.solution = tdcr::solve(model_, ws_, input_, warm ? trial_solver_ : solver_, warm);
    const Solution& s = out.solution;
    if (s.disk_frames.empty()) return false;
    const Vec3 dp = s.tip().p - target_.position;
    out.position_error = dp.norm();
    out.rotation_error = 0.0;
    if (!s.converged() || (s.tip_jacobian.rows() != 6 && !difference_jacobian(out.solution))) return false;
    const Eigen::Index m = T.size();
    if (!target_.rotation) {
      out.e = dp;
      out.J = s.tip_jacobian.topRows(3);
    } else {
      // e_r = log(R R_t^T); d e_r = J_l(e_r)^-1 w for R -> exp([w]) R.
      const Vec3 er = lie::log_so3(s.tip().R * R_target_.transpose());
      out.rotation_error = er.norm();
      out.e.resize(6);
      out.e << dp, rotation_weight_ * er;
      out.J.resize(6, m);
      out.J.topRows(3) = s.tip_jacobian.topRows(3);
      out.J.bottomRows(3) = rotation_weight_ * lie::left_jacobian_so3(er).lu().solve(s.tip_jacobian.bottomRows(3));
    }
    out.reached = out.position_error <= options_.position_tolerance &&
                  (!target_.rotation || out.rotation_error <= options_.rotation_tolerance);
    return true;
  }

  // Where the model's differential kinematics is unavailable (PRB on a straight subsegment:
  // its bending-plane angle is singular there), the tip Jacobian by forward differences of full
  // solves, warm-started from `s`: one-sided, as tensions cannot decrease below zero.
  bool difference_jacobian(Solution& s) {
    const ModelInput base = input_;
    const Eigen::Index m = static_cast<Eigen::Index>(base.actuation.values.size());
    MatrixXd D(6, m);
    for (Eigen::Index j = 0; j < m; ++j) {
      input_ = base;
      const double h = 1e-6 * std::max(1.0, base.actuation.values[static_cast<std::size_t>(j)]);
      input_.actuation.values[static_cast<std::size_t>(j)] += h;
      const Solution p = tdcr::solve(model_, ws_, input_, difference_solver_, &s);
      if (!p.converged()) break;
      D.col(j) << (p.tip().p - s.tip().p) / h, lie::log_so3(p.tip().R * s.tip().R.transpose()) / h;
      if (j + 1 == m) s.tip_jacobian = D;
    }
    input_ = base;
    return s.tip_jacobian.rows() == 6;
  }

  // Gauss-Newton corrections from a trial point c (its own Jacobian) until the target is
  // reached again: at most `kCorrections` forward solves, each lowering the error.
  bool restore(Point& c, int& iterations) {
    for (int k = 0; k < kCorrections && !c.reached; ++k) {
      if (iterations >= options_.max_iterations) return false;
      ++iterations;
      Point next;
      const VectorXd y = damped_step(c.J, c.e, c.T, lambda_floor(c.J));
      if (!evaluate(y, &c.solution, next) || next.merit() >= c.merit()) return false;
      c = std::move(next);
    }
    return c.reached;
  }

  // Smallest damping: keeps the step problem strictly convex without biasing it.
  static double lambda_floor(const MatrixXd& J) {
    return 1e-12 * std::max(J.colwise().squaredNorm().maxCoeff(), std::numeric_limits<double>::min());
  }

  static constexpr int kCorrections = 6;

 private:
  const StaticModel& model_;
  ModelWorkspace& ws_;
  ModelInput input_;
  const InverseTarget& target_;
  SolverOptions solver_, trial_solver_, difference_solver_;
  const InverseOptions& options_;
  Mat3 R_target_ = Mat3::Identity();
  double rotation_weight_ = 0.0;
};

void finish(InverseResult& r, Point& p, InverseStatus status, std::string message) {
  r.status = status;
  r.message = std::move(message);
  r.tensions.assign(p.T.data(), p.T.data() + p.T.size());
  r.position_error = p.position_error;
  r.rotation_error = p.rotation_error;
  r.solution = std::move(p.solution);
}

std::string component(const char* name, int i) { return std::string("target.") + name + "[" + std::to_string(i) + "]"; }

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
  char buf[256];
  std::snprintf(buf, sizeof buf, "%s: |dp| = %.3g m, |drot| = %.3g rad, %d iterations, |T| = %.6g N",
                to_string(status).c_str(), position_error, rotation_error, iterations, std::sqrt(norm));
  return message.empty() ? std::string(buf) : std::string(buf) + " (" + message + ")";
}

InverseResult inverse_solve(const StaticModel& model, ModelWorkspace& workspace, const ModelInput& start,
                            const InverseTarget& target, const SolverOptions& solver, const InverseOptions& options) {
  target.validate();
  options.validate();
  if (start.actuation.kind != Actuation::Kind::Tensions)
    throw InputError("actuation", "displacements", "the inverse solve varies the tensions: start from tension input");
  Iteration it(model, workspace, start, target, solver, options);
  InverseResult r;
  Point cur;
  const std::vector<double>& t0 = start.actuation.values;
  if (!it.evaluate(Eigen::Map<const VectorXd>(t0.data(), static_cast<Eigen::Index>(t0.size())), nullptr, cur)) {
    finish(r, cur, InverseStatus::ForwardFailed,
           "the forward solve at the start tensions failed: " + cur.solution.summary.brief_report());
    return r;
  }

  // Reach the target: Levenberg-Marquardt steps with T >= 0, kept only if the error drops.
  const double scale = std::max(cur.J.colwise().squaredNorm().maxCoeff(), std::numeric_limits<double>::min());
  const double lambda_min = Iteration::lambda_floor(cur.J);
  double lambda = 1e-3 * scale;
  while (!cur.reached) {
    if (r.iterations >= options.max_iterations) {
      finish(r, cur, InverseStatus::MaxIterations, "iteration limit before the target was reached");
      return r;
    }
    const VectorXd y = damped_step(cur.J, cur.e, cur.T, lambda);
    if ((y - cur.T).cwiseAbs().maxCoeff() <= options.tension_tolerance) {
      finish(r, cur, InverseStatus::Unreachable,
             "no step with non-negative tensions gets closer: the closest pose found");
      return r;
    }
    ++r.iterations;
    Point trial;
    if (it.evaluate(y, &cur.solution, trial) && trial.merit() < cur.merit()) {
      cur = std::move(trial);
      ++r.accepted_steps;
      lambda = std::max(lambda / 3.0, lambda_min);
    } else {
      lambda = std::max(4.0 * lambda, 1e-9 * scale);
    }
  }

  // Lower |T| on the target: minimum-norm steps on the linearised target set, each brought back
  // to the target by Gauss-Newton corrections, kept if |T| drops; shortened if not.
  r.minimum_norm = false;
  while (r.iterations < options.max_iterations) {
    const VectorXd d = min_norm_step(cur.J, cur.e, cur.T) - cur.T;
    if (d.cwiseAbs().maxCoeff() <= options.tension_tolerance) {
      r.minimum_norm = true;
      break;
    }
    bool kept = false;
    for (double alpha = 1.0; !kept && alpha >= 1.0 / 64.0 && r.iterations < options.max_iterations; alpha /= 4.0) {
      ++r.iterations;
      Point c;
      kept = it.evaluate(cur.T + alpha * d, &cur.solution, c) && it.restore(c, r.iterations) &&
             c.T.norm() < cur.T.norm();
      if (kept) cur = std::move(c);
    }
    if (!kept) {
      r.minimum_norm = r.iterations < options.max_iterations;
      break;
    }
    ++r.accepted_steps;
  }
  finish(r, cur, InverseStatus::Converged,
         r.minimum_norm ? "" : "iteration limit before the minimum norm was confirmed");
  return r;
}

}  // namespace tdcr
