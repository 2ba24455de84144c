/// @file newton_flags.hpp
/// @brief Private to bvp: what KINSOL's return flag means for a NewtonSolver::solve(). KINSOL's
/// flag alone is no proof of convergence (KIN_STEP_LT_STPTOL means "stuck" as often as
/// "converged"), so the verdict also weighs the residual at the returned point and which
/// callback failed.
#pragma once

#include <string>

#include "tdcr/core/solution.hpp"

namespace tdcr::bvp::detail {

/// KINSOL's flag names, without KINGetReturnFlagName (which returns malloc'd memory).
const char* kinsol_flag_name(int flag);

/// Why the most recent evaluation inside a callback failed.
enum class EvalFailure { None, NotEvaluated, NonFinite };

/// The termination a failed evaluation stands for.
TerminationType termination_of(EvalFailure e);

/// A failed evaluation in words ("" for None).
const char* describe(EvalFailure e);

/// How a KINSOL solve ended.
struct Verdict {
  TerminationType termination = TerminationType::NoConvergence;
  std::string why;  ///< What the flag does not say ("" if it says it all).
};

/// The verdict on a solve that returned `flag`. `at_returned_point`: the residual evaluation at
/// the returned point (None: evaluated, finite); `within_tolerance`: it met the residual
/// tolerance; `jacobian` and `residual`: the last failed Jacobian and residual callbacks.
Verdict judge(int flag, EvalFailure at_returned_point, bool within_tolerance, EvalFailure jacobian,
              EvalFailure residual);

/// NewtonResult::message: "<flag name>: <iterations> iterations, |F|=<residual_norm>", then
/// "; <why>" if any, then KINSOL's own error text in parentheses for a solve that did not converge.
std::string newton_message(int flag, int iterations, double residual_norm, const Verdict& verdict,
                           const std::string& kinsol_message);

}  // namespace tdcr::bvp::detail
