/// @file newton_flags.cpp
/// @brief KINSOL's return flags translated into TerminationType (newton_flags.hpp).
#include "newton_flags.hpp"

#include <kinsol/kinsol.h>

#include <cstdio>

namespace tdcr::bvp::detail {

const char* kinsol_flag_name(int flag) {
#define TDCR_KIN_FLAG(f) \
  case f: return #f;
  switch (flag) {
    TDCR_KIN_FLAG(KIN_SUCCESS) TDCR_KIN_FLAG(KIN_INITIAL_GUESS_OK) TDCR_KIN_FLAG(KIN_STEP_LT_STPTOL)
    TDCR_KIN_FLAG(KIN_WARNING) TDCR_KIN_FLAG(KIN_MEM_NULL) TDCR_KIN_FLAG(KIN_ILL_INPUT)
    TDCR_KIN_FLAG(KIN_NO_MALLOC) TDCR_KIN_FLAG(KIN_MEM_FAIL) TDCR_KIN_FLAG(KIN_LINESEARCH_NONCONV)
    TDCR_KIN_FLAG(KIN_MAXITER_REACHED) TDCR_KIN_FLAG(KIN_MXNEWT_5X_EXCEEDED)
    TDCR_KIN_FLAG(KIN_LINESEARCH_BCFAIL) TDCR_KIN_FLAG(KIN_LINSOLV_NO_RECOVERY)
    TDCR_KIN_FLAG(KIN_LINIT_FAIL) TDCR_KIN_FLAG(KIN_LSETUP_FAIL) TDCR_KIN_FLAG(KIN_LSOLVE_FAIL)
    TDCR_KIN_FLAG(KIN_SYSFUNC_FAIL) TDCR_KIN_FLAG(KIN_FIRST_SYSFUNC_ERR)
    TDCR_KIN_FLAG(KIN_REPTD_SYSFUNC_ERR) TDCR_KIN_FLAG(KIN_VECTOROP_ERR)
    TDCR_KIN_FLAG(KIN_CONTEXT_ERR)
    default: return "KIN_UNKNOWN_FLAG";
  }
#undef TDCR_KIN_FLAG
}

TerminationType termination_of(EvalFailure e) {
  // residual() returning false is, in tdcr, an integrator that gave up (shooting models); a
  // finite-but-wrong F is impossible to detect here, so those are the only two kinds.
  switch (e) {
    case EvalFailure::NotEvaluated: return TerminationType::IntegrationFailed;
    case EvalFailure::NonFinite: return TerminationType::NonFiniteResidual;
    default: return TerminationType::NoConvergence;
  }
}

const char* describe(EvalFailure e) {
  switch (e) {
    case EvalFailure::NotEvaluated: return "residual could not be evaluated";
    case EvalFailure::NonFinite: return "residual is not finite";
    default: return "";
  }
}

Verdict judge(int flag, EvalFailure at_returned_point, bool within_tolerance, EvalFailure jacobian,
              EvalFailure residual) {
  Verdict v;
  if (at_returned_point != EvalFailure::None) {
    v.termination = termination_of(at_returned_point);
    v.why = std::string(describe(at_returned_point)) + " at the returned point";
    return v;
  }
  if ((flag == KIN_SUCCESS || flag == KIN_INITIAL_GUESS_OK || flag == KIN_STEP_LT_STPTOL) && within_tolerance) {
    v.termination = TerminationType::Converged;
    return v;
  }
  switch (flag) {
    case KIN_SUCCESS:
    case KIN_INITIAL_GUESS_OK:
      v.termination = TerminationType::NoConvergence;
      v.why = "residual above tolerance at the returned point";
      break;
    case KIN_STEP_LT_STPTOL:
      v.termination = TerminationType::NoConvergence;
      v.why = "step below step_tolerance but residual above function_tolerance";
      break;
    case KIN_LINESEARCH_NONCONV:
    case KIN_LINESEARCH_BCFAIL:
      v.termination = TerminationType::LineSearchFailed;
      break;
    case KIN_MAXITER_REACHED:
      v.termination = TerminationType::MaxIterations;
      break;
    case KIN_MXNEWT_5X_EXCEEDED:
      v.termination = TerminationType::NoConvergence;
      v.why = "five consecutive steps of maximum length: diverging or no root";
      break;
    case KIN_LINSOLV_NO_RECOVERY:
    case KIN_LINIT_FAIL:
    case KIN_LSETUP_FAIL:
    case KIN_LSOLVE_FAIL:
      // A failed factorisation may be a Jacobian that could not be evaluated: say which.
      if (jacobian != EvalFailure::None) {
        v.termination = termination_of(jacobian);
        v.why = std::string("Jacobian: ") + describe(jacobian);
      } else {
        v.termination = TerminationType::LinearSolverFailed;
        v.why = "singular or failed Jacobian factorisation";
      }
      break;
    case KIN_SYSFUNC_FAIL:
    case KIN_FIRST_SYSFUNC_ERR:
    case KIN_REPTD_SYSFUNC_ERR:
      v.termination = termination_of(residual);
      v.why = describe(residual);
      break;
    default:
      v.termination = TerminationType::NoConvergence;
      break;
  }
  return v;
}

std::string newton_message(int flag, int iterations, double residual_norm, const Verdict& verdict,
                           const std::string& kinsol_message) {
  char head[160];
  std::snprintf(head, sizeof head, "%s: %d iterations, |F|=%.3g", kinsol_flag_name(flag), iterations, residual_norm);
  std::string message = head;
  if (!verdict.why.empty()) message += "; " + verdict.why;
  if (!kinsol_message.empty() && verdict.termination != TerminationType::Converged)
    message += " (" + kinsol_message + ")";
  return message;
}

}  // namespace tdcr::bvp::detail
