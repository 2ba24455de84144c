// A converged answer linearised for models of nearby robots (answer_linearisation.hpp): the
// implicit function theorem across two models of the same kind, F_x of the first, F of both.
#include "tdcr/models/answer_linearisation.hpp"

#include <algorithm>
#include <cmath>

#include "solve/displacement_input.hpp"
#include "tdcr/bvp/continuation.hpp"
#include "tdcr/bvp/residual_system.hpp"

namespace tdcr {

namespace {

// The unknowns of `answer` in the problem `P` is bound to (its warm guess: it also sets a
// problem's references, e.g. the lumped models' active subsegments), at load factor 1.
bool unknowns_of(detail::ModelProblem& P, const Solution& answer, Eigen::VectorXd& x) {
  bvp::ParameterizedSystem* sys = P.system();
  if (!sys) return false;
  sys->set_parameter(1.0);
  return P.warm_guess(answer, x) && x.size() == sys->size() && x.size() > 0 && x.allFinite() &&
         P.differentiable(x);
}

}  // namespace

bool AnswerLinearisation::linearise(const StaticModel& model, ModelWorkspace& workspace, const ModelInput& input,
                                    const SolverOptions& options, const Solution& answer) {
  valid_ = false;
  if (!answer.converged() || answer.model != model.name() || !workspace.belongs_to(model) ||
      input.actuation.kind != Actuation::Kind::Tensions || detail::needs_displacement_solve(model, input))
    return false;
  const SolverOptions resolved = options.resolved(model.robot().total_length());
  detail::ModelProblem& P = model.bind(workspace, input, resolved);
  if (!unknowns_of(P, answer, x_)) return false;
  bvp::ParameterizedSystem& sys = *P.system();
  const Eigen::Index n = x_.size();
  f_.resize(n);
  if (!sys.residual(x_, f_) || !f_.allFinite()) return false;
  // The converged unknowns themselves where the warm guess is derived from the answer's outputs
  // instead (VC: the base reaction, off by the Newton tolerance): x must be the root, as an
  // error e there would put (frames(x + e) - frames(x)) / h into every column.
  if (answer.unknowns.size() == n && answer.unknowns != x_) {
    Eigen::VectorXd g(n), scale(n);
    sys.residual_scale(scale);
    if (sys.residual(answer.unknowns, g) && g.allFinite() &&
        g.cwiseProduct(scale).cwiseAbs().maxCoeff() < f_.cwiseProduct(scale).cwiseAbs().maxCoeff()) {
      x_ = answer.unknowns;
      f_ = g;
    } else if (!sys.residual(x_, f_)) {  // the system's last evaluation at x again (a Jacobian may reuse it)
      return false;
    }
  }
  // F_x as Newton's own (analytic, structured, or forward differences): its O(sqrt(eps)) error
  // is a relative error of dx of that size, far below a difference Jacobian's.
  Eigen::MatrixXd J(n, n);
  const bool ok = sys.has_jacobian() ? bvp::analytic_jacobian_dense(sys, x_, f_, J)
                                     : bvp::finite_difference_jacobian(sys, x_, f_, J);
  if (!ok || !J.allFinite()) return false;
  lu_.compute(J);
  // A singular F_x (a fold) has no implicit function.
  const Eigen::VectorXd d = lu_.matrixLU().diagonal().cwiseAbs();
  if (!(d.minCoeff() > 1e-12 * d.maxCoeff())) return false;
  answer_ = answer;
  valid_ = true;
  return true;
}

bool AnswerLinearisation::predict(const StaticModel& other, ModelWorkspace& workspace, const ModelInput& input,
                                  const SolverOptions& options, Solution& out) const {
  if (!valid_ || other.name() != answer_.model || !workspace.belongs_to(other)) return false;
  const SolverOptions resolved = options.resolved(other.robot().total_length());
  detail::ModelProblem& P = other.bind(workspace, input, resolved);
  Solution start = answer_;
  start.model_fingerprint = other.fingerprint();
  // The other model's warm guess from the answer sets its problem's state (e.g. the lumped
  // models' active subsegments); its vector may differ (VC derives the base reaction from the
  // answer through its own stiffness), the unknowns' meaning must not: checked below.
  Eigen::VectorXd x;
  if (!unknowns_of(P, start, x) || x.size() != x_.size()) return false;
  const Eigen::Index n = x_.size();
  Eigen::VectorXd f(n), g(n), scale(n);
  if (!P.system()->residual(x_, f) || !f.allFinite()) return false;
  x = x_ - lu_.solve(f - f_);
  if (!P.differentiable(x) || !P.final_residual(x, g) || !g.allFinite()) return false;
  // First order: the step must remove the parameter change's residual but for its square. A
  // residual it does not reduce a thousandfold means the unknowns do not correspond (or the
  // change is far outside the linear range): solve instead.
  P.system()->residual_scale(scale);
  const double before = (f - f_).cwiseProduct(scale).cwiseAbs().maxCoeff();
  const double after = g.cwiseProduct(scale).cwiseAbs().maxCoeff();
  if (!(after <= 1e-3 * before + 10.0 * resolved.function_tolerance)) return false;
  out = Solution();
  out.model = other.name();
  out.model_fingerprint = other.fingerprint();
  out.summary.termination = TerminationType::Converged;
  out.summary.message = "linearised from a converged answer of a nearby model (no Newton solve)";
  out.summary.function_tolerance = resolved.function_tolerance;
  out.unknowns = x;
  P.extract(x, true, out);
  if (out.tensions.empty()) out.tensions = input.actuation.values;
  out.loads = input.loads;
  return out.converged() && !out.disk_frames.empty() && out.disk_frames.back().p.allFinite();
}

}  // namespace tdcr
