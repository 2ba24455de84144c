// Displacement input's completion after a converged solve (displacement_input.hpp,
// DisplacementProblem::complete): the homotopy compliance taken to zero, slack and taut tendons
// by complementarity, and the refinement of the driven tensions.
#include "solve/displacement_input.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "physics/geometry_check.hpp"
#include "solve/newton_summary.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/models/static_model.hpp"

namespace tdcr::detail {

namespace {
// The homotopy compliance below which stiffen()'s next step is zero, and the changes between
// slack and taut tendons complete() makes before it calls them cycling.
constexpr double kMinCompliance = 1e-12;
constexpr int kMaxConstraintUpdates = 8;
}  // namespace

bool DisplacementProblem::stiffen(Eigen::VectorXd& y, const bvp::NewtonOptions& options, SolverSummary& summary) {
  double factor = 0.0;  // straight to zero first; where that fails, in decades, then shorter steps
  Eigen::VectorXd last = y;
  bvp::NewtonOptions o = options;
  while (compliance_ > 0.0) {
    const double from = compliance_;
    compliance_ = from * factor < kMinCompliance ? 0.0 : from * factor;
    const bvp::NewtonResult res = newton_.solve(*this, y, o);
    copy_newton_result(res, summary);
    o.reuse_jacobian = true;  // the next compliance changes only the diagonal
    if (res.converged()) {
      last = y;
      continue;
    }
    y = last;
    compliance_ = from;
    factor = factor == 0.0 ? 1e-2 : std::sqrt(factor);
    o.reuse_jacobian = false;
    if (factor > 0.9) {
      summary.message += "; the taut tendons' homotopy compliance could not be taken below " + format_value(from);
      compliance_ = 0.0;
      return false;
    }
  }
  return true;
}

bool DisplacementProblem::flip(const Eigen::VectorXd& y) {
  if (!apply(y.tail(k_))) return false;
  x_ = y.head(n_);
  if (!inner_->tendon_pulls(x_, pulls_)) return false;
  bool changed = false;
  for (int i = 0; i < k_; ++i) {
    char& t = taut_[static_cast<std::size_t>(i)];
    const double gap = (pulls_[index_[i]] + stretch_[i] * ts_[i] * std::max(0.0, y[n_ + i]) - target(i)) / r_[i];
    if (t && y[n_ + i] < -tolerance_) {
      t = 0;  // it would push: slack
      changed = true;
    } else if (!t && gap < -tolerance_) {
      t = 1;  // its path is too long for it: taut
      changed = true;
    }
  }
  if (changed) applied_valid_ = false;
  return changed;
}

ModelProblem::Completion DisplacementProblem::complete(Eigen::VectorXd& y, const bvp::NewtonOptions& options,
                                                      SolverSummary& summary) {
  const std::string path = summary.message;
  std::string what;
  bvp::NewtonOptions fresh = options;  // exact Newton: the last Jacobian is of other equations
  fresh.reuse_jacobian = false;
  fresh.max_setup_calls = 1;
  if (compliance_ > 0.0) {
    if (!stiffen(y, options, summary)) {
      // The compliant tendons' answer with a tendon at its geometric limit: the commanded pulls
      // need it past the limit (the compliance only let it stop short).
      std::string why;
      if (at_limit(y, why)) {
        summary.termination = TerminationType::Infeasible;
        summary.message = why + "; the commanded pulls need it further (" + summary.message + ")";
      }
      return Completion::Done;
    }
    what = "homotopy compliance " + format_value(kStartCompliance) + " taken to zero";
  }
  int updates = 0;
  while (flip(y)) {
    if (++updates > kMaxConstraintUpdates) {
      summary.termination = TerminationType::NoConvergence;
      summary.message = path + "; slack and taut tendons changed more than " + std::to_string(kMaxConstraintUpdates) +
                        " times (cycling)";
      return Completion::Done;
    }
    // A direct solve from the last answer; where it fails, from the same answer with the taut
    // tendons compliant and the compliance taken to zero (a tendon moved to taut at zero
    // tension may need co-contraction that its pull decides only weakly).
    const Eigen::VectorXd start = y;
    constexpr int kDirectIterations = 20;
    bvp::NewtonOptions first = fresh;
    first.max_iterations = std::min(options.max_iterations, kDirectIterations);
    bvp::NewtonResult res = newton_.solve(*this, y, first);
    copy_newton_result(res, summary);
    if (!res.converged()) {
      y = start;
      compliance_ = kStartCompliance;
      res = newton_.solve(*this, y, fresh);
      copy_newton_result(res, summary);
      if (!res.converged() || !stiffen(y, fresh, summary)) {
        // Solved cold instead, with the new branches and the compliance back.
        compliance_ = kStartCompliance;
        applied_valid_ = false;
        summary.message = path + "; after tendons changed between slack and taut, from the answer: " + summary.message;
        return Completion::FollowAgain;
      }
    }
  }
  if (updates > 0) what += (what.empty() ? "" : ", ") + std::string("slack and taut tendons changed ") +
                           std::to_string(updates) + (updates == 1 ? " time" : " times");
  refine(y, options);
  if (!what.empty()) summary.message = path + "; then " + what + ": " + summary.message;
  return Completion::Done;
}

bool DisplacementProblem::at_limit(const Eigen::VectorXd& y, std::string& why) {
  if (infeasibility(y, physics::kTendonLimitNear, why)) return true;
  Solution shape;
  Eigen::VectorXd f(size());
  const bool evaluated = final_residual(y, f);
  extract(y, evaluated, shape);
  return evaluated && physics::tendon_limit(model_->routing(), shape, physics::kTendonLimitNear, why);
}

void DisplacementProblem::refine(Eigen::VectorXd& y, const bvp::NewtonOptions& options) {
  constexpr double kRefineTighter = 1e-3;
  constexpr double kRefineFloor = 1e-15;
  constexpr int kRefineIterations = 3;
  Eigen::VectorXd f(size()), s(size());
  residual_scale(s);
  if (!residual(y, f)) return;
  const double before = f.cwiseProduct(s).lpNorm<Eigen::Infinity>();
  bvp::NewtonOptions o = options;
  o.function_tolerance = std::max(kRefineTighter * options.function_tolerance, kRefineFloor);
  if (before <= o.function_tolerance) return;
  o.max_iterations = kRefineIterations;
  o.reuse_jacobian = false;
  o.max_setup_calls = 1;
  o.freeze_jacobian_below = 0.0;
  Eigen::VectorXd z = y;
  newton_.solve(*this, z, o);
  if (residual(z, f) && f.cwiseProduct(s).lpNorm<Eigen::Infinity>() < before) y = z;
}

}  // namespace tdcr::detail
