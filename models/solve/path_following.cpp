// The loading path from rest (load_continuation.hpp: follow_loading_path): arclength
// continuation with snaps, its events mapped to PathEvents with the tip jump in metres, and the
// bifurcations its determinant does not see (hidden_bifurcation).
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "physics/least_stable_mode.hpp"
#include "solve/bvp_options.hpp"
#include "solve/load_continuation.hpp"
#include "tdcr/models/model_problem.hpp"
#include "physics/geometry_check.hpp"

namespace tdcr::detail {

namespace {

// The scaled arclength of a loading path is the norm of the change of all unknowns: where a
// load bends every disk a little, it grows like the square root of their number. The step bound
// grows with it, sqrt(n / kStepBoundUnknowns) times the options' max_step (at most
// kStepBoundFactor times), so that a path of many unknowns is not cut into more steps than its
// turning asks for (the turn and corrector-distance tests still bound each step). bench_soft
// --rk4-tip-tol 1e-8 (24 soft scenes): VCref 15.0x -> 7.7x of the fastest model (median), its
// E0.1x_n10_+x path 31 -> 15 steps; the loaded-scene suite the same in all 80 rows.
constexpr double kStepBoundUnknowns = 30.0;
constexpr double kStepBoundFactor = 8.0;

PathEvent::Type event_type(bvp::ArclengthEventType t) {
  switch (t) {
    case bvp::ArclengthEventType::Fold: return PathEvent::Type::Fold;
    case bvp::ArclengthEventType::Bifurcation: return PathEvent::Type::Bifurcation;
    case bvp::ArclengthEventType::Snap: return PathEvent::Type::Snap;
  }
  return PathEvent::Type::Fold;
}

// One loading path of problem P from rest (x: its unknowns), with snaps.
bvp::ArclengthResult run_path(ModelProblem& P, const TendonRouting& routing, bvp::ParameterizedSystem& system,
                              Eigen::VectorXd& x, const bvp::NewtonOptions& newton_options,
                              const SolverOptions& options, double first_step) {
  bvp::ArclengthOptions a = detail::arclength_options(options);
  a.start = 0.0;
  a.target = 1.0;
  a.at_fold = bvp::FoldAction::Snap;
  a.detect_bifurcations = a.detect_bifurcations && P.determinant_marks_bifurcations();
  // The path is long in scaled arclength where the robot bends far: at least 400 corrector solves
  // (unless the problem bounds its path: a first attempt with a fallback).
  const int bound = P.cold_start().max_path_steps;
  a.max_steps = bound > 0 ? bound : std::max(a.max_steps, 400);
  a.max_step *= std::clamp(std::sqrt(system.size() / kStepBoundUnknowns), 1.0, kStepBoundFactor);
  if (first_step > 0.0) a.initial_step = std::clamp(first_step, a.min_step, a.initial_step);
  a.event_output = [&P, &system](const Eigen::VectorXd& xe, double lambda) {
    system.set_parameter(lambda);
    Vec3 tip;
    return P.tip_position(xe, tip) ? Eigen::VectorXd(tip) : Eigen::VectorXd();
  };
  // A fold where a tendon reaches its geometric limit is where the actuation becomes infeasible
  // (the curvature the tension asks for puts the tendon at the centre of curvature): there is
  // no branch to snap to, and the snap attempts near the singular geometry would cost hundreds
  // of Newton iterations (tests/test_infeasible_actuation.cpp).
  a.fold_limit = [&P, &routing, &system](const Eigen::VectorXd& xf, double lambda) {
    system.set_parameter(lambda);
    Eigen::VectorXd f(xf.size());
    Solution at_fold;
    P.extract(xf, P.final_residual(xf, f), at_fold);
    std::string why;
    if (!P.infeasibility(xf, physics::kTendonLimitWarn, why))
      physics::tendon_limit(routing, at_fold, physics::kTendonLimitWarn, why);
    return why;
  };
  // The answer is a stable equilibrium (docs/models.md, "The answer"): past a fold a Newton
  // attempt converges to whichever root is nearest, which can be a saddle (s1006 of the
  // loaded-scene suite with its loads x 1.05: VCref's first attempt landed on an equilibrium
  // its stability test calls unstable, and the path went on from there to full load).
  a.accept_landing = [&P](const Eigen::VectorXd& xl, double lambda) {
    const Stability st = P.stability(xl, lambda);
    if (st.status != StabilityStatus::Unstable) return std::string();
    char buf[96];
    std::snprintf(buf, sizeof buf, "an unstable equilibrium, stability margin %.3g", st.margin);
    return std::string(buf);
  };
  system.set_parameter(0.0);
  P.rest_state(x);
  return bvp::arclength_continuation(P.newton(), system, x, newton_options, a);
}

// A bifurcation the path's determinant does not see. The path watches the sign of its
// Jacobian's determinant, which changes where an odd number of real eigenvalues cross zero; at
// a bifurcation of even multiplicity (a straight round column past its critical load: both
// bending planes at once) it keeps its sign, and the path goes on along the branch it is on,
// which is unstable from there (PRB's determinant is not watched at all). After a path that
// reached its target, the answer's own stability test (which counts the unstable directions
// with their multiplicity) tells: if the answer is unstable through a real eigenvalue (not a
// complex pair, which non-conservative loads can have without any bifurcation) and no
// bifurcation was recorded since the path's last stable point (the start, or its last snap
// landing), the branch lost stability on the way. The load where it did is found by walking
// back along the branch from the answer by natural Newton steps (1/8 of the way to that point,
// halved when Newton fails), each tested, until a point that is not unstable, then by the
// secant of the margin through the last two unstable points and regula falsi (Illinois) on the
// margin between the two sides, to kHiddenBifurcationTolerance or a point the test does not
// decide. The branch must be continuous there: the states on either side of the located load
// (scaled by the system's unknown scales) closer than a tenth of the way from there to the
// answer. Otherwise the natural steps left the branch (it ends in a fold on the way back: the
// loading path jumped onto it; a near-perfect column, docs/hard-cases.md), and no bifurcation is
// reported. The Newton solves have a solver of their own (the workspace's
// keeps the path's last Jacobian for the solves after it), their work is counted in `sum`; the
// system's parameter is left at the answer's.
struct HiddenBifurcation {
  double lambda = -1.0;  ///< Where the branch lost stability (< 0: none located).
  double margin = 0.0;   ///< The answer's stability margin.
  bool unstable = false; ///< The answer is unstable through a real eigenvalue, unexplained.
};
constexpr int kHiddenBifurcationSolves = 24;          // Newton solves (each tested) in all
constexpr int kHiddenBifurcationIterations = 30;      // per Newton solve (a corrector's limit)
constexpr double kHiddenBifurcationTolerance = 1e-5;  // load fraction

HiddenBifurcation hidden_bifurcation(ModelProblem& P, bvp::ParameterizedSystem& system, const Eigen::VectorXd& x,
                                     const bvp::NewtonOptions& newton_options, const bvp::ArclengthResult& r,
                                     SolverSummary& sum) {
  HiddenBifurcation out;
  const double end = r.parameter;
  double floor = 0.0;     // the path's last stable point: the start, or its last snap landing
  bool recorded = false;  // a bifurcation recorded since then
  for (const bvp::ArclengthEvent& e : r.events) {
    if (e.type == bvp::ArclengthEventType::Snap) {
      floor = e.lambda;
      recorded = false;
    }
    if (e.type == bvp::ArclengthEventType::Bifurcation) recorded = true;
  }
  if (recorded || !(end > floor)) return out;
  const Stability at_end = P.stability(x, end);
  system.set_parameter(end);
  if (at_end.status != StabilityStatus::Unstable || oscillatory_mode(at_end.method)) return out;
  out.unstable = true;
  out.margin = at_end.margin;
  bvp::NewtonSolver newton;
  bvp::NewtonOptions options = newton_options;
  options.max_iterations = std::min(options.max_iterations, kHiddenBifurcationIterations);
  int solves = 0;
  auto solve_at = [&](double l, Eigen::VectorXd& y) {
    ++solves;
    system.set_parameter(l);
    const bvp::NewtonResult nr = newton.solve(system, y, options);
    sum.iterations += nr.iterations;
    sum.residual_evaluations += nr.residual_evaluations + nr.fd_residual_evaluations;
    sum.jacobian_evaluations += nr.jacobian_evaluations;
    return nr.converged() && y.allFinite();
  };
  // The walk back from the answer (hi: unstable) to a point that is not (lo).
  Eigen::VectorXd hi = x, lo, trial;
  double l_hi = end, m_hi = at_end.margin, l_lo = -1.0, m_lo = 0.0;
  double l_hi2 = NAN, m_hi2 = NAN;  // the unstable point before (l_hi, m_hi)
  double step = 0.125 * (end - floor);
  while (l_lo < 0.0 && solves < kHiddenBifurcationSolves && step > 1e-4 * (end - floor)) {
    const double l = std::max(floor, l_hi - step);
    trial = hi;
    if (!solve_at(l, trial)) {
      step *= 0.5;
      continue;
    }
    const Stability st = P.stability(trial, l);
    if (st.status == StabilityStatus::Undetermined && std::isfinite(st.margin)) {  // at the crossing
      lo = hi = trial;
      l_lo = l_hi = l;
    } else if (st.status != StabilityStatus::Stable) {
      if (l <= floor) break;  // unstable down to the last stable point: nothing to locate
      hi = trial;
      l_hi2 = l_hi;
      m_hi2 = m_hi;
      l_hi = l;
      m_hi = st.margin;
    } else {
      lo = trial;
      l_lo = l;
      m_lo = st.margin;
    }
  }
  // Then the secant through the last two unstable points (the margin on the unstable side is
  // the mode that crosses zero; on the stable side another mode can be the least stable one,
  // PRB's column), and once a point falls on the stable side, regula falsi on the margin
  // between the two sides.
  int side = 0;
  bool secant = std::isfinite(l_hi2);
  while (l_lo >= 0.0 && l_hi - l_lo > kHiddenBifurcationTolerance && solves < kHiddenBifurcationSolves) {
    double l = secant ? l_hi - m_hi * (l_hi - l_hi2) / (m_hi - m_hi2) : l_lo + (l_hi - l_lo) * m_lo / (m_lo - m_hi);
    if (!(l > l_lo && l < l_hi)) l = 0.5 * (l_lo + l_hi);
    trial = l - l_lo < l_hi - l ? lo : hi;
    if (!solve_at(l, trial)) break;
    const Stability st = P.stability(trial, l);
    if (st.status == StabilityStatus::Undetermined) {  // at the crossing, unless the test failed
      if (!std::isfinite(st.margin)) break;
      lo = hi = trial;
      l_lo = l_hi = l;
    } else if (st.status == StabilityStatus::Unstable) {
      hi = trial;
      l_hi2 = l_hi;
      m_hi2 = m_hi;
      l_hi = l;
      m_hi = st.margin;
      if (side == -1) m_lo *= 0.5;
      side = -1;
    } else {
      lo = trial;
      l_lo = l;
      m_lo = st.margin;
      if (side == +1) m_hi *= 0.5;
      side = +1;
      secant = false;
    }
  }
  system.set_parameter(end);
  if (l_lo < 0.0 || l_hi - l_lo > kHiddenBifurcationTolerance) return out;
  Eigen::VectorXd w(x.size());
  system.unknown_scale(w);
  if ((hi - lo).cwiseProduct(w).norm() <= 0.1 * (x - lo).cwiseProduct(w).norm()) out.lambda = 0.5 * (l_lo + l_hi);
  return out;
}

void add_counts(const bvp::ArclengthResult& r, SolverSummary& sum) {
  sum.iterations += r.iterations;
  sum.residual_evaluations += r.residual_evaluations;
  sum.jacobian_evaluations += r.jacobian_evaluations;
  sum.continuation_steps += r.steps;
}

}  // namespace

bvp::ArclengthResult follow_loading_path(ModelProblem& P, const TendonRouting& routing,
                                         bvp::ParameterizedSystem& system, Eigen::VectorXd& x,
                                         const bvp::NewtonOptions& newton_options, const SolverOptions& options,
                                         SolverSummary& sum, std::vector<PathEvent>& events, double first_step,
                                         const std::string& purpose) {
  bvp::ArclengthResult r = run_path(P, routing, system, x, newton_options, options, first_step);
  add_counts(r, sum);
  // A snap with no landing in a formulation that cannot damp (VC's single shooting): the path
  // again in one that can, its answer polished in this one (a direct solve from it).
  std::string again;
  ModelProblem* D = !r.converged() && r.unlanded_snap ? P.damping_formulation() : nullptr;
  if (D && D->system()) {
    bvp::ParameterizedSystem& ds = *D->system();
    bvp::NewtonOptions dn = detail::newton_options(options);
    D->adjust(dn);
    Eigen::VectorXd y;
    bvp::ArclengthResult rd = run_path(*D, routing, ds, y, dn, options, first_step);
    add_counts(rd, sum);
    double fold = r.parameter;  // the fold's own load (the path's last point can lie past it)
    for (const bvp::ArclengthEvent& e : r.events)
      if (e.type == bvp::ArclengthEventType::Fold) fold = e.lambda;
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  "the snap at %.2f %% of the load found no landing in this formulation, which cannot damp; "
                  "followed again in one that can: ",
                  100.0 * fold);
    again = buf;
    Eigen::VectorXd xd;
    if (rd.converged() || !rd.unlanded_snap) {  // an answer, or a stop the driver can name
      P.from_damping_formulation(y, xd);
      system.set_parameter(rd.parameter);
      const bvp::NewtonResult polish = P.newton().solve(system, xd, newton_options);
      sum.iterations += polish.iterations;
      sum.residual_evaluations += polish.residual_evaluations + polish.fd_residual_evaluations;
      sum.jacobian_evaluations += polish.jacobian_evaluations;
      if (polish.converged() && xd.allFinite()) {
        x = xd;
        rd.last = polish;
        r = std::move(rd);
      } else {
        again += "its answer did not converge in this formulation: " + polish.message + "; ";
      }
    } else {
      again += rd.message + "; ";
    }
    if (D->system() != &system) system.set_parameter(r.parameter);
  }
  const HiddenBifurcation hidden =
      r.converged() ? hidden_bifurcation(P, system, x, newton_options, r, sum) : HiddenBifurcation{};
  sum.solver_flag = r.last.flag;
  sum.residual_norm = r.last.residual_norm;
  sum.physical_residual = r.last.physical_residual;
  if (!r.last.linear_solver.empty()) sum.linear_solver = r.last.linear_solver;

