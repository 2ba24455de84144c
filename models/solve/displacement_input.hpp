// Private to models/: displacement input for the static models (CCsub, PRB, VC, VCref). The
// tensions of the displacement-driven tendons join the model's unknowns and their displacement
// conditions join its residuals: one residual system that the solve driver solves as it solves
// a tension input (direct solve, loading path from rest, final check, stability, infeasibility);
// docs/models.md, "Displacement input".
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "tdcr/models/model_problem.hpp"
#include "tdcr/bvp/continuation.hpp"
#include "tdcr/bvp/newton_solver.hpp"
#include "tdcr/core/scene.hpp"

namespace tdcr {
class StaticModel;
class ModelWorkspace;
}  // namespace tdcr

namespace tdcr::detail {

/// True if `model` solves `input` with the tensions of displacement-driven tendons as unknowns:
/// some tendon is given by displacement and the model has statics
/// (ModelCapabilities::displacement_statics; CC maps displacements kinematically instead).
bool needs_displacement_solve(const StaticModel& model, const ModelInput& input);

/// The tension form of a displacement input: every tendon by tension, the given tensions kept,
/// each displacement-driven tendon at `placeholder` (N; > 0 so that the model binds it as
/// acting: its actual tension is set per evaluation, ModelProblem::set_driven_tensions).
ModelInput tension_form(const ModelInput& input, const std::vector<double>& placeholder);

/// The model's problem with the driven tendons' tensions as unknowns.
///
/// Unknowns y = (x, tau): the model's unknowns x at the driven tensions T = T_s tau (T_s,k =
/// EI / (r_k L_k), the tension that bends tendon k's path by about one radian; r_k its lever arm,
/// L_k its free length from the base to its end disk). Residuals: the model's F(x; T, lambda),
/// then one row per driven tendon k:
///   taut:  (d_k(x) + T_k L_k / EA_k - lambda delta_k) / r_k = 0   (its path plus its stretch is
///          the commanded pull; 1 / EA_k = 0 for an inextensible tendon);
///   slack: tau_k = 0                                               (no tension).
/// d_k(x) is the pull of its path (ModelProblem::tendon_pulls), delta_k the commanded pull. The
/// parameter lambda is the model's load factor (loads and given tensions) and scales the
/// commanded pulls too, so lambda = 0 is the robot at rest with every tension 0: the driver's
/// loading path from rest is the motors and the loads brought on together. Which tendons are
/// taut is decided by complementarity (a tendon cannot push, T >= 0, and cannot be longer than
/// its path, d + T L / EA >= delta, one of them tight): after a converged solve
/// update_constraints() moves a taut tendon with T < 0 to slack and a slack one whose path is
/// too long to taut, and the driver solves again.
class DisplacementProblem final : public ModelProblem, public bvp::ParameterizedSystem {
 public:
  DisplacementProblem();
  ~DisplacementProblem() override;

  /// Bind to `inner`, the model's problem bound to tension_form(input, placeholders) (see
  /// placeholders()), for `input`'s commanded displacements. `warm`: a previous Solution whose
  /// tensions decide which tendons start taut (else: the pulled ones, delta > 0).
  void bind(const StaticModel& model, ModelProblem& inner, const ModelInput& input, const SolverOptions& options,
            const Solution* warm);
  /// The tensions to bind the driven tendons with (their T_s), by global index (0 elsewhere).
  static std::vector<double> placeholders(const StaticModel& model, const ModelInput& input);

  // --- bvp::ParameterizedSystem ---
  int size() const override { return n_ + k_; }
  bool residual(const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Ref<Eigen::VectorXd> f) override;
  const bvp::SparsityPattern* sparsity() const override { return sparse_ ? &pattern_ : nullptr; }
  bool has_jacobian() const override { return true; }
  bool jacobian_is_forward_difference() const override { return true; }
  bool jacobian(const Eigen::Ref<const Eigen::VectorXd>& y, const Eigen::Ref<const Eigen::VectorXd>& f,
                Eigen::Ref<Eigen::MatrixXd> J) override;
  bool sparse_jacobian(const Eigen::Ref<const Eigen::VectorXd>& y, const Eigen::Ref<const Eigen::VectorXd>& f,
                       double* values) override;
  void residual_scale(Eigen::Ref<Eigen::VectorXd> s) const override;
  void unknown_scale(Eigen::Ref<Eigen::VectorXd> s) const override;
  double relative_noise() const override;
  void set_parameter(double lambda) override;
  void accept_step(Eigen::VectorXd& y) override;
  bool recenter(Eigen::Ref<Eigen::VectorXd> y) override;

