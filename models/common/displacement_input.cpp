// Displacement input by an outer semismooth Newton over tensions (displacement_input.hpp).
#include "common/displacement_input.hpp"

#include "physics/tendon_path.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/LU>
#include <Eigen/QR>

#include "tdcr/models/model_registry.hpp"
#include "tdcr/models/static_model.hpp"

namespace tdcr::detail {

namespace {

// Relative singular value below which the generalized Jacobian is taken as rank deficient (above
// the forward differences' noise; VC's co-contraction, set by the axial stiffness EA, is 7e-4 on
// the paper robot).
constexpr double kRankThreshold = 1e-6;
// Forward-difference increment of dd/dT relative to max(T, T_s).
constexpr double kDifferenceStep = 1e-4;

// A tendon given by displacement, with its scales.
struct DrivenTendon {
  int index = 0;         // global tendon index
  double delta = 0.0;    // commanded displacement (m), positive when pulled
  double r = 1.0;        // lever arm |r_k| (m): the displacement scale (d ~ r x bending angle)
  double t_scale = 1.0;  // EI / (r L_free) (N): the tension that bends its path by about 1 rad
  double c = 0.0;        // EA / L_free (N/m) of an elastic tendon; 0: inextensible
};

std::vector<DrivenTendon> driven_tendons(const StaticModel& model, const ModelInput& input) {
  const Robot& robot = model.robot();
  const double EI = robot.backbone.effective_stiffness().EI;
  std::vector<DrivenTendon> out;
  int k = 0;
  for (const Segment& seg : robot.segments) {
    for (const TendonSpec& spec : seg.tendons) {
      if (input.actuation.kind_of(static_cast<std::size_t>(k)) == Actuation::Kind::Displacements) {
        const RoutedTendon& rt = model.routing().tendons[static_cast<std::size_t>(k)];
        // Free length: the tendon's path from the base to its end disk on the straight robot
        // (its routing included: a helix is longer than the segments it spans).
        const double l_free = physics::rest_length(rt, 0.0, model.routing().disk_s[static_cast<std::size_t>(rt.end_disk)]);
        DrivenTendon t;
        t.index = k;
        t.delta = input.actuation.values[static_cast<std::size_t>(k)];
        t.r = rt.r.norm();
        t.t_scale = EI / (t.r * l_free);
        t.c = spec.stiffness ? *spec.stiffness / l_free : 0.0;
        out.push_back(t);
      }
      ++k;
    }
  }
  return out;
}

// The outer problem: tensions T of the driven tendons -> their displacements d(T) by tension solves.
class Outer {
 public:
  Outer(const StaticModel& model, ModelWorkspace& ws, const ModelInput& input, const SolverOptions& options)
      : model_(model), ws_(ws), tendons_(driven_tendons(model, input)), inner_(input), options_(options) {
    inner_.actuation.kind = Actuation::Kind::Tensions;
    inner_.actuation.kinds.clear();
    options_.differential_kinematics = false;  // with respect to tensions: not this input's
    options_.stability = false;                // only at the answer
    // The outer Jacobian differences warm-started tension solves: their answers must not depend
    // on the workspace's last solves (SolverOptions::reuse_jacobian, extrapolate_warm_starts),
    // only on T.
    options_.reuse_jacobian = false;
    options_.extrapolate_warm_starts = false;
  }

  int size() const { return static_cast<int>(tendons_.size()); }
  const DrivenTendon& tendon(int i) const { return tendons_[static_cast<std::size_t>(i)]; }

  // Tension solve at T (warm-started from `warm` if given) into `sol`, its driven displacements into d.
  bool evaluate(const Eigen::VectorXd& T, const Solution* warm, Solution& sol, Eigen::VectorXd& d) {
    for (int i = 0; i < size(); ++i) inner_.actuation.values[static_cast<std::size_t>(tendon(i).index)] = T[i];
    sol = tdcr::solve(model_, ws_, inner_, options_, warm);
    ++solves;
    newton_iterations += sol.summary.iterations;
    if (!sol.converged() || sol.tendon_displacements.size() != inner_.actuation.values.size()) return false;
    d.resize(size());
    for (int i = 0; i < size(); ++i) d[i] = sol.tendon_displacements[static_cast<std::size_t>(tendon(i).index)];
    return d.allFinite();
  }