  // Events; a snap's tip jump is measured from the fold it leaves.
  std::string snaps;
  const Eigen::VectorXd* fold_tip = nullptr;
  for (const bvp::ArclengthEvent& e : r.events) {
    PathEvent pe;
    pe.type = event_type(e.type);
    pe.load_fraction = e.lambda;
    char buf[160];
    if (e.type == bvp::ArclengthEventType::Snap) {
      const bool measured = fold_tip && fold_tip->size() == 3 && e.output.size() == 3;
      pe.tip_jump = measured ? (e.output - *fold_tip).norm() : 0.0;
      std::snprintf(buf, sizeof buf, "snapped to another branch at %.2f %% of the load (tip jump %.3g mm%s)",
                    100.0 * e.lambda, measured ? 1e3 * pe.tip_jump : -1.0,
                    e.damped_steps > 0 ? "; landed by damped motion" : "");
      snaps += std::string(snaps.empty() ? "" : "; ") + buf;
    } else {
      std::snprintf(buf, sizeof buf, "%s at %.4g %% of the load%s", bvp::to_string(e.type).c_str(),
                    100.0 * e.lambda, e.refined ? "" : " (location not refined)");
    }
    if (e.type == bvp::ArclengthEventType::Fold) fold_tip = &e.output;
    pe.note = buf;
    events.push_back(pe);
  }