  // --- ModelProblem ---
  bvp::ParameterizedSystem* system() override { return this; }
  bvp::NewtonSolver& newton() override { return newton_; }
  void adjust(bvp::NewtonOptions& options) const override;
  void adjust_warm(bvp::NewtonOptions& options, bool same_input) const override;
  /// The model's rule; from a tension solve's start (start_from) the pulls' homotopy, a first
  /// attempt, keeps its path to kStartPathSteps corrector solves (the driver solves from rest
  /// after it).
  ColdStart cold_start() const override;
  bool determinant_marks_bifurcations() const override { return inner_->determinant_marks_bifurcations(); }
  void cold_guess(Eigen::VectorXd& y) override;
  bool alternative_guess(Eigen::VectorXd& y) override;
  void rest_state(Eigen::VectorXd& y) override;
  bool warm_guess(const Solution& previous, Eigen::VectorXd& y) override;
  bool final_residual(const Eigen::VectorXd& y, Eigen::Ref<Eigen::VectorXd> f) override;
  void extract(const Eigen::VectorXd& y, bool evaluated, Solution& solution) override;
  Stability stability(const Eigen::VectorXd& y, double load_factor) override;
  Stability direct_stability(const Eigen::VectorXd& y, double load_factor) override;
  bool automatic_stability_under_loads() const override { return inner_->automatic_stability_under_loads(); }
  bool infeasibility(const Eigen::VectorXd& y, double threshold, std::string& why) override;
  bool differentiable(const Eigen::VectorXd& y) const override { return inner_->differentiable(y.head(n_)); }
  double max_curvature() const override { return inner_->max_curvature(); }
  std::string integrator_name() const override { return inner_->integrator_name(); }
  /// An inextensible tendon commanded a pull not shorter than its path's length on the straight
  /// robot (from the base, or over its own segment with the per-segment convention): its path
  /// would have to be shorter than nothing.
  bool impossible_input(std::string& why) const override;
  /// From the driver's answer: the homotopy compliance taken to zero, then complementarity
  /// (a taut tendon that would push goes slack, a slack one whose path is too long goes taut,
  /// each change solved again from the last answer, at most kMaxConstraintUpdates; where that
  /// fails, FollowAgain: the driver solves the new equations cold, from rest or the cold guess,
  /// with the compliance back), then refined (see refine()).
  Completion complete(Eigen::VectorXd& y, const bvp::NewtonOptions& options, SolverSummary& summary) override;

  /// From now until the next bind the parameter lambda brings the commanded pulls on from those
  /// of `start` (a converged tension solve of this model at the same loads, e.g. tension_start):
  /// target_k(lambda) = d_k(start) + lambda (delta_k - d_k(start)), the loads and given tensions at
  /// full value; its equilibrium is the rest state (lambda = 0) and the cold guess, its tensioned
  /// tendons taut, no compliance.
  void start_from(const Solution& start);
  /// `values` (the input's, global order) with each driven tendon's entry the tension of the
  /// linear guess (see linear_guess()).
  std::vector<double> linear_tensions(std::vector<double> values) const;
  /// Time stepping (VC's and VCref's dynamics, models/vc/vc_dynamics.cpp): from now on the
  /// commanded pulls of `input` (the tendons driven as bound), without a rebind; the driven
  /// tensions are applied again at the next evaluation (the inner problem may have been rebound).
  /// Allocation-free.
  void set_commanded(const ModelInput& input) {
    for (int i = 0; i < k_; ++i) delta_[i] = input.actuation.values[static_cast<std::size_t>(index_[i])];
    applied_valid_ = false;
  }
  /// Complementarity after a converged solve at y (a taut tendon that would push goes slack, a
  /// slack one whose path is too long goes taut): true if a tendon changed (then solve again).
  bool update_slack(const Eigen::VectorXd& y) { return flip(y); }
  /// Which driven tendons are taut (by driven index) and their global indices.
  const std::vector<char>& taut() const { return taut_; }
  const std::vector<int>& driven() const { return index_; }

