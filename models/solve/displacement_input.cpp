// Displacement input: the driven tendons' tensions as unknowns of the model's own residual
// system (displacement_input.hpp, docs/models.md "Displacement input"). Here: which solves take
// that path, binding the problem, its starts (the linear guess, the cold, rest and warm states,
// a tension solve's start) and the binding entry; its residual system is in
// displacement_residual.cpp, its completion after a converged solve in displacement_completion.cpp.
#include "solve/displacement_input.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <Eigen/SVD>

#include "physics/tendon_path.hpp"
#include "tdcr/core/error.hpp"
#include "tdcr/models/static_model.hpp"

namespace tdcr::detail {

bool needs_displacement_solve(const StaticModel& model, const ModelInput& input) {
  return input.actuation.kind == Actuation::Kind::Displacements &&
         model.capabilities().displacement_statics;
}

ModelInput tension_form(const ModelInput& input, const std::vector<double>& placeholder) {
  ModelInput out = input;
  out.actuation.kind = Actuation::Kind::Tensions;
  out.actuation.kinds.clear();
  for (std::size_t k = 0; k < out.actuation.values.size(); ++k)
    if (input.actuation.kind_of(k) == Actuation::Kind::Displacements) out.actuation.values[k] = placeholder[k];
  return out;
}

DisplacementProblem::DisplacementProblem() = default;
DisplacementProblem::~DisplacementProblem() = default;

std::vector<double> DisplacementProblem::placeholders(const StaticModel& model, const ModelInput& input) {
  const double EI = model.robot().backbone.effective_stiffness().EI;
  const TendonRouting& routing = model.routing();
  std::vector<double> p(input.actuation.values.size(), 0.0);
  for (std::size_t k = 0; k < p.size(); ++k) {
    if (input.actuation.kind_of(k) != Actuation::Kind::Displacements) continue;
    const RoutedTendon& t = routing.tendons[k];
    p[k] = EI / (t.r.norm() * physics::rest_length(t, 0.0, routing.disk_s[static_cast<std::size_t>(t.end_disk)]));
  }
  return p;
}

void DisplacementProblem::bind(const StaticModel& model, ModelProblem& inner, const ModelInput& input,
                               const SolverOptions& options, const Solution* warm) {
  model_ = &model;
  tolerance_ = options.function_tolerance;
  inner_ = &inner;
  sys_ = inner.system();
  n_ = sys_->size();
  const Robot& robot = model.robot();
  const TendonRouting& routing = model.routing();
  const double EI = robot.backbone.effective_stiffness().EI;
  index_.clear();
  std::vector<double> stiffness;
  {
    std::size_t k = 0;
    for (const Segment& seg : robot.segments)
      for (const TendonSpec& spec : seg.tendons) {
        if (input.actuation.kind_of(k) == Actuation::Kind::Displacements) {
          index_.push_back(static_cast<int>(k));
          stiffness.push_back(spec.stiffness ? *spec.stiffness : 0.0);
        }
        ++k;
      }
  }
  k_ = static_cast<int>(index_.size());
  delta_.resize(k_);
  r_.resize(k_);
  ts_.resize(k_);
  stretch_.resize(k_);
  std::vector<double> l_free(static_cast<std::size_t>(k_));
  longest_.resize(k_);
  for (int i = 0; i < k_; ++i) {
    const RoutedTendon& t = routing.tendons[static_cast<std::size_t>(index_[i])];
    const bool per_segment = input.actuation.convention == Actuation::DisplacementConvention::PerSegment && t.segment > 0;
    const double s0 = per_segment ? routing.segment_end_s[static_cast<std::size_t>(t.segment - 1)] : 0.0;
    longest_[i] = physics::rest_length(t, s0, routing.disk_s[static_cast<std::size_t>(t.end_disk)]);
    delta_[i] = input.actuation.values[static_cast<std::size_t>(index_[i])];
    r_[i] = t.r.norm();
    l_free[i] = physics::rest_length(t, 0.0, routing.disk_s[static_cast<std::size_t>(t.end_disk)]);
    ts_[i] = EI / (r_[i] * l_free[i]);
    stretch_[i] = stiffness[i] > 0.0 ? l_free[i] / stiffness[i] : 0.0;
  }
  // Linear beam theory on the straight robot: tendon j's tension bends every segment it spans
  // with curvature T_j r_j / EI towards it, which pulls tendon i by (r_i . r_j) / EI per length
  // they share (the base offsets: a guess, exact for straight routing).
  // The tendons given by tension pull the driven ones by linear_given_ (in units of r).
  const auto pull = [&](int i, int j) {  // d pull_i / d T_j (m/N), global indices
    const RoutedTendon& a = routing.tendons[static_cast<std::size_t>(i)];
    const RoutedTendon& b = routing.tendons[static_cast<std::size_t>(j)];
    return a.r.dot(b.r) * routing.disk_s[static_cast<std::size_t>(std::min(a.end_disk, b.end_disk))] / EI;
  };
  linear_.resize(k_, k_);
  linear_given_.setZero(k_);
  for (int i = 0; i < k_; ++i) {
    for (int j = 0; j < k_; ++j) linear_(i, j) = pull(index_[i], index_[j]) * ts_[j] / r_[i];
    for (std::size_t j = 0; j < input.actuation.values.size(); ++j)
      if (input.actuation.kind_of(j) == Actuation::Kind::Tensions)
        linear_given_[i] += pull(index_[i], static_cast<int>(j)) * input.actuation.values[j] / r_[i];
  }
  // Which tendons start taut: a warm start's tensioned ones, else those the linear guess
  // tensions (a tendon it leaves slack is moved to taut after the solve if its path is too long:
  // update_constraints; starting it taut at zero tension can make the loading path's first
  // Jacobian singular, PRB's bending planes set by the external load alone).
  taut_.assign(static_cast<std::size_t>(k_), 0);
  Eigen::VectorXd tau;
  const bool from_warm = warm && tensions_of(*warm, tau);
  if (!from_warm) linear_guess(tau);
  for (int i = 0; i < k_; ++i) taut_[static_cast<std::size_t>(i)] = tau[i] > 0.0;
  lambda_ = 1.0;
  start_.resize(0);
  base_.setZero(k_);
  T_.setZero(k_);
  applied_valid_ = false;
  // A cold solve starts with every taut tendon compliant (complete() takes it to zero): co-
  // contraction that the pulls decide only weakly is then held down on the way, not sent far.
  compliance_ = from_warm ? 0.0 : kStartCompliance;

  // The Jacobian's pattern: the inner one bordered by k full rows (the pulls read every unknown
  // that moves a disk) and k full columns (a tension loads every disk it passes).
  const bvp::SparsityPattern* p = sys_->sparsity();
  sparse_ = p != nullptr;
  if (sparse_) {
    const int m = n_ + k_;
    pattern_.rows = pattern_.cols = m;
    pattern_.col_ptr.assign(static_cast<std::size_t>(m) + 1, 0);
    pattern_.row_idx.clear();
    inner_pos_.resize(static_cast<std::size_t>(p->nnz()));
    for (int j = 0; j < n_; ++j) {
      for (int q = p->col_ptr[j]; q < p->col_ptr[j + 1]; ++q) {
        inner_pos_[static_cast<std::size_t>(q)] = static_cast<int>(pattern_.row_idx.size());
        pattern_.row_idx.push_back(p->row_idx[q]);
      }
      for (int i = 0; i < k_; ++i) pattern_.row_idx.push_back(n_ + i);
      pattern_.col_ptr[static_cast<std::size_t>(j) + 1] = static_cast<int>(pattern_.row_idx.size());
    }
    for (int j = n_; j < m; ++j) {
      for (int i = 0; i < m; ++i) pattern_.row_idx.push_back(i);
      pattern_.col_ptr[static_cast<std::size_t>(j) + 1] = static_cast<int>(pattern_.row_idx.size());
    }
    inner_values_.assign(static_cast<std::size_t>(p->nnz()), 0.0);
    fd_.prepare(*p);
  } else {
    fd_.prepare(n_);
  }
}

bool DisplacementProblem::tensions_of(const Solution& s, Eigen::VectorXd& tau) const {
  tau.resize(k_);
  for (int i = 0; i < k_; ++i) {
    const auto k = static_cast<std::size_t>(index_[i]);
    if (k >= s.tensions.size() || !std::isfinite(s.tensions[k])) return false;
    tau[i] = s.tensions[k] / ts_[i];
  }
  return true;
}

ColdStart DisplacementProblem::cold_start() const {
  constexpr int kStartPathSteps = 128;
  if (start_.size() == 0) return inner_->cold_start();
  ColdStart c;
  c.max_path_steps = kStartPathSteps;
  return c;
}

void DisplacementProblem::start_from(const Solution& start) {
  Eigen::VectorXd y;
  if (!warm_guess(start, y)) return;  // stays from rest
  base_.resize(k_);
  for (int i = 0; i < k_; ++i) base_[i] = start.tendon_displacements[static_cast<std::size_t>(index_[i])];
  start_ = y;
  compliance_ = 0.0;
  sys_->set_parameter(1.0);
}

void DisplacementProblem::linear_guess(Eigen::VectorXd& tau) const {
  // The linear complementarity problem w = L tau + p - delta / r >= 0, tau >= 0, tau . w = 0 (p:
  // the pulls of the tendons given by tension), by
  // moving tendons between the taut set (w = 0, minimum-norm) and the slack set (tau = 0).
  tau.setZero(k_);
  if (k_ == 0) return;
  Eigen::VectorXd q(k_);
  for (int i = 0; i < k_; ++i) q[i] = delta_[i] / r_[i] - linear_given_[i];
  std::vector<char> taut(static_cast<std::size_t>(k_));
  for (int i = 0; i < k_; ++i) taut[static_cast<std::size_t>(i)] = q[i] > 0.0;
  for (int pass = 0; pass < 2 * k_ + 2; ++pass) {
    std::vector<int> A;
    for (int i = 0; i < k_; ++i)
      if (taut[static_cast<std::size_t>(i)]) A.push_back(i);
    tau.setZero();
    if (!A.empty()) {
      Eigen::MatrixXd M(A.size(), A.size());
      Eigen::VectorXd b(A.size());
      for (std::size_t a = 0; a < A.size(); ++a) {
        b[static_cast<Eigen::Index>(a)] = q[A[a]];
        for (std::size_t c = 0; c < A.size(); ++c)
          M(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(c)) = linear_(A[a], A[c]);
      }
      // Minimum norm by a singular value decomposition: antagonistic tendons taut together make M
      // singular, and Eigen's CompleteOrthogonalDecomposition read uninitialised memory in its
      // solve of a rank-deficient matrix (valgrind, Eigen 3.4).
      const Eigen::JacobiSVD<Eigen::MatrixXd> svd(M, Eigen::ComputeThinU | Eigen::ComputeThinV);
      Eigen::VectorXd c = svd.matrixU().transpose() * b;
      const Eigen::VectorXd& sv = svd.singularValues();
      for (Eigen::Index q = 0; q < sv.size(); ++q) c[q] = sv[q] > 1e-12 * sv[0] ? c[q] / sv[q] : 0.0;
      const Eigen::VectorXd t = svd.matrixV() * c;
      for (std::size_t a = 0; a < A.size(); ++a) tau[A[a]] = t[static_cast<Eigen::Index>(a)];
    }
    const Eigen::VectorXd w = linear_ * tau - q;
    bool moved = false;
    for (int i = 0; i < k_; ++i) {
      char& ti = taut[static_cast<std::size_t>(i)];
      if ((ti && tau[i] < 0.0) || (!ti && w[i] < -1e-12)) {
        ti = !ti;
        moved = true;
      }
    }
    if (!moved) break;
  }
  tau = tau.cwiseMax(0.0);
}

std::vector<double> DisplacementProblem::linear_tensions(std::vector<double> values) const {
  Eigen::VectorXd tau;
  linear_guess(tau);
  for (int i = 0; i < k_; ++i) values[static_cast<std::size_t>(index_[i])] = ts_[i] * tau[i];
  return values;
}

void DisplacementProblem::cold_guess(Eigen::VectorXd& y) {
  if (start_.size() > 0) {
    y = start_;
    return;
  }
  Eigen::VectorXd tau;
  linear_guess(tau);
  apply(tau);
  inner_->cold_guess(x_);
  y.resize(n_ + k_);
  y.head(n_) = x_;
  y.tail(k_) = tau;
}

bool DisplacementProblem::alternative_guess(Eigen::VectorXd& y) {
  if (start_.size() > 0) return false;
  Eigen::VectorXd tau;
  linear_guess(tau);
  apply(tau);
  if (!inner_->alternative_guess(x_)) return false;
  y.resize(n_ + k_);
  y.head(n_) = x_;
  y.tail(k_) = tau;
  return true;
}

void DisplacementProblem::rest_state(Eigen::VectorXd& y) {
  if (start_.size() > 0) {  // the tension solve's equilibrium solves the pulls' homotopy at 0
    y = start_;
    return;
  }
  // The straight robot with every driven tension 0.
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(k_);
  apply(zero);
  inner_->rest_state(x_);
  y.resize(n_ + k_);
  y.head(n_) = x_;
  y.tail(k_).setZero();
  // A model whose rest state has a gauge that the loads set (PRB's bending planes of straight
  // subsegments) takes it from the tensions the commanded pulls will need (the linear guess):
  // from the external loads alone the plane can lie across a driven tendon, whose pull then does
  // not move to first order and the loading path's first Jacobian is singular. Kept where it is a
  // rest state at zero tension as well (the shape is straight either way).
  Eigen::VectorXd tau;
  linear_guess(tau);
  if (!(tau.array() > 0.0).any()) return;
  apply(tau);
  Eigen::VectorXd xg;
  inner_->rest_state(xg);
  Eigen::VectorXd yg(n_ + k_), f(n_ + k_), s(n_ + k_);
  yg.head(n_) = xg;
  yg.tail(k_).setZero();
  residual_scale(s);
  if (residual(yg, f) && f.cwiseProduct(s).lpNorm<Eigen::Infinity>() <= 1e-14) {
    y = yg;
    return;
  }
  apply(zero);  // its gauge state back to the zero-tension rest state's
  inner_->rest_state(x_);
}

bool DisplacementProblem::warm_guess(const Solution& previous, Eigen::VectorXd& y) {
  Eigen::VectorXd tau;
  if (!tensions_of(previous, tau)) return false;
  for (int i = 0; i < k_; ++i) taut_[static_cast<std::size_t>(i)] = tau[i] > 0.0 || (previous.tendon_slack.empty() && delta_[i] > 0.0);
  apply(tau);
  if (!inner_->warm_guess(previous, x_)) return false;
  y.resize(n_ + k_);
  y.head(n_) = x_;
  y.tail(k_) = tau;
  return true;
}

bool DisplacementProblem::impossible_input(std::string& why) const {
  for (int i = 0; i < k_; ++i) {
    if (stretch_[i] > 0.0 || !(delta_[i] >= longest_[i])) continue;
    const int k = index_[i];
    why = "infeasible actuation: tendon T" + std::to_string(k + 1) + " (index " + std::to_string(k) +
          ") commanded a pull of " + format_value(delta_[i]) + " m, not less than its path's length " +
          format_value(longest_[i]) + " m on the straight robot: no shape shortens its path that much";
    return true;
  }
  return false;
}

}  // namespace tdcr::detail

