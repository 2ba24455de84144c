/// @file answer_linearisation.hpp
/// @brief A converged answer linearised for models of nearby robots: first-order answers at
/// other parameters by the implicit function theorem, without a Newton solve (the calibration's
/// Jacobian, docs/calibration.md).
///
/// For the residual system F(x; p) = 0 of a model at parameters p and its answer x, a model of
/// the same kind at p + dp (another Young's modulus, other tendon offsets, ...) answers
/// x + dx with dx = -F_x^{-1} (F(x; p + dp) - F(x; p)) to first order in dp: one residual
/// evaluation of the other model at x and one output pass, with F_x evaluated and factorised once
/// per answer and shared by every other model.
///
/// @code
/// tdcr::AnswerLinearisation lin;
/// if (lin.linearise(*model, *ws, input, options, answer)) {
///   tdcr::Solution near;
///   if (lin.predict(*other_model, *other_ws, input, options, near)) use(near.disk_frames);
/// }
/// @endcode
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>

#include "tdcr/core/solution.hpp"
#include "tdcr/core/solver_options.hpp"
#include "tdcr/models/static_model.hpp"

namespace tdcr {

/// @brief The linearisation of one converged answer of one model for one input.
class AnswerLinearisation {
 public:
  /// @brief Evaluate and factorise F_x at the unknowns of `answer`, a converged Solution of
  /// `model` for `input` (tension input) solved with `options`. False (and nothing held) if the
  /// model has no residual system (CC), the input is not tensions, the answer gives no unknowns
  /// or F_x cannot be evaluated or is singular: then solve instead.
  bool linearise(const StaticModel& model, ModelWorkspace& workspace, const ModelInput& input,
                 const SolverOptions& options, const Solution& answer);

  /// @brief The first-order answer of `other` (a model of the same kind and structure at nearby
  /// parameters, with its own workspace) for the same input: its outputs (frames, samples) at
  /// x + dx, into `out` (converged summary, no iterations). False if nothing is held, the other
  /// model's problem has another number of unknowns, an evaluation fails, or the step does not
  /// reduce the other model's residual at x a thousandfold (to within 10 Newton tolerances): the
  /// first-order check that the unknowns correspond and the change is in the linear range. Then
  /// solve instead.
  bool predict(const StaticModel& other, ModelWorkspace& workspace, const ModelInput& input,
               const SolverOptions& options, Solution& out) const;

  /// @brief True if linearise() succeeded.
  bool valid() const { return valid_; }

 private:
  bool valid_ = false;
  Solution answer_;                       // the linearised answer (a warm guess for `other`)
  Eigen::VectorXd x_, f_;                 // its unknowns and F(x; p) there
  Eigen::PartialPivLU<Eigen::MatrixXd> lu_;  // F_x at x
};

}  // namespace tdcr