  // (d_k + T_k / c_k - delta_k) / r_k: the path's pull plus the tendon's stretch minus the
  // commanded pull, >= 0 (an elastic tendon's T = c max(0, delta - d) in complementarity form).
  double gap(int i, const Eigen::VectorXd& T, const Eigen::VectorXd& d) const {
    const DrivenTendon& t = tendon(i);
    return (d[i] + (t.c > 0.0 ? T[i] / t.c : 0.0) - t.delta) / t.r;
  }

  // True if tendon i is slack at (T, d): the tension branch of its complementarity is active.
  bool slack(int i, const Eigen::VectorXd& T, const Eigen::VectorXd& d) const {
    return T[i] / tendon(i).t_scale <= gap(i, T, d);
  }

  // phi(T, d) (dimensionless, see the header).
  Eigen::VectorXd phi(const Eigen::VectorXd& T, const Eigen::VectorXd& d) const {
    Eigen::VectorXd f(size());
    for (int i = 0; i < size(); ++i) f[i] = std::min(T[i] / tendon(i).t_scale, gap(i, T, d));
    return f;
  }

  // An element of the generalized Jacobian of phi, with B = dd/dT.
  Eigen::MatrixXd jacobian(const Eigen::VectorXd& T, const Eigen::VectorXd& d, const Eigen::MatrixXd& B) const {
    Eigen::MatrixXd G = Eigen::MatrixXd::Zero(size(), size());
    for (int i = 0; i < size(); ++i) {
      const DrivenTendon& t = tendon(i);
      if (slack(i, T, d)) {
        G(i, i) = 1.0 / t.t_scale;
      } else {
        G.row(i) = B.row(i) / t.r;
        if (t.c > 0.0) G(i, i) += 1.0 / (t.c * t.r);
      }
    }
    return G;
  }

  // dd/dT by forward differences of tension solves warm-started from `at` (increments keep T >= 0).
  bool difference_jacobian(const Eigen::VectorXd& T, const Eigen::VectorXd& d, const Solution& at,
                           Eigen::MatrixXd& B) {
    ++jacobians;
    B.resize(size(), size());
    Solution s;
    Eigen::VectorXd Tp = T, dp;
    for (int j = 0; j < size(); ++j) {
      const double h = kDifferenceStep * std::max(T[j], tendon(j).t_scale);
      Tp[j] = T[j] + h;
      if (!evaluate(Tp, &at, s, dp)) return false;
      B.col(j) = (dp - d) / h;
      Tp[j] = T[j];
    }
    return B.allFinite();
  }

  int solves = 0, newton_iterations = 0, jacobians = 0;