namespace tdcr {

detail::DisplacementProblem& ModelWorkspace::displacement_problem() {
  if (!displacement_) displacement_ = std::make_unique<detail::DisplacementProblem>();
  return *displacement_;
}

}  // namespace tdcr

namespace tdcr::detail {

bool tension_start(const StaticModel& model, ModelWorkspace& workspace, const ModelInput& input,
                   const SolverOptions& options, Solution& start) {
  const auto& D =
      static_cast<const DisplacementProblem&>(bind_displacement_problem(model, workspace, input, options, nullptr, nullptr));
  ModelInput tensions = input;
  tensions.actuation.kind = Actuation::Kind::Tensions;
  tensions.actuation.kinds.clear();
  tensions.actuation.values = D.linear_tensions(input.actuation.values);
  SolverOptions o = options;
  o.stability = StabilityCheck::Never;
  o.differential_kinematics = false;
  start = tdcr::solve(model, workspace, tensions, o);
  return start.converged();
}

ModelProblem& bind_displacement_problem(const StaticModel& model, ModelWorkspace& workspace, const ModelInput& input,
                                        const SolverOptions& options, const Solution* warm_start,
                                        const Solution* tension_start) {
  const ModelInput tensions = tension_form(input, DisplacementProblem::placeholders(model, input));
  ModelProblem& inner = model.bind(workspace, tensions, options);
  DisplacementProblem& D = workspace.displacement_problem();
  D.bind(model, inner, input, options, warm_start ? warm_start : tension_start);
  if (tension_start && !warm_start) D.start_from(*tension_start);
  return D;
}

}  // namespace tdcr::detail