 private:
  // The inner problem's verdict at the answer's tensions held fixed, read for tendons held at
  // their lengths (stable stays stable, unstable is not decided).
  Stability held_tensions(Stability s) const;
  // Set the inner problem's driven tensions to T_s tau (if they changed).
  bool apply(const Eigen::Ref<const Eigen::VectorXd>& tau);
  // The rows of the driven tendons at y (pulls d_ evaluated at x): into r.
  void driven_rows(const Eigen::Ref<const Eigen::VectorXd>& tau, Eigen::Ref<Eigen::VectorXd> r) const;
  // The border of the Jacobian at y (f = F(y)): col_, row_, tt_.
  // With Jxx (not null), the model's forward-difference Jacobian from the pulls' evaluations.
  bool border(const Eigen::Ref<const Eigen::VectorXd>& y, const Eigen::Ref<const Eigen::VectorXd>& f,
              Eigen::Ref<Eigen::MatrixXd>* Jxx);
  // complete()'s parts. stiffen(): the compliance from its value down to zero in Newton solves
  // from the last answer (straight to zero, else decades, else shorter steps). flip(): move the tendons whose
  // complementarity y violates (true if any moved). refine(): Newton iterations (fresh Jacobians,
  // at most 3) towards 1e-3 of the tolerance, kept if they lower the residual: the driven
  // tensions then carry the precision of the pulls (co-contraction of an antagonistic pair moves
  // the pulls by 1e-3 (VC, VCref, PRB) to 1e-8 (CCsub) of what a differential pull does, so a
  // residual at the tolerance leaves it loose).
  bool stiffen(Eigen::VectorXd& y, const bvp::NewtonOptions& options, SolverSummary& summary);
  bool flip(const Eigen::VectorXd& y);
  // True and the reason if a tensioned tendon is at its geometric limit at y (the model's test,
  // else the disk frames': physics::tendon_limit with kTendonLimitNear).
  bool at_limit(const Eigen::VectorXd& y, std::string& why);
  void refine(Eigen::VectorXd& y, const bvp::NewtonOptions& options);
  // T_s-scaled tensions of a Solution's driven tendons (false if it has none).
  bool tensions_of(const Solution& s, Eigen::VectorXd& tau) const;
  // The minimum-norm non-negative tensions that meet the commanded pulls on the straight robot
  // in linear beam theory: the cold guess's tensions.
  void linear_guess(Eigen::VectorXd& tau) const;

  ModelProblem* inner_ = nullptr;
  bvp::ParameterizedSystem* sys_ = nullptr;
  const StaticModel* model_ = nullptr;
  int n_ = 0, k_ = 0;
  std::vector<int> index_;           // global index of driven tendon i
  Eigen::VectorXd delta_, r_, ts_, stretch_;  // commanded pull, lever arm, T_s, L / EA (0: inextensible)
  Eigen::VectorXd longest_;          // the longest pull any shape gives an inextensible tendon
  Eigen::MatrixXd linear_;           // linear beam theory's d pull_i / d tau_j on the straight robot
  Eigen::VectorXd linear_given_;     // and the pulls the tendons given by tension add (over r_i)
  std::vector<char> taut_;
  double lambda_ = 1.0;
  Eigen::VectorXd start_, base_;     // start_from(): the start's unknowns and pulls (empty: from rest)
  // The commanded pull of driven tendon i at the parameter: lambda delta (from rest), or from
  // the start's pull to delta.
  double target(int i) const { return base_[i] + lambda_ * (delta_[i] - base_[i]); }
  double tolerance_ = 1e-10;         // SolverOptions::function_tolerance: the complementarity's slack
  // The homotopy compliance a cold solve starts with (bind), which complete() takes to zero.
  static constexpr double kStartCompliance = 1e-2;
  double compliance_ = 0.0;          // the homotopy compliance c of the taut rows (driven_rows)
  Eigen::VectorXd T_, applied_;      // tensions to apply, last applied
  bool applied_valid_ = false;
  Eigen::VectorXd pulls_;            // every tendon's pull at the last evaluated x
  Eigen::VectorXd x_, f_, fp_, dp_;  // scratch
  Eigen::MatrixXd col_, row_, tt_;  // Jacobian border: dF/dtau, d rows/dx, d rows/dtau
  std::vector<double> inner_values_;
  bvp::FiniteDifferenceWorkspace fd_;
  bool sparse_ = false;
  bvp::SparsityPattern pattern_;
  std::vector<int> inner_pos_;       // bordered CSC position of every inner entry
  bvp::NewtonSolver newton_;
  int last_iterations_ = 0;
};

/// The start of a cold displacement solve: the tension solve (by the driver's rule, stability and
/// differential kinematics off) of `input` with its displacement-driven tendons at the tensions
/// of DisplacementProblem's linear guess. False if it did not converge (`start` says why).
bool tension_start(const StaticModel& model, ModelWorkspace& workspace, const ModelInput& input,
                   const SolverOptions& options, Solution& start);

/// bind_displacement_problem (declared in tdcr/models/static_model.hpp, a friend of the model
/// and the workspace): the workspace's DisplacementProblem, bound for `input` on the model's
/// problem bound to its tension form (made on first use; belongs to the workspace, reused after).

}  // namespace tdcr::detail