  std::string unstable;  // why the answer is unstable, for the summary
  if (hidden.lambda >= 0.0) {
    PathEvent pe;
    pe.type = PathEvent::Type::Bifurcation;
    pe.load_fraction = hidden.lambda;
    char buf[400];
    std::snprintf(buf, sizeof buf,
                  "bifurcation at %.4g %% of the load, found by the stability test (%s): the path stays on its "
                  "branch, unstable beyond it (stability margin %.3g at the answer)",
                  100.0 * hidden.lambda,
                  P.determinant_marks_bifurcations()
                      ? "the path's determinant keeps its sign there: an even number of directions lose stability "
                        "at once, as a round column's two bending planes"
                      : "this model's determinant does not mark bifurcations",
                  hidden.margin);
    pe.note = buf;
    events.push_back(pe);
    unstable = pe.note;
  } else if (hidden.unstable) {
    char buf[240];
    std::snprintf(buf, sizeof buf,
                  "stability margin %.3g, and walking back along its branch found no point where it loses "
                  "stability continuously (the loading path may have jumped onto it)",
                  hidden.margin);
    unstable = buf;
  }

  const std::string why = purpose + "; " + again + r.message;
  if (r.converged()) {
    sum.termination = TerminationType::Converged;
    sum.message = r.last.message + " (by following the loading path from rest: " + why + ")";
    if (!unstable.empty()) sum.message = "the answer is unstable: " + unstable + "; " + sum.message;
    if (!snaps.empty()) sum.message = "the robot snaps: " + snaps + "; " + sum.message;
  } else {
    sum.termination = r.last.converged() || r.steps == 0 ? TerminationType::NoConvergence : r.last.termination;
    char buf[160];
    std::snprintf(buf, sizeof buf,
                  "the loading path stopped at %.1f %% of the load (returned shape: the equilibrium there): ",
                  100.0 * r.parameter);
    sum.message = buf + why;
    if (!r.limit.empty()) {
      // The robot snaps at the fold and its motion runs into a tendon's geometric limit. The
      // fold's own load (the last point kept can lie beyond it, on the branch turning back).
      double fold = r.parameter;
      for (const bvp::ArclengthEvent& e : r.events)
        if (e.type == bvp::ArclengthEventType::Fold) fold = e.lambda;
      std::snprintf(buf, sizeof buf, ", met by the robot snapping from the fold at %.2f %% of the load; ", 100.0 * fold);
      sum.termination = TerminationType::Infeasible;
      sum.message = r.limit + buf + sum.message;
    }
  }
  return r;
}

}  // namespace tdcr::detail