 private:
  const StaticModel& model_;
  ModelWorkspace& ws_;
  std::vector<DrivenTendon> tendons_;
  ModelInput inner_;
  SolverOptions options_;
};

std::string slack_list(const std::vector<bool>& slack) {
  std::string s;
  for (std::size_t k = 0; k < slack.size(); ++k)
    if (slack[k]) s += (s.empty() ? "" : ", ") + std::to_string(k);
  return s.empty() ? "none" : s;
}

}  // namespace

bool needs_displacement_solve(const StaticModel& model, const ModelInput& input) {
  return input.actuation.kind == Actuation::Kind::Displacements &&
         model_info(model.kind()).capabilities.displacement_statics;
}

Solution solve_displacement_input(const StaticModel& model, ModelWorkspace& workspace, const ModelInput& input,
                                  const SolverOptions& options, const Solution* warm_start) {
  const auto t0 = std::chrono::steady_clock::now();
  Outer P(model, workspace, input, options);
  const int n = P.size();
  const double tol = options.function_tolerance;
  const int max_outer = std::min(options.max_iterations, 50);

  // Start: a warm start's tensions (then its unknowns), else zero tension.
  Eigen::VectorXd T = Eigen::VectorXd::Zero(n), d, dn, Tn;
  if (warm_start && warm_start->tensions.size() == input.actuation.values.size())
    for (int i = 0; i < n; ++i)
      T[i] = std::max(0.0, warm_start->tensions[static_cast<std::size_t>(P.tendon(i).index)]);
  Solution cur, trial;
  bool ok = P.evaluate(T, warm_start, cur, d);
  if (!ok && warm_start) ok = P.evaluate(T = Eigen::VectorXd::Zero(n), nullptr, cur, d);

  Eigen::MatrixXd B;
  Eigen::VectorXd f = ok ? P.phi(T, d) : Eigen::VectorXd::Constant(n, INFINITY);
  std::string stop = ok ? "" : "the tension solve at the starting tensions failed";
  bool fresh = ok && P.difference_jacobian(T, d, cur, B);  // B = dd/dT evaluated, not updated
  if (ok && !fresh) stop = "a tension solve of the difference Jacobian failed";
  int iterations = 0;
  while (stop.empty() && f.lpNorm<Eigen::Infinity>() > tol) {
    if (iterations == max_outer) {
      stop = "iteration limit";
      break;
    }
    ++iterations;
    // Minimum-norm step: with an inextensible backbone (CCsub, PRB) two antagonistic tendons of
    // a segment pulled together leave the shape as it is, so G is singular along co-contraction.
    Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(P.jacobian(T, d, B));
    cod.setThreshold(kRankThreshold);
    Eigen::VectorXd step = cod.solve(-f);
    // At most one tension scale per step (about 1 rad of bending): the first difference Jacobian
    // at zero tension can be far from the secant (PRB's straight subsegments).
    double largest = 0.0;
    for (int i = 0; i < n; ++i) largest = std::max(largest, std::abs(step[i]) / P.tendon(i).t_scale);
    if (largest > 1.0) step /= largest;
    std::vector<bool> tension_branch(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) tension_branch[static_cast<std::size_t>(i)] = P.slack(i, T, d);
    // Backtracking on max |phi|; T stays >= 0 (a tendon cannot push).
    const double norm = f.lpNorm<Eigen::Infinity>();
    bool accepted = false;
    double alpha = 1.0;
    for (int ls = 0; ls < 8 && step.allFinite(); ++ls, alpha *= 0.5) {
      Tn = (T + alpha * step).cwiseMax(0.0);
      for (int i = 0; i < n; ++i)  // on the tension branch the step is -T_i exactly (no round-off)
        if (tension_branch[i]) Tn[i] = (1.0 - alpha) * T[i];
      if (P.evaluate(Tn, &cur, trial, dn) && P.phi(Tn, dn).lpNorm<Eigen::Infinity>() < (1.0 - 1e-4 * alpha) * norm) {
        accepted = true;
        break;
      }
    }
    if (!accepted) {
      if (fresh) {
        stop = "no decrease of the displacement residual along the Newton direction";
        break;
      }
      fresh = P.difference_jacobian(T, d, cur, B);  // Broyden's B went stale: difference again
      if (!fresh) stop = "a tension solve of the difference Jacobian failed";
      continue;
    }
    // Broyden update of dd/dT with the accepted step.
    const Eigen::VectorXd s = Tn - T, y = dn - d;
    if (s.squaredNorm() > 0.0) B += (y - B * s) * s.transpose() / s.squaredNorm();
    fresh = false;
    T = Tn;
    d = dn;
    std::swap(cur, trial);
    f = P.phi(T, d);
  }

  const double mismatch = f.lpNorm<Eigen::Infinity>();
  const bool converged = stop.empty() && cur.converged() && mismatch <= tol;
  if (converged && options.stability) {
    SolverOptions so = options;
    so.differential_kinematics = false;
    ModelInput in = input;
    in.actuation.kind = Actuation::Kind::Tensions;
    in.actuation.kinds.clear();
    in.actuation.values = cur.tensions;
    cur.stability = tdcr::solve(model, workspace, in, so, &cur).stability;
  }
  cur.tendon_slack.assign(input.actuation.values.size(), false);
  if (ok)
    for (int i = 0; i < n; ++i) cur.tendon_slack[static_cast<std::size_t>(P.tendon(i).index)] = P.slack(i, T, d);

  SolverSummary& sum = cur.summary;
  const std::string inner = sum.message;
  if (!converged)
    sum.termination = !cur.converged()                ? sum.termination
                      : stop == "iteration limit"     ? TerminationType::MaxIterations
                                                      : TerminationType::NoConvergence;
  char buf[256];
  std::snprintf(buf, sizeof buf,
                "displacement input%s: %d outer iterations, max |phi| = %.3g (tolerance %.3g), %d tension solves "
                "(%d Newton iterations, %d difference Jacobians); slack tendons: ",
                converged ? "" : " failed", iterations, mismatch, tol, P.solves, P.newton_iterations,
                P.jacobians);
  sum.message = buf + slack_list(cur.tendon_slack) + (stop.empty() ? "" : "; stopped: " + stop) +
                "; last tension solve: " + inner;
  sum.iterations = iterations;
  sum.residual_evaluations = P.solves;
  sum.jacobian_evaluations = P.jacobians;
  sum.residual_norm = std::max(sum.residual_norm, mismatch);
  sum.unknowns += n;
  sum.solve_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return cur;
}

}  // namespace tdcr::detail
